"""Admittance laws against closed-form responses."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal

from ftcomp.control import (
    CombinedLaw,
    MassDamperSpringLaw,
    PositionLaw,
    VelocityLaw,
    selection_matrix,
)
from ftcomp.errors import ParameterError

DT = 1e-3


def test_selection_matrix_from_names_and_values() -> None:
    assert np.array_equal(selection_matrix("z"), np.diag([0, 0, 1, 0, 0, 0]))
    assert np.array_equal(selection_matrix("x, y rz"), np.diag([1, 1, 0, 0, 0, 1]))
    assert np.array_equal(selection_matrix([1, 0, 0, 0, 0, 1]), np.diag([1, 0, 0, 0, 0, 1]))


def test_selection_matrix_raises_on_unknown_axis_and_bad_values() -> None:
    with pytest.raises(ParameterError, match="unknown selection axis 'w'"):
        selection_matrix("z w")
    with pytest.raises(ParameterError, match="0/1"):
        selection_matrix([1, 0.5, 0, 0, 0, 0])


def test_laws_reject_negative_gains_and_bad_dt() -> None:
    with pytest.raises(ParameterError, match="k1_m_per_N must be >= 0"):
        CombinedLaw(-1.0, 0.0, "z")
    with pytest.raises(ParameterError, match="mass_kg must be > 0"):
        MassDamperSpringLaw(0.0, 1.0, 1.0, "z")
    law = VelocityLaw(1e-3, "z")
    with pytest.raises(ParameterError, match="dt must be > 0"):
        law.step(law.initial_state(), np.zeros(6), 0.0)


def test_position_law_offset_is_k1_times_force_change_on_selected_axes() -> None:
    k1 = np.array([1, 2, 3, 4, 5, 6]) * 1e-4
    law = PositionLaw(k1, "x z rz")
    state = law.initial_state()
    rng = np.random.default_rng(0)
    for _ in range(50):
        f = rng.normal(size=6)
        state, _ = law.step(state, f, DT)
    expected = k1 * f * np.array([1, 0, 1, 0, 0, 1])
    np.testing.assert_allclose(state.offset, expected, atol=1e-15)  # exact algebra


def test_position_law_gain_change_does_not_jump_the_command() -> None:
    law = PositionLaw(1e-4, "z")
    state = law.initial_state()
    f = np.array([0, 0, 2.0, 0, 0, 0])
    state, _ = law.step(state, f, DT)
    state, twist = PositionLaw(5e-4, "z").step(state, f, DT)  # same force, new gain
    assert np.all(twist == 0.0)


def test_velocity_law_on_a_spring_converges_at_rate_k_times_k2() -> None:
    # Contact of stiffness k: ΔF = -W + k*depth, depth grows with the downward twist.
    k, k2, weight = 2000.0, 2e-3, 4.9
    law = VelocityLaw(k2, "z")
    state = law.initial_state()
    depth, errors = 0.0, []
    for _ in range(2000):
        e = -weight + k * depth
        errors.append(e)
        state, twist = law.step(state, [0, 0, e, 0, 0, 0], DT)
        depth -= twist[2] * DT
    t = np.arange(len(errors)) * DT
    # Forward Euler of dE/dt = -k K2 E: E_n = E_0 (1 - k K2 dt)^n.
    np.testing.assert_allclose(errors, -weight * (1 - k * k2 * DT) ** np.arange(len(t)), rtol=1e-9)
    # Against the continuous exp(-k K2 t): Euler's factor differs by (k K2 dt)^2/2 a step.
    np.testing.assert_allclose(errors[-1], -weight * math.exp(-k * k2 * t[-1]), rtol=2e-2)


def test_combined_law_on_a_spring_converges_at_rate_k_k2_over_one_plus_k1_k() -> None:
    k, k1, k2, weight = 2000.0, 1e-4, 2e-3, 4.9
    law = CombinedLaw(k1, k2, "z")
    state = law.initial_state([0, 0, -weight, 0, 0, 0])
    depth, errors = 0.0, []
    for _ in range(3000):
        e = -weight + k * depth
        errors.append(e)
        state, twist = law.step(state, [0, 0, e, 0, 0, 0], DT)
        depth -= twist[2] * DT
    # e_{n+1} = (1 - a - b) e_n + a e_{n-1}, a = k K1, b = k K2 dt: a slow root near
    # exp(-k K2 dt / (1 + k K1)) and a parasitic one near -a (stable only while k K1 < 1).
    a, b = k * k1, k * k2 * DT
    slow = ((1 - a - b) + math.sqrt((1 - a - b) ** 2 + 4 * a)) / 2
    ratios = np.array(errors[1000:]) / np.array(errors[999:-1])
    np.testing.assert_allclose(ratios, slow, rtol=1e-9)  # parasitic root died out: exact
    rate = k * k2 / (1 + k1 * k)
    np.testing.assert_allclose(-math.log(slow) / DT, rate, rtol=2e-3)  # O(dt) discretisation


def test_mass_damper_spring_step_response_matches_lsim() -> None:
    m, d, k, force = 2.0, 30.0, 200.0, 3.0
    law = MassDamperSpringLaw(m, d, k, "z")
    dt = 1e-4
    state = law.initial_state()
    xs = []
    for _ in range(30000):
        state, _ = law.step(state, [0, 0, force, 0, 0, 0], dt)
        xs.append(state.offset[2])
    t = (np.arange(len(xs)) + 1) * dt
    _, x_ref, _ = signal.lsim(([1.0], [m, d, k]), np.full(len(t), force), t)
    # Semi-implicit Euler is first order: error ~ dt * max|x'| ≈ 1e-4 * 0.05 m/s.
    np.testing.assert_allclose(xs, x_ref, atol=2e-5)
    np.testing.assert_allclose(xs[-1], force / k, rtol=1e-3)
    assert np.all(state.offset[[0, 1, 3, 4, 5]] == 0.0)
