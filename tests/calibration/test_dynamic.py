"""Inertia identification from an excitation trajectory, and its refusals."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.calibration.dynamic import ExcitationLimits, identify_inertia
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import CalibrationFileError, IdentificationError
from ftcomp.io.dynamic_json import load_dynamic, save_dynamic
from ftcomp.kinematics import SensorMotion, inertial_wrench
from ftcomp.model import GravityModel

TOOL = GravityModel(
    3.2,
    np.array([0.001, -0.002, 0.05]),
    np.array([0.3, -0.2, 0.1]),
    np.array([0.01, 0.02, -0.01]),
    tilt_U_rad=0.003,
    tilt_V_rad=-0.002,
)
INERTIA = np.array([[8e-4, 1e-5, 0.0], [1e-5, 7e-4, 2e-5], [0.0, 2e-5, 4e-4]])


def excitation(duration_s: float, speed: float, seed: int, noise: bool = True):
    """Readings of TOOL (with INERTIA) turning about three axes at once; ``speed`` scales the
    frequencies (1: about 40 rad/s^2 peak angular acceleration)."""
    rng = np.random.default_rng(seed)
    dt = 0.001
    t = np.arange(round(duration_s / dt)) * dt
    f = speed * np.array([9.0, 11.0, 13.0])
    amp = np.array([0.5, 0.4, 0.3])
    angles = amp * np.sin(np.outer(t, f))
    rot = Rotation.from_euler("x", np.pi) * Rotation.from_euler("xyz", angles)
    R = rot.as_matrix()
    p = np.column_stack([0.4 + 0.02 * np.sin(5 * t), 0.01 * np.cos(4 * t), 0.4 + 0 * t])
    # Motion by finite differences of the exact path (fine steps): the same as the filter sees.
    h = 1e-5
    R_p = (
        Rotation.from_euler("x", np.pi)
        * Rotation.from_euler("xyz", amp * np.sin(np.outer(t + h, f)))
    ).as_matrix()
    R_m = (
        Rotation.from_euler("x", np.pi)
        * Rotation.from_euler("xyz", amp * np.sin(np.outer(t - h, f)))
    ).as_matrix()
    Rt = R.transpose(0, 2, 1)

    def unskew(S):
        A = 0.5 * (S - S.transpose(0, 2, 1))
        return np.stack([A[:, 2, 1], A[:, 0, 2], A[:, 1, 0]], axis=1)

    omega = unskew(Rt @ (R_p - R_m) / (2 * h))
    alpha = unskew(Rt @ (R_p - 2 * R + R_m) / h**2)
    a_base = np.column_stack([-0.02 * 25 * np.sin(5 * t), -0.01 * 16 * np.cos(4 * t), 0 * t])
    motion = SensorMotion(np.einsum("nji,nj->ni", R, a_base), omega, alpha)
    mass = TOOL.weight_N / STANDARD_GRAVITY_MPS2
    w = TOOL.predict(R) + inertial_wrench(mass, TOOL.center_of_gravity_m, INERTIA, motion)
    if noise:
        w = w + rng.normal(0.0, 1.0, w.shape) * np.array([0.125] * 3 + [0.003] * 3)
    return t, w, p, R


def test_identifies_the_inertia_within_a_few_standard_errors() -> None:
    t, w, p, R = excitation(2.0, 1.0, seed=3)
    dyn = identify_inertia(t, w, p, R, TOOL)
    theta = INERTIA[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]
    got = dyn.inertia_cog_kgm2[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]
    # Noise gives a few standard errors; the filter's smoothing of 13 rad/s motions adds
    # ~0.5 % of the moments (cubic fit over 21 ms: (w T)^2 / 10).
    assert np.all(np.abs(got - theta) < 4 * dyn.std_error_kgm2 + 0.01 * INERTIA.max())
    assert dyn.residual_rms_Nm.max() < 2 * 0.003


def test_a_too_short_trajectory_is_refused_naming_its_length() -> None:
    t, w, p, R = excitation(0.4, 1.0, seed=3)
    with pytest.raises(IdentificationError, match=r"too short: 0\.399 s .* at least 1 s"):
        identify_inertia(t, w, p, R, TOOL)


def test_a_too_slow_trajectory_is_refused_naming_the_acceleration() -> None:
    t, w, p, R = excitation(2.0, 0.2, seed=3)
    with pytest.raises(IdentificationError, match=r"too slow.*angular acceleration about sensor"):
        identify_inertia(t, w, p, R, TOOL)


def test_an_unexcited_parameter_is_named() -> None:
    t, w, p, R = excitation(1.2, 1.0, seed=3)
    strict = ExcitationLimits(max_relative_std=1e-6)
    with pytest.raises(IdentificationError, match="does not excite I"):
        identify_inertia(t, w, p, R, TOOL, limits=strict)


def test_dynamic_calibration_round_trips_and_needs_force(tmp_path) -> None:
    t, w, p, R = excitation(2.0, 1.0, seed=4)
    dyn = identify_inertia(t, w, p, R, TOOL)
    path = tmp_path / "dynamic.json"
    save_dynamic(path, dyn, overwrite=False)
    np.testing.assert_allclose(load_dynamic(path), dyn.inertia_cog_kgm2, rtol=1e-12)
    with pytest.raises(Exception, match="overwrite=True"):
        save_dynamic(path, dyn, overwrite=False)
    path.write_text(json.dumps({"inertia_cog_kgm2": {"Ixx": 1.0}}))
    with pytest.raises(CalibrationFileError, match="Iyy"):
        load_dynamic(path)
