"""Run-time compensation (Eq. 20-23) and weighing a grasped load."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.compensation.load import estimate_load, load_weight_N
from ftcomp.errors import ParameterError
from ftcomp.model import GravityModel

from conftest import TRUE_MODEL


def test_a_reading_with_no_contact_compensates_to_zero(rng) -> None:
    R = Rotation.random(100, rng=rng).as_matrix()
    contact = GravityCompensator(TRUE_MODEL).compensate(TRUE_MODEL.predict(R), R)
    np.testing.assert_allclose(contact, 0.0, atol=1e-12)


def test_single_sample_equals_the_batch_row_and_eq_22(rng) -> None:
    R = Rotation.random(20, rng=rng).as_matrix()
    w = rng.normal(size=(20, 6))
    comp = GravityCompensator(TRUE_MODEL)
    batch = comp.compensate(w, R)
    for i in range(20):
        single = comp.compensate(w[i], R[i])
        g_s = R[i].T @ TRUE_MODEL.gravity_base_N
        eq22 = (
            w[i]
            - np.r_[
                TRUE_MODEL.force_bias_N + g_s,
                TRUE_MODEL.torque_bias_Nm + np.cross(TRUE_MODEL.center_of_gravity_m, g_s),
            ]
        )
        np.testing.assert_allclose(single, batch[i], atol=1e-12)
        np.testing.assert_allclose(single, eq22, atol=1e-12)


def test_mismatched_shapes_are_rejected() -> None:
    comp = GravityCompensator(TRUE_MODEL)
    with pytest.raises(ParameterError, match=r"got \(5,\) and \(3, 3\)"):
        comp.compensate(np.zeros(5), np.eye(3))
    with pytest.raises(ParameterError, match=r"got \(4, 6\) and \(3, 3, 3\)"):
        comp.compensate(np.zeros((4, 6)), np.zeros((3, 3, 3)))


def _load_readings(
    rng, weight_N: float, cog_m: np.ndarray, poses: int
) -> tuple[np.ndarray, np.ndarray]:
    R = Rotation.random(poses, rng=rng).as_matrix()
    load = GravityModel(
        weight_N,
        cog_m,
        np.zeros(3),
        np.zeros(3),
        tilt_U_rad=TRUE_MODEL.tilt_U_rad,
        tilt_V_rad=TRUE_MODEL.tilt_V_rad,
    )
    return TRUE_MODEL.predict(R) + load.gravity_wrench(R), R


def test_load_weight_is_the_norm_of_the_contact_force(rng) -> None:
    w, R = _load_readings(rng, 4.905, np.array([0.0, 0.01, 0.09]), 5)
    np.testing.assert_allclose(
        load_weight_N(GravityCompensator(TRUE_MODEL), w, R), 4.905, atol=1e-12
    )


def test_load_mass_and_centre_of_gravity_are_estimated_from_several_poses(rng) -> None:
    cog = np.array([0.004, -0.01, 0.09])
    w, R = _load_readings(rng, 4.905, cog, 4)
    est = estimate_load(GravityCompensator(TRUE_MODEL), w, R)
    assert est.weight_N == pytest.approx(4.905, abs=1e-12)
    assert est.mass_kg == pytest.approx(4.905 / 9.80665, abs=1e-12)
    np.testing.assert_allclose(est.center_of_gravity_m, cog, atol=1e-12)
    assert est.cog_fully_observed


def test_one_pose_observes_only_the_cog_across_gravity(rng) -> None:
    w, R = _load_readings(rng, 2.0, np.array([0.0, 0.0, 0.09]), 1)
    est = estimate_load(GravityCompensator(TRUE_MODEL), w, R)
    assert not est.cog_fully_observed
    assert est.weight_N == pytest.approx(2.0, abs=1e-12)


def test_batch_can_write_into_a_given_buffer(rng) -> None:
    R = Rotation.random(10, rng=rng).as_matrix()
    w = rng.normal(size=(10, 6))
    comp = GravityCompensator(TRUE_MODEL)
    buffer = np.empty((10, 6))
    result = comp.compensate(w, R, out=buffer)
    assert result is buffer
    np.testing.assert_allclose(buffer, comp.compensate(w, R), atol=1e-12)
    with pytest.raises(ParameterError, match="C-contiguous float64 array of shape"):
        comp.compensate(w, R, out=np.empty((10, 6), dtype=np.float32))
