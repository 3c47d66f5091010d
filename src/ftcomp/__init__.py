"""ftcomp: F/T sensor calibration, gravity compensation and compliant control."""

from __future__ import annotations

__version__ = "0.1.0"

__all__ = ["__version__"]
