"""The sensor frame's motion from poses (Savitzky-Golay) or an IMU, and the Newton-Euler
wrench."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import ParameterError
from ftcomp.kinematics import SensorMotion, imu_motion, inertial_wrench, sensor_motion
from ftcomp.model import skew


def analytic_path(n: int = 1500, dt: float = 0.001):
    """Positions and orientations with known derivatives: a sinusoidal translation and a
    rotation about one fixed axis by theta(t) = 0.8 sin(3 t)."""
    t = np.arange(n) * dt
    amp, freq = np.array([0.1, -0.05, 0.08]), np.array([4.0, 5.0, 3.0])
    p = amp * np.sin(np.outer(t, freq))
    a_base = -amp * freq**2 * np.sin(np.outer(t, freq))
    u = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    theta, dtheta, ddtheta = 0.8 * np.sin(3 * t), 2.4 * np.cos(3 * t), -7.2 * np.sin(3 * t)
    R0 = Rotation.from_euler("xyz", [3.0, 0.2, -0.4]).as_matrix()
    R = R0 @ Rotation.from_rotvec(np.outer(theta, u)).as_matrix()
    omega = np.outer(dtheta, u)  # body frame: the axis is fixed in the body
    alpha = np.outer(ddtheta, u)
    a_sensor = np.einsum("nji,nj->ni", R, a_base)
    return t, p, R, SensorMotion(a_sensor, omega, alpha)


def test_motion_from_poses_matches_the_analytic_derivatives() -> None:
    t, p, R, truth = analytic_path()
    motion = sensor_motion(t, p, R, window_s=0.021, polyorder=3)
    inner = slice(20, -20)  # the filter's edges extrapolate
    # Cubic fits over 21 ms of motions at <= 5 rad/s: truncation ~ (w T)^2 / 10 ~ 1e-3 relative.
    np.testing.assert_allclose(
        motion.accel_sensor_mps2[inner], truth.accel_sensor_mps2[inner], atol=5e-3
    )
    np.testing.assert_allclose(
        motion.omega_sensor_rad_s[inner], truth.omega_sensor_rad_s[inner], atol=1e-4
    )
    np.testing.assert_allclose(
        motion.alpha_sensor_rad_s2[inner], truth.alpha_sensor_rad_s2[inner], atol=5e-3
    )


def test_motion_rejects_uneven_times_and_short_series() -> None:
    t, p, R, _ = analytic_path(100)
    t_bad = t.copy()
    t_bad[50] += 0.0005
    with pytest.raises(ParameterError, match="evenly spaced"):
        sensor_motion(t_bad, p, R)
    with pytest.raises(ParameterError, match="filter window"):
        sensor_motion(t[:10], p[:10], R[:10])


def test_inertial_wrench_equals_the_sum_over_point_masses() -> None:
    rng = np.random.default_rng(7)
    r = rng.normal(0.0, 0.05, (12, 3)) + np.array([0.0, 0.0, 0.06])
    m = rng.uniform(0.01, 0.1, 12)
    mass = m.sum()
    c = m @ r / mass
    d = r - c
    inertia = sum(
        mi * (di @ di * np.eye(3) - np.outer(di, di)) for mi, di in zip(m, d, strict=True)
    )
    a, w, al = rng.normal(size=(5, 3)), rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    got = inertial_wrench(mass, c, inertia, SensorMotion(a, w, al))
    for k in range(5):
        acc = a[k] + np.cross(al[k], r) + np.cross(w[k], np.cross(w[k], r))  # (12, 3)
        force = -(m[:, None] * acc).sum(axis=0)
        torque = -np.cross(r, m[:, None] * acc).sum(axis=0)
        np.testing.assert_allclose(got[k], np.concatenate([force, torque]), atol=1e-12)
    assert skew(c).shape == (3, 3)


def test_motion_from_an_imu_matches_the_analytic_motion() -> None:
    t, _p, R, truth = analytic_path()
    g_sensor = np.einsum("nji,j->ni", R, [0.0, 0.0, -STANDARD_GRAVITY_MPS2])
    # What an accelerometer and a gyroscope on the sensor's axes read.
    f = truth.accel_sensor_mps2 - g_sensor
    motion = imu_motion(t, f, truth.omega_sensor_rad_s, g_sensor)
    # a and w are the readings' own (exact algebra); alpha is the gyroscope's rate
    # differentiated as the poses are (sensor_motion's bound).
    np.testing.assert_allclose(motion.accel_sensor_mps2, truth.accel_sensor_mps2, atol=1e-12)
    np.testing.assert_array_equal(motion.omega_sensor_rad_s, truth.omega_sensor_rad_s)
    inner = slice(20, -20)
    np.testing.assert_allclose(
        motion.alpha_sensor_rad_s2[inner], truth.alpha_sensor_rad_s2[inner], atol=5e-3
    )
    with pytest.raises(ParameterError, match="imu_motion needs"):
        imu_motion(t, f[:, :2], truth.omega_sensor_rad_s, g_sensor)
