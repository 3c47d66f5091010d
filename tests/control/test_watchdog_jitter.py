"""The sensor watchdog judges data by its age, not by the ticks it misses: a healthy stream whose
ticks arrive late, up to the stale limit, never stops the loop; older data does, in the period
that sees it (fake clocks: every stamp is chosen, nothing waits)."""

from __future__ import annotations

import numpy as np

from ftcomp.control.safety import SafetyLimits, StopReason
from ftcomp.session.run import AdmittanceConfig

PERIOD_NS = 2_000_000  # a 500 Hz loop
STALE_NS = 20_000_000


def _limits() -> SafetyLimits:
    """``ftcomp run``'s watchdog: no count of repeated stamps, the stale limit decides."""
    return SafetyLimits(
        0.05, 1.0, 0.1, 40.0, 8.0, STALE_NS * 1e-9, max_repeated_samples=None,
        max_identical_samples=5,
    )  # fmt: skip


def _run(arrivals_ns: np.ndarray, cycles: int) -> list[StopReason | None]:
    """Step the controller at each period with the newest sample that has arrived (its stamp is
    its arrival, as a Net F/T's); the stop reason of every cycle."""
    rng = np.random.default_rng(21)
    controller = AdmittanceConfig(_limits()).controller(PERIOD_NS * 1e-9)
    wrenches = rng.normal(0.0, 0.125, (len(arrivals_ns), 6))  # one count of noise
    R = np.eye(3)
    state = controller.initial_state(wrenches[0], R)
    reasons: list[StopReason | None] = []
    for k in range(1, cycles + 1):
        now = k * PERIOD_NS
        i = int(np.searchsorted(arrivals_ns, now, side="right")) - 1
        state, _ = controller.step(
            state, arrivals_ns[i] * 1e-9, wrenches[i], R, now * 1e-9, PERIOD_NS * 1e-9
        )
        reasons.append(state.stop_reason)
    return reasons


def test_sensor_ticks_late_up_to_the_stale_limit_never_stop_the_loop() -> None:
    # A 1 kHz stream whose packets come in bursts: after every 50 on time, a gap that grows to
    # just under the stale limit (the data in use then ages to 19.9 ms), then the held-back
    # packets arrive together.
    arrivals, t = [], 0
    for gap_ms in (3, 6, 9, 12, 15, 18, 19.9):
        for _ in range(50):
            t += 1_000_000
            arrivals.append(t)
        held = round(gap_ms * 1e6)
        burst = t + held
        for _ in range(held // 1_000_000):
            t += 1_000_000
            arrivals.append(burst)  # held back, arriving together at the gap's end
        t = burst
    arrivals_ns = np.array(arrivals, dtype=np.int64)
    cycles = int(arrivals_ns[-1] // PERIOD_NS)
    assert all(reason is None for reason in _run(arrivals_ns, cycles))


def test_data_older_than_the_stale_limit_stops_in_the_period_that_sees_it() -> None:
    # 100 ms of a 1 kHz stream (off the loop's grid by 0.5 ms), then silence.
    arrivals_ns = np.arange(1, 101, dtype=np.int64) * 1_000_000 + 500_000
    reasons = _run(arrivals_ns, 100)
    first = next(k for k, reason in enumerate(reasons) if reason is not None)
    age_ns = (first + 1) * PERIOD_NS - arrivals_ns[-1]
    assert reasons[first] is StopReason.STALE_SAMPLE
    assert STALE_NS < age_ns <= STALE_NS + PERIOD_NS  # the first period whose data is too old
