"""Property-based: whatever the controller step is fed, it never raises, never commands a
non-finite twist, and once it has stopped it commands zero."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ftcomp.control import (
    AdmittanceController,
    CombinedLaw,
    LowPassFilter,
    MassDamperSpringLaw,
    SafetyLimits,
)

DT = 1e-3
LIMITS = SafetyLimits(
    max_twist=0.05,
    max_twist_rate=0.5,
    max_travel=0.05,
    max_force_N=30.0,
    max_torque_Nm=3.0,
    stale_after_s=0.005,
    max_repeated_samples=2,
    max_identical_samples=10,
    sensor_range=(250.0, 6.0),
)
CONTROLLERS = [
    AdmittanceController(CombinedLaw(1e-4, 2e-3, "z"), LowPassFilter(20.0, DT), LIMITS, "base"),
    AdmittanceController(MassDamperSpringLaw(2.0, 40.0, 100.0, "x y z"), None, LIMITS, "sensor"),
]

anything = st.floats(allow_nan=True, allow_infinity=True, width=64)
plausible = st.floats(-50.0, 50.0)
vector6 = st.one_of(
    st.lists(plausible, min_size=6, max_size=6),
    st.lists(anything, min_size=6, max_size=6),
    st.lists(anything, min_size=0, max_size=9),  # wrong lengths
)
rotation = st.one_of(
    st.just(np.diag([1.0, -1.0, -1.0]).tolist()),
    st.lists(st.lists(anything, min_size=3, max_size=3), min_size=3, max_size=3),
    st.lists(anything, min_size=0, max_size=5),  # wrong shapes
)
period = st.one_of(st.just(DT), anything)
clock_step = st.one_of(st.just(DT), st.floats(-0.01, 0.01), anything)
one_step = st.tuples(vector6, rotation, period, clock_step, st.one_of(st.none(), vector6))


@settings(max_examples=150, deadline=None)
@given(
    controller=st.sampled_from(CONTROLLERS),
    steps=st.lists(one_step, min_size=1, max_size=25),
    raw=st.booleans(),
)
def test_the_step_never_raises_never_commands_nan_and_stays_stopped(
    controller: AdmittanceController, steps: list, raw: bool
) -> None:
    state = controller.initial_state([0.0, 0.0, 4.9, 0.0, 0.0, 0.0], np.diag([1.0, -1.0, -1.0]))
    now = 0.0
    stopped = False
    for wrench, R, dt, advance, nominal in steps:
        now = now + advance
        state, twist = controller.step(
            state,
            now,
            wrench,
            R,
            now,
            dt,
            nominal,
            wrench_raw_sensor=wrench if raw else None,
        )
        twist = np.asarray(twist)
        assert twist.shape == (6,) and np.all(np.isfinite(twist))
        if stopped:
            assert state.stop_reason is not None
        if state.stop_reason is not None:
            stopped = True
            assert not np.any(twist)
