"""ftcomp: F/T sensor calibration, gravity compensation and compliant control."""

from __future__ import annotations

from ftcomp.calibration import Calibration, StandardErrors, calibrate
from ftcomp.compensation import GravityCompensator, LoadEstimate
from ftcomp.errors import FtcompError
from ftcomp.io.calibration_file import load_calibration, save_calibration
from ftcomp.io.samples import Samples, read_samples, write_samples
from ftcomp.model import GravityModel

__version__ = "0.1.0"

__all__ = [
    "Calibration",
    "FtcompError",
    "GravityCompensator",
    "GravityModel",
    "LoadEstimate",
    "Samples",
    "StandardErrors",
    "__version__",
    "calibrate",
    "load_calibration",
    "read_samples",
    "save_calibration",
    "write_samples",
]
