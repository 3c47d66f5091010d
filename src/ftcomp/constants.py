"""Physical constants used across ftcomp (SI units)."""

from __future__ import annotations

__all__ = ["STANDARD_GRAVITY_MPS2"]

#: Standard acceleration of gravity [m/s^2] (ISO 80000-3), used to turn weights into masses.
STANDARD_GRAVITY_MPS2 = 9.80665
