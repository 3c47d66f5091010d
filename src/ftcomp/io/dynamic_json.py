"""The dynamic calibration file (``ftcomp calibrate-dynamic``): the tool's inertia tensor as JSON.

Format ``ftcomp-dynamic-calibration/1``: ``inertia_cog_kgm2`` (``Ixx, Iyy, Izz, Ixy, Ixz, Iyz``
[kg m^2], about the centre of gravity, sensor axes), their standard errors and the recording's
statistics (:func:`dynamic_to_dict`).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration_record import DynamicCalibration
from ftcomp.errors import CalibrationFileError
from ftcomp.io.atomic import atomic_write_text, check_writable
from ftcomp.kinematics import INERTIA_PARAMETERS, inertia_from_parameters

__all__ = ["FORMAT", "dynamic_to_dict", "load_dynamic", "save_dynamic"]

FORMAT = "ftcomp-dynamic-calibration/1"


def dynamic_to_dict(dynamic: DynamicCalibration) -> dict[str, Any]:
    """A dynamic calibration as a JSON-ready document (SI units, names with units)."""
    theta = dynamic.inertia_cog_kgm2[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]
    return {
        "format": FORMAT,
        "inertia_cog_kgm2": dict(zip(INERTIA_PARAMETERS, theta.tolist(), strict=True)),
        "std_error_kgm2": dict(
            zip(INERTIA_PARAMETERS, dynamic.std_error_kgm2.tolist(), strict=True)
        ),
        "residual_rms_Nm": dynamic.residual_rms_Nm.tolist(),
        "samples": dynamic.samples,
        "duration_s": dynamic.duration_s,
        "peak_alpha_rad_s2": dynamic.peak_alpha_rad_s2.tolist(),
        "peak_omega_rad_s": dynamic.peak_omega_rad_s.tolist(),
        "peak_accel_mps2": dynamic.peak_accel_mps2,
    }


def save_dynamic(
    path: str | os.PathLike[str], dynamic: DynamicCalibration, *, overwrite: bool
) -> None:
    """Write ``dynamic`` as JSON; an existing file needs ``overwrite`` (``--force``)."""
    out = check_writable(path, overwrite=overwrite)
    atomic_write_text(out, json.dumps(dynamic_to_dict(dynamic), indent=2) + "\n")


def load_dynamic(path: str | os.PathLike[str]) -> NDArray[np.float64]:
    """The inertia tensor (3, 3) [kg m^2] of a file written by :func:`save_dynamic`.

    Raises:
        CalibrationFileError: unreadable, not this format, or a parameter missing.
    """
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
        values = doc["inertia_cog_kgm2"]
        theta = [float(values[name]) for name in INERTIA_PARAMETERS]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise CalibrationFileError(
            f"{path}: not a dynamic calibration (needs inertia_cog_kgm2 with "
            f"{', '.join(INERTIA_PARAMETERS)}): {exc}"
        ) from exc
    return inertia_from_parameters(theta)
