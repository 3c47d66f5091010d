"""The controller: frames, bumpless start and gain changes, faults stop within one period."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ftcomp.control import (
    AdmittanceController,
    CombinedLaw,
    LowPassFilter,
    SafetyLimits,
    StopReason,
    VelocityLaw,
)
from ftcomp.errors import ParameterError

DT = 1e-3
LIMITS = SafetyLimits(
    max_twist=0.05,
    max_twist_rate=0.5,
    max_travel=0.05,
    max_force_N=30.0,
    max_torque_Nm=3.0,
    stale_after_s=0.005,
)
# Sensor z pointing down, as a tool hanging from the flange.
R_DOWN = np.diag([1.0, -1.0, -1.0])
LOAD_SENSOR = np.array([0, 0, 4.9, 0, 0, 0])  # the load's weight pulls along sensor +z (down)


def _controller(frame: str = "base") -> AdmittanceController:
    return AdmittanceController(
        law=CombinedLaw(1e-4, 2e-3, "z"),
        wrench_filter=LowPassFilter(cutoff_hz=20.0, period_s=DT),
        limits=LIMITS,
        frame=frame,  # type: ignore[arg-type]
    )


def test_controller_requires_a_known_frame() -> None:
    with pytest.raises(ParameterError, match="frame must be 'base' or 'sensor'"):
        _controller("tool")


def test_a_hanging_load_is_lowered_in_base_frame_and_start_is_bumpless() -> None:
    ctrl = _controller("base")
    state = ctrl.initial_state(LOAD_SENSOR, R_DOWN)
    state, twist = ctrl.step(state, 0.0, LOAD_SENSOR, R_DOWN, 0.0, DT)
    assert abs(twist[2]) <= LIMITS.max_twist_rate[2] * DT + 1e-15  # acceleration-limited start
    for k in range(1, 200):
        state, twist = ctrl.step(state, k * DT, LOAD_SENSOR, R_DOWN, k * DT, DT)
    np.testing.assert_allclose(twist, [0, 0, -2e-3 * 4.9, 0, 0, 0], atol=1e-12)


def test_sensor_frame_control_moves_along_the_tool_axis() -> None:
    ctrl = dataclasses.replace(_controller("sensor"), law=VelocityLaw(2e-3, "z"))
    state = ctrl.initial_state(LOAD_SENSOR, R_DOWN)
    for k in range(200):
        state, twist = ctrl.step(state, k * DT, LOAD_SENSOR, R_DOWN, k * DT, DT)
    np.testing.assert_allclose(twist, [0, 0, -2e-3 * 4.9, 0, 0, 0], atol=1e-12)


def test_gain_change_mid_run_moves_the_command_by_at_most_one_acceleration_step() -> None:
    ctrl = _controller()
    state = ctrl.initial_state(LOAD_SENSOR, R_DOWN)
    for k in range(200):
        state, before = ctrl.step(state, k * DT, LOAD_SENSOR, R_DOWN, k * DT, DT)
    faster = dataclasses.replace(ctrl, law=CombinedLaw(5e-4, 8e-3, "z"))
    state, after = faster.step(state, 0.2, LOAD_SENSOR, R_DOWN, 0.2, DT)
    assert np.max(np.abs(after - before)) <= LIMITS.max_twist_rate[2] * DT + 1e-15


@pytest.mark.parametrize(
    ("fault", "reason"),
    [
        ("nan", StopReason.NON_FINITE_SAMPLE),
        ("repeat", StopReason.REPEATED_SAMPLE),
        ("spike", StopReason.FORCE_LIMIT),
        ("stop", StopReason.REPEATED_SAMPLE),
    ],
)
def test_a_sensor_fault_stops_motion_in_the_period_that_sees_it(
    fault: str, reason: StopReason
) -> None:
    ctrl = _controller()
    state = ctrl.initial_state(LOAD_SENSOR, R_DOWN)
    last_t = 0.0
    for k in range(100):
        state, twist = ctrl.step(state, k * DT, LOAD_SENSOR, R_DOWN, k * DT, DT)
        last_t = k * DT
    assert twist[2] < 0
    w, t = LOAD_SENSOR.copy(), 100 * DT
    if fault == "nan":
        w = np.full(6, math.nan)
    elif fault == "repeat":
        t = last_t
    elif fault == "spike":
        w = np.array([0, 0, 100.0, 0, 0, 0])
    elif fault == "stop":  # the stream stops: the driver keeps returning its last reading
        t = last_t
    state, twist = ctrl.step(state, t, w, R_DOWN, 100 * DT, DT)
    assert np.all(twist == 0.0)
    assert state.stop_reason is reason
    state, twist = ctrl.step(state, 101 * DT, LOAD_SENSOR, R_DOWN, 101 * DT, DT)
    assert np.all(twist == 0.0) and state.stop_reason is reason  # latched


def test_step_replays_a_log_identically() -> None:
    ctrl = _controller()
    rng = np.random.default_rng(3)
    log = LOAD_SENSOR + rng.normal(scale=0.05, size=(300, 6))
    out = []
    for _ in range(2):
        state = ctrl.initial_state(log[0], R_DOWN)
        twists = []
        for k, w in enumerate(log):
            state, twist = ctrl.step(state, k * DT, w, R_DOWN, k * DT, DT)
            twists.append(twist)
        out.append(np.array(twists))
    np.testing.assert_array_equal(out[0], out[1])
