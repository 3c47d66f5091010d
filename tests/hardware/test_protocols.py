"""The mount: one place for R_base_sensor = R_base_tcp @ R_tcp_sensor, and its inverse."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import Mount, PoseSample, WrenchSample


def _random_pose(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    return rng.normal(size=3), Rotation.random(random_state=rng).as_matrix()


def test_identity_mount_passes_the_tcp_pose_through() -> None:
    p, R = _random_pose(np.random.default_rng(0))
    p_s, R_s = Mount().sensor_pose(p, R)
    assert p_s is p and R_s is R


def test_sensor_pose_composes_and_tcp_pose_inverts_it() -> None:
    rng = np.random.default_rng(1)
    mount = Mount.from_xyz_rpy([0.01, -0.02, 0.05], [10.0, -20.0, 30.0])
    for _ in range(20):
        p, R = _random_pose(rng)
        p_s, R_s = mount.sensor_pose(p, R)
        np.testing.assert_allclose(R_s, R @ mount.R_tcp_sensor, atol=1e-12)
        np.testing.assert_allclose(p_s, p + R @ mount.p_tcp_sensor_m, atol=1e-12)
        p_back, R_back = mount.tcp_pose(p_s, R_s)
        np.testing.assert_allclose(p_back, p, atol=1e-12)
        np.testing.assert_allclose(R_back, R, atol=1e-12)


def test_tcp_twist_moves_the_sensor_origin_as_asked() -> None:
    """Rigid body: v_sensor = v_tcp + w x (p_sensor - p_tcp); checked by finite motion."""
    rng = np.random.default_rng(2)
    mount = Mount.from_xyz_rpy([0.0, 0.03, 0.12], [0.0, 0.0, 45.0])
    p, R = _random_pose(rng)
    twist_sensor = rng.normal(size=6)
    twist_tcp = mount.tcp_twist(twist_sensor, R)
    dt = 1e-7
    R_next = Rotation.from_rotvec(twist_tcp[3:] * dt).as_matrix() @ R
    p_next = p + twist_tcp[:3] * dt
    v_sensor = (mount.sensor_pose(p_next, R_next)[0] - mount.sensor_pose(p, R)[0]) / dt
    np.testing.assert_allclose(v_sensor, twist_sensor[:3], rtol=1e-5, atol=1e-6)
    np.testing.assert_array_equal(twist_tcp[3:], twist_sensor[3:])


def test_mount_rejects_a_matrix_that_is_no_rotation() -> None:
    with pytest.raises(ParameterError, match="not a rotation"):
        Mount(np.diag([1.0, 1.0, -1.0]))


def test_samples_are_frozen_and_stamped_in_integer_nanoseconds() -> None:
    sample = WrenchSample(1_500_000_000, np.arange(6.0))
    assert sample.t_s == 1.5
    with pytest.raises(ValueError):
        sample.wrench_sensor[0] = 1.0
    with pytest.raises(ParameterError, match="shape"):
        PoseSample(0, np.zeros(2), np.eye(3))


def test_owning_constructors_take_the_arrays_and_make_them_read_only() -> None:
    w, p, R = np.arange(6.0), np.zeros(3), np.eye(3)
    sample, pose = WrenchSample.owning(7, w), PoseSample.owning(7, p, R)
    assert sample.wrench_sensor is w and pose.R_base_tcp is R and sample.t_ns == pose.t_ns == 7
    for arr in (w, p, R):
        with pytest.raises(ValueError):
            arr[0] = 1.0
