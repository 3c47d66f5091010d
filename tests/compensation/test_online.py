"""Online load estimation: exact algebra of the RLS, and the detector on synthetic readings."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.compensation.online import (
    GraspState,
    LoadRls,
    OnlineLoadCompensator,
    OnlineSettings,
)
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import ParameterError
from ftcomp.model import GravityModel

TOOL = GravityModel(
    3.2,
    np.array([0.001, -0.002, 0.05]),
    np.zeros(3),
    np.zeros(3),
    tilt_U_rad=0.003,
    tilt_V_rad=-0.002,
)


def _load_wrench(R: np.ndarray, mass_kg: float, cog_m: np.ndarray) -> np.ndarray:
    d = TOOL.gravity_base_N / np.linalg.norm(TOOL.gravity_base_N) @ R
    f = mass_kg * STANDARD_GRAVITY_MPS2 * d
    return np.concatenate([f, np.cross(cog_m, f)])


def _orientations(n: int, seed: int) -> np.ndarray:
    """Tool pointing down, slowly turning by up to ~40 deg."""
    t = np.linspace(0.0, 1.0, n)
    rotvec = np.column_stack([0.5 * np.sin(3 * t), 0.4 * t, 0.3 * np.cos(2 * t)])
    down = Rotation.from_euler("x", np.pi)
    return (down * Rotation.from_rotvec(rotvec)).as_matrix()


def test_rls_recovers_an_exact_load_without_noise() -> None:
    cog = np.array([0.01, -0.02, 0.12])
    rls = LoadRls(np.ones(6) * 1e6, 1.0)
    for R in _orientations(200, 0):
        gamma = (
            STANDARD_GRAVITY_MPS2 * TOOL.gravity_base_N / np.linalg.norm(TOOL.gravity_base_N) @ R
        )
        rls.update(gamma, _load_wrench(R, 0.5, cog))
    # The prior (weight 1 against 1e6 per row) pulls by ~1e-9 relative.
    assert rls.mass_kg == pytest.approx(0.5, rel=1e-7)
    np.testing.assert_allclose(rls.cog_m, cog, atol=1e-8)


def test_grasp_is_detected_estimated_and_compensated_then_release_is_detected() -> None:
    rng = np.random.default_rng(4)
    settings = OnlineSettings()
    online = OnlineLoadCompensator(TOOL, settings)
    cog = np.array([0.003, 0.001, 0.125])
    Rs = _orientations(3000, 1)
    noise = np.array([settings.force_noise_std_N] * 3 + [settings.torque_noise_std_Nm] * 3)
    out = []
    for i, R in enumerate(Rs):
        w = TOOL.predict(R) + rng.normal(0.0, 1.0, 6) * noise
        if 1000 <= i < 2500:
            w = w + _load_wrench(R, 0.5, cog)
        out.append(online.compensate(w, R))
        if i == 1999:
            assert online.state is GraspState.HOLDING
            # mass within a few standard deviations of the truth
            assert abs(online.rls.mass_kg - 0.5) < 4 * online.rls.mass_std_kg
            np.testing.assert_allclose(online.rls.cog_m, cog, atol=2e-3)
    kinds = [(e.kind, e.onset_sample) for e in online.events]
    assert [k for k, _ in kinds] == ["grasp", "release"]
    assert 1000 <= kinds[0][1] <= 1010 and 2500 <= kinds[1][1] <= 2510
    assert online.events[1].sample - 2500 < 200  # confirmed within 0.2 s
    assert online.state is GraspState.EMPTY
    # Holding and converged, the output is the contact wrench again: zero within the noise.
    held = np.array(out[1600:2400])
    assert np.abs(held[:, :3].mean(axis=0)).max() < 5 * 0.125 / np.sqrt(len(held))
    # Bumpless: no output step larger than a few noise deviations while switching.
    assert np.abs(np.diff(np.array(out[1000:1600])[:, 2])).max() < 8 * 0.125


def test_a_push_against_gravity_is_a_contact_not_a_grasp() -> None:
    online = OnlineLoadCompensator(TOOL)
    R = Rotation.from_euler("x", np.pi).as_matrix()
    d = TOOL.gravity_base_N / np.linalg.norm(TOOL.gravity_base_N) @ R
    for i in range(400):
        push = -5.0 * d if i >= 100 else np.zeros(3)
        online.compensate(TOOL.predict(R) + np.concatenate([push, np.zeros(3)]), R)
    assert [e.kind for e in online.events] == ["contact"]
    assert online.state is GraspState.EMPTY


def test_batch_compensation_leaves_the_state_alone() -> None:
    online = OnlineLoadCompensator(TOOL)
    Rs = _orientations(10, 0)
    out = online.compensate(TOOL.predict(Rs), Rs)
    np.testing.assert_allclose(out, 0.0, atol=1e-12)
    assert online.samples == 0


def test_settings_reject_non_positive_values() -> None:
    with pytest.raises(ParameterError, match="confirm_s"):
        OnlineSettings(confirm_s=0.0)


def test_the_control_loop_runs_it_as_its_compensator_and_sees_a_grasp() -> None:
    from ftcomp.control.loop import ControlCycle, Reading, run_loop
    from ftcomp.sim.cell import SimCell
    from ftcomp.sim.scene import SceneConfig
    from ftcomp.sim.tool import LoadSpec

    cell = SimCell(SceneConfig(load=LoadSpec(0.5)), seed=2)
    cell.settle()
    online = OnlineLoadCompensator(cell.true_gravity_model())
    cycle = ControlCycle(cell, cell.sensor, compensator=online)
    seen: list[np.ndarray] = []

    def step(reading: Reading) -> np.ndarray:
        seen.append(reading.wrench_contact_sensor)
        if len(seen) == 200:
            cell.grasp()
        return np.zeros(6)

    run_loop(cycle, step, max_cycles=900)
    assert [e.kind for e in online.events] == ["grasp"]
    assert online.state is GraspState.HOLDING
    # Still, one orientation: the mass is observable, and the load is compensated away.
    assert online.rls.mass_kg == pytest.approx(0.5, abs=4 * online.rls.mass_std_kg + 1e-3)
    assert np.abs(np.mean(seen[-200:], axis=0)[:3]).max() < 0.05


def _moving_with_a_load(accelerometer: bool) -> tuple[OnlineLoadCompensator, np.ndarray]:
    """Grasp 0.5 kg while still, then shake it about (up to 4.5 m/s^2, 2.9 RMS) for 3 s; the
    compensated forces while shaking, and the compensator (fed the accelerometer or not)."""
    rng = np.random.default_rng(9)
    settings = OnlineSettings()
    online = OnlineLoadCompensator(TOOL, settings)
    cog = np.array([0.003, 0.001, 0.125])
    tool_kg = TOOL.weight_N / STANDARD_GRAVITY_MPS2
    noise = np.array([settings.force_noise_std_N] * 3 + [settings.torque_noise_std_Nm] * 3)
    Rs = _orientations(4000, 2)
    out = []
    for i, R in enumerate(Rs):
        t = max(0.0, (i - 1000) * 1e-3)
        a = 2.0 * np.array([np.sin(4.4 * t), 1 - np.cos(3.1 * t), 0.5 * np.sin(5.7 * t)])
        g_s = TOOL.gravity_base_N @ R / tool_kg
        shaken = np.concatenate([-tool_kg * a, np.cross(TOOL.center_of_gravity_m, -tool_kg * a)])
        w = TOOL.predict(R) + shaken + rng.normal(0.0, 1.0, 6) * noise
        if i >= 500:  # the load, under the gravity it feels: g_s - a
            f_load = 0.5 * (g_s - a)
            w = w + np.concatenate([f_load, np.cross(cog, f_load)])
        f = a - g_s + rng.normal(0.0, 0.03, 3)  # what the accelerometer reads
        out.append(online.compensate(w, R, specific_force_mps2=f if accelerometer else None))
    return online, np.array(out[1500:])


def test_an_accelerometer_weighs_and_compensates_a_load_that_moves() -> None:
    online, shaking = _moving_with_a_load(accelerometer=True)
    assert [e.kind for e in online.events] == ["grasp"]
    assert online.state is GraspState.HOLDING
    assert abs(online.rls.mass_kg - 0.5) < 4 * online.rls.mass_std_kg
    # The contact force while shaking is the noise around zero: 50-sample means within
    # 5 of their standard deviations (0.125 N / sqrt(50), and the accelerometer's
    # 0.03 m/s^2 through 0.83 kg: 0.025 N per sample).
    means = shaking[: len(shaking) // 50 * 50, :3].reshape(-1, 50, 3).mean(axis=1)
    assert np.abs(means).max() < 5 * np.hypot(0.125, 0.025) / np.sqrt(50)
    # Held at the pose's gravity, the same shaking is felt as a contact of about m a: 0.83 kg
    # (tool and load) at 2.9 m/s^2 RMS, 2.4 N (2.5 measured), taken for contacts as it goes.
    still_online, still = _moving_with_a_load(accelerometer=False)
    assert np.sqrt(np.mean(np.sum(still[:, :3] ** 2, axis=1))) > 2.0
    assert [e.kind for e in still_online.events].count("contact") > 0
