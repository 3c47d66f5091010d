"""The sensor frame's motion and what it does to the rigid body below the sensor.

:func:`sensor_motion`: linear acceleration, angular velocity and angular acceleration of the
sensor frame, in the sensor frame, from its measured poses (:func:`imu_motion`: the same from an
IMU in the sensor). :func:`inertial_wrench`: the
Newton-Euler wrench of a rigid body in that motion (docs/calibration.md). Used by the inertial
compensation (:mod:`ftcomp.compensation.inertial`) and the inertia identification
(:mod:`ftcomp.calibration.dynamic`), so it sits below both.

A robot reports the TCP pose its controller computes from the *measured* joint positions
(forward kinematics), so the sensor's pose series (:class:`~ftcomp.hardware.protocols.Mount`)
carries the measured joint states. This module differentiates that series with a
Savitzky-Golay filter (:func:`scipy.signal.savgol_filter`: a least-squares polynomial of order
``polyorder`` fitted over ``window_s`` around each sample, differentiated analytically), the
stated filter of the inertial compensation:

- linear acceleration ``a_sensor = R_base_sensor.T @ d2p_base/dt2`` (the base frame is inertial);
- angular velocity from ``skew(w_sensor) = R.T @ dR/dt``;
- angular acceleration from ``R.T @ d2R/dt2 = skew(alpha_sensor) + skew(w_sensor)^2``, whose
  antisymmetric part is ``skew(alpha_sensor)``.

The filter is centred (non-causal): it delays nothing, so it serves identification and
evaluation of recorded runs; a live loop would evaluate the fit at the window's end instead.
The samples must be evenly spaced (one per control cycle).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import savgol_filter

from ftcomp.errors import ParameterError

__all__ = [
    "INERTIA_PARAMETERS",
    "SensorMotion",
    "imu_motion",
    "inertia_from_parameters",
    "inertial_wrench",
    "sensor_motion",
]


@dataclass(frozen=True)
class SensorMotion:
    """The sensor frame's motion at each sample, all in the sensor frame.

    Attributes:
        accel_sensor_mps2: linear acceleration of the sensor origin (gravity not included)
            [m/s^2], (N, 3).
        omega_sensor_rad_s: angular velocity [rad/s], (N, 3).
        alpha_sensor_rad_s2: angular acceleration [rad/s^2], (N, 3).
    """

    accel_sensor_mps2: NDArray[np.float64] = field(repr=False)
    omega_sensor_rad_s: NDArray[np.float64] = field(repr=False)
    alpha_sensor_rad_s2: NDArray[np.float64] = field(repr=False)


def _unskew(S: NDArray[np.float64]) -> NDArray[np.float64]:
    """The vector of the antisymmetric part of each (3, 3) matrix, (N, 3)."""
    A = 0.5 * (S - S.transpose(0, 2, 1))
    return np.stack([A[:, 2, 1], A[:, 0, 2], A[:, 1, 0]], axis=1)


def sensor_motion(
    t_s: ArrayLike,
    p_base_sensor: ArrayLike,
    R_base_sensor: ArrayLike,
    *,
    window_s: float = 0.021,
    polyorder: int = 3,
) -> SensorMotion:
    """Differentiate an evenly sampled pose series (see the module docstring).

    Args:
        t_s: sample times [s], (N,), evenly spaced (1 % jitter tolerated).
        p_base_sensor: sensor origin [m], base frame, (N, 3).
        R_base_sensor: sensor orientation, (N, 3, 3).
        window_s: the Savitzky-Golay window [s] (rounded to an odd number of samples).
        polyorder: its polynomial order (>= 2 for accelerations).

    Raises:
        ParameterError: shapes disagree, the times are not evenly spaced, or the series is
            shorter than one window.
    """
    t = np.asarray(t_s, dtype=float)
    p = np.asarray(p_base_sensor, dtype=float)
    R = np.asarray(R_base_sensor, dtype=float)
    n = len(t)
    if t.ndim != 1 or p.shape != (n, 3) or R.shape != (n, 3, 3):
        raise ParameterError(
            f"sensor_motion needs t (N,), p (N, 3), R (N, 3, 3); got {t.shape}, {p.shape}, "
            f"{R.shape}"
        )
    smooth = _smoother(t, "sensor_motion", window_s, polyorder)
    accel_base = smooth(p, 2)
    Rt = R.transpose(0, 2, 1)
    accel = np.einsum("nij,nj->ni", Rt, accel_base)
    omega = _unskew(Rt @ smooth(R.reshape(n, 9), 1).reshape(n, 3, 3))
    alpha = _unskew(Rt @ smooth(R.reshape(n, 9), 2).reshape(n, 3, 3))
    return SensorMotion(accel, omega, alpha)


def _smoother(
    t: NDArray[np.float64], who: str, window_s: float, polyorder: int
) -> Callable[[NDArray[np.float64], int], NDArray[np.float64]]:
    """The Savitzky-Golay smoother (and differentiator) of series sampled at the evenly spaced
    times ``t``: ``smooth(x, deriv)`` along axis 0 (``who`` names the caller in errors)."""
    n = len(t)
    if polyorder < 2:
        raise ParameterError(f"polyorder must be >= 2 for accelerations, got {polyorder}")
    if n < 2:
        raise ParameterError(f"{who} needs at least 2 samples, got {n}")
    steps = np.diff(t)
    dt = float(np.median(steps))
    if not (math.isfinite(dt) and dt > 0.0) or np.abs(steps - dt).max() > 0.01 * dt:
        raise ParameterError(
            f"{who} needs evenly spaced samples (one per control cycle); the steps "
            f"range over [{steps.min():.6g}, {steps.max():.6g}] s"
        )
    window = max(polyorder + 2, round(window_s / dt))
    window += 1 - window % 2
    if n < window:
        raise ParameterError(
            f"{who} needs at least one filter window ({window} samples, "
            f"{window * dt:.3g} s); got {n} samples"
        )

    def smooth(x: NDArray[np.float64], deriv: int) -> NDArray[np.float64]:
        return np.asarray(
            savgol_filter(x, window, polyorder, deriv=deriv, delta=dt, axis=0, mode="interp")
        )

    return smooth


def imu_motion(
    t_s: ArrayLike,
    specific_force_sensor_mps2: ArrayLike,
    angular_rate_sensor_rad_s: ArrayLike,
    gravity_sensor_mps2: ArrayLike,
    *,
    window_s: float = 0.021,
    polyorder: int = 3,
) -> SensorMotion:
    """The sensor frame's motion from an IMU in the sensor (its axes the sensor's), not from
    poses: ``a = f + g_s`` (an accelerometer reads the specific force ``f``, the acceleration
    less gravity), ``w`` the gyroscope's rate, ``alpha`` its derivative (the Savitzky-Golay
    filter of :func:`sensor_motion`, over the same window).

    Args:
        t_s: sample times [s], (N,), evenly spaced (1 % jitter tolerated).
        specific_force_sensor_mps2: the accelerometer's readings [m/s^2], sensor frame, (N, 3).
        angular_rate_sensor_rad_s: the gyroscope's [rad/s], sensor frame, (N, 3).
        gravity_sensor_mps2: gravity in the sensor frame at each sample [m/s^2], (N, 3): the
            calibration's, so that the static model's tool gravity and ``-m a`` sum to the
            accelerometer's ``-m f`` whatever its error.
        window_s, polyorder: the filter (:func:`sensor_motion`'s).

    Raises:
        ParameterError: shapes disagree, the times are not evenly spaced, or the series is
            shorter than one window.
    """
    t = np.asarray(t_s, dtype=float)
    f = np.asarray(specific_force_sensor_mps2, dtype=float)
    w = np.asarray(angular_rate_sensor_rad_s, dtype=float)
    g = np.asarray(gravity_sensor_mps2, dtype=float)
    n = len(t)
    if t.ndim != 1 or any(x.shape != (n, 3) for x in (f, w, g)):
        raise ParameterError(
            f"imu_motion needs t (N,), and (N, 3) for the rest; got {t.shape}, {f.shape}, "
            f"{w.shape}, {g.shape}"
        )
    smooth = _smoother(t, "imu_motion", window_s, polyorder)
    return SensorMotion(f + g, w, smooth(w, 1))


#: Order of the six inertia parameters: ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` [kg m^2].
INERTIA_PARAMETERS = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


def inertia_from_parameters(theta: ArrayLike) -> NDArray[np.float64]:
    """The symmetric (3, 3) tensor from ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` [kg m^2]."""
    xx, yy, zz, xy, xz, yz = np.asarray(theta, dtype=float)
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def inertial_wrench(
    mass_kg: float,
    cog_m: ArrayLike,
    inertia_cog_kgm2: ArrayLike,
    motion: SensorMotion,
) -> NDArray[np.float64]:
    """The motion's part of the sensed wrench [N, N*m], sensor frame, (N, 6).

    ``[-m a_c; -c x m a_c - (I alpha + w x I w)]`` (module docstring); zero at rest.

    Args:
        mass_kg: mass below the sensing element [kg].
        cog_m: its centre of gravity, sensor frame [m], (3,).
        inertia_cog_kgm2: its inertia tensor about the centre of gravity, sensor axes, (3, 3).
        motion: the sensor frame's motion (:func:`sensor_motion`).
    """
    c = np.asarray(cog_m, dtype=float)
    inertia = np.asarray(inertia_cog_kgm2, dtype=float)
    a = motion.accel_sensor_mps2
    w = motion.omega_sensor_rad_s
    alpha = motion.alpha_sensor_rad_s2
    a_c = a + np.cross(alpha, c) + np.cross(w, np.cross(w, c))
    force = -mass_kg * a_c
    torque = np.cross(c, force) - (alpha @ inertia.T + np.cross(w, w @ inertia.T))
    return np.hstack([force, torque])
