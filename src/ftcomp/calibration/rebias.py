"""Re-bias: the sensor bias alone from a few still readings, the tool model kept.

The practical cure for bias drift (:mod:`.drift`): with the tool model known, a few seconds of
still readings at any one pose without contact give the bias alone (``reading - tool gravity
wrench``), gravity-aware where a vendor's tare is not (``ftcomp rebias``).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.calibration_record import Calibration
from ftcomp.errors import IdentificationError
from ftcomp.model import GravityModel
from ftcomp.samples import Samples

__all__ = ["bias_from_still", "bias_of", "rebias"]


def bias_from_still(
    model: GravityModel, wrench_sensor: ArrayLike, R_base_sensor: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The bias ``[F0, M0]`` from still readings without contact, the tool model known.

    Args:
        model: the identified tool model (its bias is ignored).
        wrench_sensor: readings [N, N*m], sensor frame, (N, 6), at one or more poses.
        R_base_sensor: the sensor's orientation at each, (N, 3, 3).

    Returns:
        ``(bias (6,), standard error (6,))``, the standard error from the readings' scatter
        (NaN with a single reading). The live loop can call this on a buffer of readings.
    """
    w = np.atleast_2d(np.asarray(wrench_sensor, dtype=float))
    R = np.asarray(R_base_sensor, dtype=float).reshape(len(w), 3, 3)
    estimate = w - model.gravity_wrench(R)
    n = len(estimate)
    se = estimate.std(axis=0, ddof=1) / math.sqrt(n) if n > 1 else np.full(6, np.nan)
    return estimate.mean(axis=0), se


def bias_of(calibration: Calibration) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A calibration's bias ``[F0, M0]`` and its standard errors, each (6,)."""
    m, se = calibration.model, calibration.std_errors
    return (
        np.concatenate([m.force_bias_N, m.torque_bias_Nm]),
        np.concatenate([se.force_bias_N, se.torque_bias_Nm]),
    )


def rebias(calibration: Calibration, samples: Samples) -> Calibration:
    """The calibration with only its bias re-estimated from still readings (tool model kept).

    The samples' orientations are the sensor's, or the recorded frame's when the calibration
    carries a mount. A drift model is dropped: the new bias is the bias now.

    Raises:
        IdentificationError: no readings.
    """
    if len(samples) == 0:
        raise IdentificationError(f"{samples.source}: no readings to re-estimate the bias from")
    R = samples.R_base_sensor
    if calibration.mount is not None:
        R = R @ calibration.mount.R_rec_sensor
    bias, se = bias_from_still(calibration.model, samples.wrench_sensor, R)
    m = calibration.model
    model = GravityModel(
        m.weight_N,
        m.center_of_gravity_m,
        bias[:3],
        bias[3:],
        tilt_U_rad=m.tilt_U_rad,
        tilt_V_rad=m.tilt_V_rad,
    )
    std_errors = replace(calibration.std_errors, force_bias_N=se[:3], torque_bias_Nm=se[3:])
    return replace(calibration, model=model, std_errors=std_errors, bias_drift=None)
