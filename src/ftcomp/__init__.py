"""ftcomp: F/T sensor calibration, gravity compensation and compliant control.

The names below are imported on first use (PEP 562), so ``import ftcomp`` and the ``ftcomp``
command start without loading numpy, scipy or MuJoCo. See ``docs/architecture.md`` for the
modules and how data flows between them.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

#: Public name -> the module that defines it.
_EXPORTS = {
    "Calibration": "ftcomp.calibration_record",
    "FtcompError": "ftcomp.errors",
    "GravityCompensator": "ftcomp.compensation.compensator",
    "GravityModel": "ftcomp.model",
    "LoadEstimate": "ftcomp.compensation.load",
    "Mount": "ftcomp.hardware.protocols",
    "R_base_sensor_from": "ftcomp.frames",
    "Samples": "ftcomp.samples",
    "StandardErrors": "ftcomp.calibration_record",
    "calibrate": "ftcomp.calibration.identify",
    "estimate_load": "ftcomp.compensation.load",
    "load_calibration": "ftcomp.io.calibration_json",
    "open_robot": "ftcomp.hardware.registry",
    "open_sensor": "ftcomp.hardware.registry",
    "read_samples": "ftcomp.io.samples_csv",
    "save_calibration": "ftcomp.io.calibration_json",
    "write_samples": "ftcomp.io.samples_csv",
}

__all__ = [
    "Calibration",
    "FtcompError",
    "GravityCompensator",
    "GravityModel",
    "LoadEstimate",
    "Mount",
    "R_base_sensor_from",
    "Samples",
    "StandardErrors",
    "__version__",
    "calibrate",
    "estimate_load",
    "load_calibration",
    "open_robot",
    "open_sensor",
    "read_samples",
    "save_calibration",
    "write_samples",
]

if TYPE_CHECKING:
    from ftcomp.calibration.identify import calibrate
    from ftcomp.calibration_record import Calibration, StandardErrors
    from ftcomp.compensation.compensator import GravityCompensator
    from ftcomp.compensation.load import LoadEstimate, estimate_load
    from ftcomp.errors import FtcompError
    from ftcomp.frames import R_base_sensor_from
    from ftcomp.hardware.protocols import Mount
    from ftcomp.hardware.registry import open_robot, open_sensor
    from ftcomp.io.calibration_json import load_calibration, save_calibration
    from ftcomp.io.samples_csv import read_samples, write_samples
    from ftcomp.model import GravityModel
    from ftcomp.samples import Samples


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'ftcomp' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
