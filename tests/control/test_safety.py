"""The safety envelope on crafted streams."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ftcomp.control import (
    SafetyLimits,
    StopReason,
    WatchdogState,
    check_sample,
    check_travel,
    check_wrench,
    limit_twist,
)
from ftcomp.errors import ParameterError

LIMITS = SafetyLimits(
    max_twist=[0.1, 0.1, 0.05, 1, 1, 1],
    max_twist_rate=1.0,
    max_travel=[0.01, 0.01, 0.02, 0.1, 0.1, 0.1],
    max_force_N=20.0,
    max_torque_Nm=2.0,
    stale_after_s=0.005,
)


def test_limits_raise_on_non_positive_values() -> None:
    with pytest.raises(ParameterError, match="max_force_N must be > 0"):
        SafetyLimits(1, 1, 1, max_force_N=0.0, max_torque_Nm=1, stale_after_s=1)
    with pytest.raises(ParameterError, match="max_twist must be > 0"):
        SafetyLimits([1, 1, -1, 1, 1, 1], 1, 1, max_force_N=1, max_torque_Nm=1, stale_after_s=1)


def test_limit_twist_clamps_velocity_then_acceleration() -> None:
    v = limit_twist(LIMITS, [1, 0, -1, 0, 0, 0], np.zeros(6), 1e-3)
    np.testing.assert_allclose(v, [1e-3, 0, -1e-3, 0, 0, 0])
    v = limit_twist(LIMITS, [1, 0, -1, 0, 0, 0], [0.1, 0, -0.05, 0, 0, 0], 1e-3)
    np.testing.assert_allclose(v, [0.1, 0, -0.05, 0, 0, 0])


def test_watchdog_accepts_a_fresh_stream() -> None:
    state = WatchdogState()
    for k in range(10):
        state, reason = check_sample(LIMITS, state, k * 1e-3, np.zeros(6), k * 1e-3 + 2e-4)
        assert reason is None
    assert state.last_t == pytest.approx(9e-3)


@pytest.mark.parametrize(
    ("t", "wrench", "now", "reason"),
    [
        (0.002, [math.nan, 0, 0, 0, 0, 0], 0.002, StopReason.NON_FINITE_SAMPLE),
        (math.inf, np.zeros(6), 0.002, StopReason.NON_FINITE_SAMPLE),
        (0.001, np.zeros(6), 0.002, StopReason.REPEATED_SAMPLE),
        (0.0005, np.zeros(6), 0.002, StopReason.REPEATED_SAMPLE),
        (0.002, np.zeros(6), 0.0075, StopReason.STALE_SAMPLE),
    ],
)
def test_watchdog_stops_on_bad_samples(
    t: float, wrench: list[float], now: float, reason: StopReason
) -> None:
    state = WatchdogState(last_t=0.001)
    _, got = check_sample(LIMITS, state, t, np.asarray(wrench), now)
    assert got is reason


def test_watchdog_tolerates_configured_repeats_until_stale() -> None:
    limits = SafetyLimits(
        1, 1, 1, max_force_N=1, max_torque_Nm=1, stale_after_s=0.005, max_repeated_samples=3
    )
    state = WatchdogState(last_t=0.0)
    state, reason = check_sample(limits, state, 0.0, np.zeros(6), 0.001)
    assert reason is None and state.repeats == 1
    _, reason = check_sample(limits, state, 0.0, np.zeros(6), 0.006)
    assert reason is StopReason.STALE_SAMPLE


def test_force_and_torque_limits() -> None:
    assert check_wrench(LIMITS, [0, 0, 19.9, 0, 0, 0]) is None
    assert check_wrench(LIMITS, [0, 0, -100, 0, 0, 0]) is StopReason.FORCE_LIMIT
    assert check_wrench(LIMITS, [0, 0, 0, 0, 2.5, 0]) is StopReason.TORQUE_LIMIT


def test_travel_limit_stops_before_leaving_the_envelope() -> None:
    travel = np.array([0, 0, -0.01999, 0, 0, 0])
    new, reason = check_travel(LIMITS, travel, [0, 0, -0.05, 0, 0, 0], 1e-3)
    assert reason is StopReason.TRAVEL_LIMIT
    np.testing.assert_array_equal(new, travel)
    new, reason = check_travel(LIMITS, travel, [0, 0, 0.05, 0, 0, 0], 1e-3)
    assert reason is None
    np.testing.assert_allclose(new[2], -0.01999 + 5e-5)


def test_limit_twist_passes_nan_through_like_numpy_clip() -> None:
    v = limit_twist(LIMITS, [math.nan, 0.5, 0, 0, 0, 0], np.zeros(6), 1e-3)
    assert math.isnan(v[0]) and v[1] == pytest.approx(1e-3)
    v = limit_twist(LIMITS, np.zeros(6), [math.nan, 0, 0, 0, 0, 0], 1e-3)
    assert math.isnan(v[0]) and np.all(v[1:] == 0.0)
    v = limit_twist(LIMITS, [math.inf, -math.inf, 0, 0, 0, 0], [0.1, -0.1, 0, 0, 0, 0], 1e-3)
    np.testing.assert_allclose(v, [0.1, -0.1, 0, 0, 0, 0])


def test_watchdog_calls_huge_finite_values_finite_and_the_force_limit_stops_them() -> None:
    huge = np.array([1e308, 1e308, 0, 0, 0, 0])  # finite, though their sum overflows
    _, reason = check_sample(LIMITS, WatchdogState(), 0.0, huge, 0.0)
    assert reason is None
    assert check_wrench(LIMITS, huge) is StopReason.FORCE_LIMIT


def test_checks_raise_on_vectors_that_are_not_six_values() -> None:
    with pytest.raises(ParameterError, match=r"wrench must have shape \(6,\)"):
        check_wrench(LIMITS, [0, 0, 1])
    with pytest.raises(ParameterError, match=r"twist_prev must have shape \(6,\)"):
        limit_twist(LIMITS, np.zeros(6), np.zeros(5), 1e-3)
    with pytest.raises(ParameterError, match=r"twist must have shape \(6,\)"):
        check_travel(LIMITS, np.zeros(6), np.zeros(7), 1e-3)


def test_uniform_limits_make_the_per_axis_envelope_with_the_rotation_limits() -> None:
    from ftcomp.control.safety import (
        MAX_ROTATION_ACCEL_RAD_S2,
        MAX_ROTATION_SPEED_RAD_S,
        UniformLimits,
    )

    limits = UniformLimits(max_speed_m_s=0.01, max_rotation_rad=0.1).safety_limits((250.0, 6.0))
    assert limits.max_twist.tolist() == [0.01] * 3 + [MAX_ROTATION_SPEED_RAD_S] * 3
    assert limits.max_twist_rate.tolist() == [0.5] * 3 + [MAX_ROTATION_ACCEL_RAD_S2] * 3
    assert limits.max_travel.tolist() == [0.02] * 3 + [0.1] * 3
    assert limits.max_repeated_samples is None and limits.max_identical_samples == 5
    assert limits.sensor_range == (250.0, 6.0)
    with pytest.raises(ParameterError, match=r"^max_speed_m_s must be > 0 m/s, got 0$"):
        UniformLimits(max_speed_m_s=0.0)
