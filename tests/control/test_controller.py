"""The controller: frames, bumpless start and gain changes, faults stop within one period."""

from __future__ import annotations

import dataclasses
import math
import pickle

import numpy as np
import pytest
from scipy import signal
from scipy.spatial.transform import Rotation

from ftcomp.control import (
    AdmittanceController,
    AdmittanceLaw,
    CombinedLaw,
    ControllerState,
    LowPassFilter,
    MassDamperSpringLaw,
    PositionLaw,
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


# --- The lean step against a straightforward recomputation, and over faults ---------------------


def _arrays_of(state: ControllerState) -> list[np.ndarray]:
    law = state.law
    return [
        law.offset,
        law.twist,
        law.wrench_error,
        state.filter,
        state.wrench_filtered_sensor,
        state.twist_base,
        state.travel_base,
    ]


def _rotate6(R: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Each row of v (N, 6) rotated by its R (N, 3, 3), force and torque alike."""
    return np.concatenate(
        [np.einsum("nij,nj->ni", R, v[:, :3]), np.einsum("nij,nj->ni", R, v[:, 3:])], axis=1
    )


def _straightforward(
    ctrl: AdmittanceController,
    w0: np.ndarray,
    R0: np.ndarray,
    w_log: np.ndarray,
    R_log: np.ndarray,
    nominal_log: np.ndarray | None,
    dt: float,
) -> dict[str, np.ndarray]:
    """The no-fault path written out on the whole log: sosfilt, the law, np.clip, a sum."""
    filt = ctrl.wrench_filter
    if filt is None:
        w_filt, zf = w_log, np.zeros((0, 2, 6))
    else:
        w_filt, zf = signal.sosfilt(np.array(filt.sos), w_log, axis=0, zi=filt.initial_state(w0))
    base = ctrl.frame == "base"
    e = (_rotate6(R_log, w_filt) if base else w_filt) - ctrl.wrench_desired
    e_start = (_rotate6(R0[None], w0[None])[0] if base else w0) - ctrl.wrench_desired
    law = ctrl.law
    if isinstance(law, (CombinedLaw, PositionLaw, VelocityLaw)):  # the closed form, Eq. 24-27
        k1 = getattr(law, "k1_m_per_N", np.zeros(6))
        k2 = getattr(law, "k2_m_per_s_N", np.zeros(6))
        s = np.diag(law.selection)
        de_dt = np.diff(np.vstack([e_start, e]), axis=0) / dt
        twist_law = s * (k1 * de_dt + k2 * e)
        offset = np.cumsum(twist_law * dt, axis=0)
    else:  # any other law: its own step
        state, rows = law.initial_state(e_start), []
        for e_k in e:
            state, twist_k = law.step(state, e_k, dt)
            rows.append((state.offset, twist_k))
        offset, twist_law = (np.array(x) for x in zip(*rows, strict=True))
    cmd = twist_law if base else _rotate6(R_log, twist_law)
    if nominal_log is not None:
        cmd = cmd + nominal_log
    limits = ctrl.limits
    twist, prev = [], np.zeros(6)
    for c in cmd:
        v = np.clip(c, -limits.max_twist, limits.max_twist)
        prev = np.clip(v, prev - limits.max_twist_rate * dt, prev + limits.max_twist_rate * dt)
        twist.append(prev)
    twist_base = np.array(twist)
    return {
        "w_filt": w_filt,
        "zf": zf,
        "e": e,
        "twist_law": twist_law,
        "offset": offset,
        "twist_base": twist_base,
        "travel": np.cumsum(twist_base * dt, axis=0),
    }


_LAWS: dict[str, AdmittanceLaw] = {
    "combined": CombinedLaw([1e-4, 2e-4, 1e-4, 1e-3, 1e-3, 2e-3], 2e-3, "x z rz"),
    "position": PositionLaw(3e-4, "y z"),
    "velocity": VelocityLaw([1e-3, 2e-3, 3e-3, 1e-2, 1e-2, 1e-2], [1, 1, 1, 0, 1, 0]),
    "mass-damper-spring": MassDamperSpringLaw(2.0, 40.0, 100.0, "z rx"),
}


@pytest.mark.parametrize("law_name", list(_LAWS))
@pytest.mark.parametrize("frame", ["base", "sensor"])
@pytest.mark.parametrize("extras", ["plain", "nominal+desired", "unfiltered"])
def test_no_fault_step_equals_sosfilt_and_the_law_written_out(
    law_name: str, frame: str, extras: str
) -> None:
    rng = np.random.default_rng(11)
    n = 400
    limits = SafetyLimits(
        max_twist=[0.02, 0.02, 0.01, 0.2, 0.2, 0.2],
        max_twist_rate=[0.5, 0.5, 0.2, 5.0, 5.0, 5.0],  # active at the start and on spikes
        max_travel=1.0,
        max_force_N=100.0,
        max_torque_Nm=10.0,
        stale_after_s=0.005,
    )
    desired = rng.normal(size=6) if extras == "nominal+desired" else np.zeros(6)
    ctrl = AdmittanceController(
        law=_LAWS[law_name],
        wrench_filter=None if extras == "unfiltered" else LowPassFilter(30.0, DT, order=4),
        limits=limits,
        frame=frame,  # type: ignore[arg-type]
        wrench_desired=desired,
    )
    scale = np.array([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])  # [N, N*m]
    ramp = np.linspace(0.0, 1.0, n)[:, None] * rng.normal(scale=5.0 * scale, size=6)
    w_log = LOAD_SENSOR + ramp + rng.normal(scale=0.3 * scale, size=(n, 6))
    R_log = Rotation.random(n, rng=rng).as_matrix()  # a new orientation every period
    nominal = rng.normal(scale=0.005, size=(n, 6)) if extras == "nominal+desired" else None
    w0, R0 = w_log[0] + 0.1, R_log[0]
    expected = _straightforward(ctrl, w0, R0, w_log, R_log, nominal, DT)

    state = ctrl.initial_state(w0, R0)
    got: dict[str, list[np.ndarray]] = {k: [] for k in expected if k != "zf"}
    for k in range(n):
        nominal_k = None if nominal is None else nominal[k]
        state, twist = ctrl.step(state, k * DT, w_log[k], R_log[k], k * DT + 2e-4, DT, nominal_k)
        assert state.stop_reason is None
        assert twist is state.twist_base
        for key, value in (
            ("w_filt", state.wrench_filtered_sensor),
            ("e", state.law.wrench_error),
            ("twist_law", state.law.twist),
            ("offset", state.law.offset),
            ("twist_base", twist),
            ("travel", state.travel_base),
        ):
            got[key].append(value)
    for key, rows in got.items():
        # The same arithmetic up to summation order (rotation, cumulative sums): 1e-12 holds.
        np.testing.assert_allclose(rows, expected[key], rtol=0, atol=1e-12, err_msg=key)
    np.testing.assert_allclose(state.filter, expected["zf"], rtol=0, atol=1e-12)
    assert np.ptp(np.array(got["twist_base"])[:, 2]) > 0  # the command did move


@pytest.mark.parametrize("law_name", list(_LAWS))
def test_the_state_holds_the_filtered_error_the_law_acted_on(law_name: str) -> None:
    ctrl = AdmittanceController(_LAWS[law_name], LowPassFilter(30.0, DT), LIMITS, "base")
    rng = np.random.default_rng(12)
    R = Rotation.random(rng=rng).as_matrix()
    state = ctrl.initial_state(LOAD_SENSOR, R)
    law_state = state.law
    for k in range(50):
        w = LOAD_SENSOR + rng.normal(scale=0.3, size=6)
        state, _ = ctrl.step(state, k * DT, w, R, k * DT, DT)
        e = state.law.wrench_error
        np.testing.assert_array_equal(e, ctrl.wrench_error(state.wrench_filtered_sensor, R))
        law_state, twist_law = ctrl.law.step(law_state, e, DT)  # the logged error, replayed
        np.testing.assert_array_equal(twist_law, state.law.twist)
    assert state.stop_reason is None


def _faulty_log(
    fault: str, n: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Stamps, wrenches and robot clock of a noisy run with tolerated repeats and one fault.

    Returns ``(t_sample, wrench, now, k_fault)``; ``k_fault`` is where the stop must happen
    (-1 for "travel": wherever the travel runs out).
    """
    t = np.arange(n) * DT
    wrench = LOAD_SENSOR + rng.normal(scale=[0.2, 0.2, 0.2, 0.02, 0.02, 0.02], size=(n, 6))
    for k in rng.choice(np.arange(20, n - 20), size=8, replace=False):
        t[k] = t[k - 1]  # the sensor missed a beat: a tolerated repeat
    now = np.arange(n) * DT + 3e-4
    k_fault = n // 2
    if fault == "nan":
        wrench[k_fault, rng.integers(6)] = math.nan
    elif fault == "repeat":
        t[k_fault - 2 : k_fault + 1] = t[k_fault - 3]  # three in a row, two are tolerated
    elif fault == "force":
        wrench[k_fault, :3] = [20.0, -20.0, 25.0]
    elif fault == "torque":
        wrench[k_fault, 3:] = [3.5, 0.0, 0.0]
    elif fault == "stale":
        now[k_fault:] += 0.01
    else:
        k_fault = -1
    return t, wrench, now, k_fault


@pytest.mark.parametrize(
    ("fault", "reason"),
    [
        ("nan", StopReason.NON_FINITE_SAMPLE),
        ("repeat", StopReason.REPEATED_SAMPLE),
        ("force", StopReason.FORCE_LIMIT),
        ("torque", StopReason.TORQUE_LIMIT),
        ("stale", StopReason.STALE_SAMPLE),
        ("travel", StopReason.TRAVEL_LIMIT),
    ],
)
@pytest.mark.parametrize("frame", ["base", "sensor"])
def test_a_seeded_run_with_faults_replays_exactly_and_never_writes_into_a_state(
    fault: str, reason: StopReason, frame: str
) -> None:
    rng = np.random.default_rng(5)
    n = 300
    t, wrench, now, k_fault = _faulty_log(fault, n, rng)
    R = Rotation.from_euler("xyz", [178.0, 4.0, 30.0], degrees=True).as_matrix()
    max_travel_z = 1e-3 if fault == "travel" else 0.05  # the law moves at about 10 mm/s
    limits = dataclasses.replace(
        LIMITS, max_travel=[0.05, 0.05, max_travel_z, 0.1, 0.1, 0.1], max_repeated_samples=2
    )
    ctrl = dataclasses.replace(_controller(frame), limits=limits)
    nominal = np.array([1e-3, 0.0, -2e-3, 0.0, 0.0, 0.01])

    runs = []
    for _ in range(2):
        state = ctrl.initial_state(wrench[0], R)
        trace = []
        for k in range(n):
            before = [a.copy() for a in _arrays_of(state)]
            watchdog = state.watchdog
            new, twist = ctrl.step(state, t[k], wrench[k], R, now[k], DT, nominal)
            for a, b in zip(_arrays_of(state), before, strict=True):
                np.testing.assert_array_equal(a, b)  # the step never writes into its input
            assert state.watchdog == watchdog
            trace.append((new.stop_reason, twist.copy(), *[a.copy() for a in _arrays_of(new)]))
            state = new
        runs.append(trace)

    stops = [k for k, row in enumerate(runs[0]) if row[0] is not None]
    assert stops and stops[-1] == n - 1  # latched to the end
    k_stop = stops[0]
    if k_fault >= 0:
        assert k_stop == k_fault
    else:
        assert 50 < k_stop < 250
    assert all(runs[0][k][0] is reason for k in stops)
    assert not any(np.any(runs[0][k][1]) for k in stops)  # zero twist from the faulty period on
    assert np.any(runs[0][k_stop - 1][1])  # it was moving
    for row_a, row_b in zip(*runs, strict=True):  # replay: bit for bit
        assert row_a[0] is row_b[0]
        for a, b in zip(row_a[1:], row_b[1:], strict=True):
            np.testing.assert_array_equal(a, b)


def test_step_stops_instead_of_raising_on_a_wrong_shape_or_period() -> None:
    ctrl = _controller()
    state = ctrl.initial_state(LOAD_SENSOR, R_DOWN)
    for args in (
        (0.0, LOAD_SENSOR[:5], R_DOWN, 0.0, DT),  # a wrench of the wrong length
        (0.0, LOAD_SENSOR, R_DOWN[:2], 0.0, DT),  # an orientation of the wrong shape
        (0.0, LOAD_SENSOR, R_DOWN, 0.0, 0.0),  # dt zero
        (0.0, LOAD_SENSOR, R_DOWN, 0.0, math.nan),  # dt NaN
        (0.0, "garbage", R_DOWN, 0.0, DT),  # not numbers at all
    ):
        stopped, twist = ctrl.step(state, *args)  # type: ignore[arg-type]
        assert stopped.stop_reason is StopReason.INVALID_INPUT and not np.any(twist)
    huge = np.array([1e308, 1e308, 0.0, 0.0, 0.0, 0.0])  # finite, though its sum is not
    stopped, twist = ctrl.step(state, 0.0, huge, R_DOWN, 0.0, DT)
    assert stopped.stop_reason is StopReason.FORCE_LIMIT and not np.any(twist)


def _moving(ctrl: AdmittanceController, n: int = 20) -> tuple[ControllerState, float]:
    """A controller lowering a hanging load for ``n`` periods; returns the state and the time."""
    state = ctrl.initial_state(LOAD_SENSOR, R_DOWN)
    for k in range(n):
        state, twist = ctrl.step(state, k * DT, LOAD_SENSOR + 0.01 * k, R_DOWN, k * DT, DT)
    assert state.stop_reason is None and np.any(twist)
    return state, n * DT


def test_a_nan_orientation_once_stops_and_keeps_the_travel_limit() -> None:
    ctrl = _controller()
    state, t = _moving(ctrl)
    R_bad = R_DOWN.copy()
    R_bad[0, 0] = math.nan
    stopped, twist = ctrl.step(state, t, LOAD_SENSOR, R_bad, t, DT)
    assert stopped.stop_reason is StopReason.NON_FINITE_POSE and not np.any(twist)
    np.testing.assert_array_equal(stopped.travel_base, state.travel_base)
    assert np.all(np.isfinite(stopped.travel_base))
    later, twist = ctrl.step(stopped, t + DT, LOAD_SENSOR, R_DOWN, t + DT, DT)
    assert later.stop_reason is StopReason.NON_FINITE_POSE and not np.any(twist)  # latched


@pytest.mark.parametrize("now_offset", [math.nan, -0.010])
def test_a_robot_clock_that_is_nan_or_runs_backwards_stops(now_offset: float) -> None:
    ctrl = _controller()
    state, t = _moving(ctrl)
    stopped, twist = ctrl.step(state, t, LOAD_SENSOR, R_DOWN, t + now_offset, DT)
    assert stopped.stop_reason is StopReason.CLOCK_FAULT and not np.any(twist)


def test_a_value_frozen_under_fresh_stamps_stops_after_the_tolerated_count() -> None:
    limits = dataclasses.replace(LIMITS, max_identical_samples=5)
    ctrl = dataclasses.replace(_controller(), limits=limits)
    state, t = _moving(ctrl)
    reasons = []
    for k in range(8):
        now = t + k * DT
        state, twist = ctrl.step(state, now, LOAD_SENSOR, R_DOWN, now, DT)
        reasons.append(state.stop_reason)
    # The first repeat of a value is the 1st identical sample; the 6th one stops.
    assert reasons[:6] == [None] * 6 and reasons[6] is StopReason.FROZEN_SAMPLE
    assert not np.any(twist)


def test_a_raw_reading_at_the_sensor_range_stops_below_the_force_limit() -> None:
    limits = dataclasses.replace(LIMITS, sensor_range=(250.0, 6.0))
    ctrl = dataclasses.replace(_controller(), limits=limits)
    state, t = _moving(ctrl)
    raw = np.array([0.0, 250.0, 3.0, 0.0, 0.0, 0.0])  # fy pinned at the range
    stopped, twist = ctrl.step(state, t, LOAD_SENSOR, R_DOWN, t, DT, wrench_raw_sensor=raw)
    assert stopped.stop_reason is StopReason.SENSOR_SATURATED and not np.any(twist)
    fine, twist = ctrl.step(state, t, LOAD_SENSOR, R_DOWN, t, DT, wrench_raw_sensor=raw * 0.5)
    assert fine.stop_reason is None


def test_a_controller_survives_pickling_with_its_prepared_constants() -> None:
    ctrl = _controller("sensor")
    copy = pickle.loads(pickle.dumps(ctrl))
    state = ctrl.initial_state(LOAD_SENSOR, R_DOWN)
    for k in range(20):
        w = LOAD_SENSOR + 0.1 * k
        new, twist = ctrl.step(state, k * DT, w, R_DOWN, k * DT, DT)
        _, twist_copy = copy.step(state, k * DT, w, R_DOWN, k * DT, DT)
        np.testing.assert_array_equal(twist, twist_copy)
        state = new
