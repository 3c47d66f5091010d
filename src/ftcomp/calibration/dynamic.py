"""The tool's inertia tensor from a short excitation trajectory (beyond the paper).

The static calibration gives the tool's weight, centre of gravity, the sensor's bias and the
base tilt; they stay. While the tool turns and accelerates, the torque the static model leaves
over is ``-(I alpha + w x I w)`` after removing the centre of gravity's acceleration
(:func:`ftcomp.kinematics.inertial_wrench`), linear in the six parameters of ``I`` (about the
centre of gravity, sensor axes). :func:`identify_inertia` fits them by least squares over a
recording (wrench, sensor pose, evenly spaced times) and refuses a recording that cannot tell
them: too short, too slow, or not turning about enough axes. The result is a
:class:`~ftcomp.calibration_record.DynamicCalibration` (:mod:`ftcomp.io.dynamic_json` writes it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.calibration_record import Calibration, DynamicCalibration
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import IdentificationError
from ftcomp.kinematics import (
    INERTIA_PARAMETERS,
    inertia_from_parameters,
    inertial_wrench,
    sensor_motion,
)
from ftcomp.model import GravityModel, skew

__all__ = ["ExcitationLimits", "identify_inertia"]


@dataclass(frozen=True)
class ExcitationLimits:
    """What a recording needs to identify the inertia.

    Attributes:
        min_duration_s: recorded time [s].
        min_alpha_rad_s2: peak angular acceleration about *each* sensor axis [rad/s^2].
        max_relative_std: each parameter's standard error at most this fraction of the
            largest principal moment.
    """

    min_duration_s: float = 1.0
    min_alpha_rad_s2: float = 5.0
    max_relative_std: float = 0.1


def _inertia_regressor(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """``L(v)`` with ``I v = L(v) theta``, theta = (Ixx, Iyy, Izz, Ixy, Ixz, Iyz); (N, 3, 6)."""
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    o = np.zeros_like(x)
    return np.stack(
        [
            np.stack([x, o, o, y, z, o], axis=1),
            np.stack([o, y, o, x, o, z], axis=1),
            np.stack([o, o, z, o, x, y], axis=1),
        ],
        axis=1,
    )


def identify_inertia(
    t_s: ArrayLike,
    wrench_sensor: ArrayLike,
    p_base_sensor: ArrayLike,
    R_base_sensor: ArrayLike,
    static: Calibration | GravityModel,
    *,
    limits: ExcitationLimits | None = None,
    window_s: float = 0.021,
) -> DynamicCalibration:
    """Fit the tool's inertia tensor to a recorded excitation trajectory.

    Args:
        t_s: sample times [s], (N,), one per control cycle.
        wrench_sensor: raw readings [N, N*m], sensor frame, (N, 6); nothing touches the tool.
        p_base_sensor: sensor origin [m], base frame, (N, 3).
        R_base_sensor: sensor orientation, (N, 3, 3).
        static: the tool's static calibration (kept as it is).
        limits: what the recording must excite; default :class:`ExcitationLimits`.
        window_s: the Savitzky-Golay window of the kinematics [s].

    Raises:
        IdentificationError: the recording is too short, too slow, or leaves a parameter
            unexcited; the message names what is missing.
    """
    lim = limits if limits is not None else ExcitationLimits()
    t = np.asarray(t_s, dtype=float)
    duration = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    if duration < lim.min_duration_s:
        raise IdentificationError(
            f"the excitation trajectory is too short: {duration:.3g} s recorded "
            f"({len(t)} samples), needs at least {lim.min_duration_s:g} s of motion"
        )
    motion = sensor_motion(t, p_base_sensor, R_base_sensor, window_s=window_s)
    alpha, omega = motion.alpha_sensor_rad_s2, motion.omega_sensor_rad_s
    peak_alpha = np.abs(alpha).max(axis=0)
    slow = [f"{ax} {v:.3g}" for ax, v in zip("xyz", peak_alpha, strict=True)]
    if peak_alpha.min() < lim.min_alpha_rad_s2:
        raise IdentificationError(
            "the excitation trajectory is too slow to excite the inertia: peak angular "
            f"acceleration about sensor {', '.join(slow)} rad/s^2, needs at least "
            f"{lim.min_alpha_rad_s2:g} rad/s^2 about each axis (turn the wrist faster, about "
            "every axis)"
        )
    model = static.model if isinstance(static, Calibration) else static
    mass = model.weight_N / STANDARD_GRAVITY_MPS2
    R = np.asarray(R_base_sensor, dtype=float)
    w = np.asarray(wrench_sensor, dtype=float)
    no_inertia = inertial_wrench(mass, model.center_of_gravity_m, np.zeros((3, 3)), motion)
    residual = (w - model.predict(R) - no_inertia)[:, 3:]  # = -(I alpha + w x I w) + noise
    Y = -(
        _inertia_regressor(alpha) + np.array([skew(v) for v in omega]) @ _inertia_regressor(omega)
    )
    Y2 = Y.reshape(-1, 6)
    theta, *_ = np.linalg.lstsq(Y2, residual.ravel(), rcond=None)
    fit_residual = residual - (Y @ theta)
    dof = max(1, Y2.shape[0] - 6)
    sigma2 = float(np.sum(fit_residual**2)) / dof
    cov = sigma2 * np.linalg.pinv(Y2.T @ Y2)
    std = np.sqrt(np.clip(np.diagonal(cov), 0.0, None))
    inertia = inertia_from_parameters(theta)
    scale = float(np.abs(np.linalg.eigvalsh(inertia)).max())
    worst = int(np.argmax(std))
    if not math.isfinite(scale) or std[worst] > lim.max_relative_std * max(scale, 1e-12):
        raise IdentificationError(
            f"the excitation trajectory does not excite {INERTIA_PARAMETERS[worst]}: its "
            f"standard error {std[worst]:.3g} kg m^2 is more than "
            f"{100 * lim.max_relative_std:g} % of the largest moment {scale:.3g} kg m^2 "
            f"(peak angular acceleration about sensor {', '.join(slow)} rad/s^2); record a "
            "longer or faster trajectory turning about every axis"
        )
    return DynamicCalibration(
        inertia_cog_kgm2=inertia,
        std_error_kgm2=std,
        residual_rms_Nm=np.sqrt(np.mean(fit_residual**2, axis=0)),
        samples=len(t),
        duration_s=duration,
        peak_alpha_rad_s2=peak_alpha,
        peak_omega_rad_s=np.abs(omega).max(axis=0),
        peak_accel_mps2=float(np.linalg.norm(motion.accel_sensor_mps2, axis=1).max()),
    )
