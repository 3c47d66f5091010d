"""LoopTiming on a fake clock: lateness against the schedule, missed periods logged with their
lateness, compute time and sensor age percentiles, the summary line."""

from __future__ import annotations

import math

import pytest

from ftcomp.control.timing import LoopTiming, TimingSummary
from ftcomp.errors import ParameterError


class _Clock:
    def __init__(self) -> None:
        self.now_ns = 0

    def __call__(self) -> int:
        return self.now_ns


def test_a_late_cycle_is_counted_logged_with_its_lateness_and_restarts_the_schedule(
    caplog: pytest.LogCaptureFixture,
) -> None:
    clock = _Clock()
    timing = LoopTiming(0.002, name="test loop", clock_ns=clock)
    for k in range(100):
        clock.now_ns = k * 2_000_000 + (5_000_000 if k >= 50 else 0)  # one stall of 5 ms
        timing.start()
        clock.now_ns += 300_000  # 0.3 ms of work
        timing.sent(1_000_000)  # the sample 1 ms old
    s = timing.summary()
    assert s.cycles == 100 and s.late_cycles == 1 and s.missed_periods == 2
    assert s.worst_late_in_a_row == 1
    assert s.lateness_max_s == pytest.approx(0.005)
    assert s.worst_gap_s == pytest.approx(0.007)
    assert s.compute_p50_s == pytest.approx(0.000301) and s.compute_max_s == pytest.approx(3e-4)
    assert s.age_p99_s == pytest.approx(0.001001)
    assert "test loop: cycle 50 started 5.0 ms late (periods missed: 2)" in caplog.text
    assert "2 missed periods (1.96%)" in s.line() and "worst stretch 1 late in a row" in s.line()


def test_late_cycles_are_logged_at_most_once_a_second_and_the_next_line_counts_the_rest(
    caplog: pytest.LogCaptureFixture,
) -> None:
    clock = _Clock()
    timing = LoopTiming(0.002, name="test loop", clock_ns=clock)
    for k in range(1000):  # every cycle 4 ms after the last: each one 2 ms late, 4 s in all
        clock.now_ns = k * 4_000_000
        timing.start()
        timing.sent()
    assert timing.summary().late_cycles == 999
    # at 0.004 s (cycle 1), then 1 s later each time: cycles 251, 501 and 751
    assert [r.getMessage() for r in caplog.records] == [
        "test loop: cycle 1 started 2.0 ms late (periods missed: 1)",
        *(
            f"test loop: cycle {k} started 2.0 ms late (periods missed: 1); "
            "249 more late cycles since the last line"
            for k in (251, 501, 751)
        ),
    ]


def test_a_simulated_loop_has_no_lateness_and_a_loop_without_stamps_no_age() -> None:
    clock = _Clock()
    timing = LoopTiming(0.001, paced=False, clock_ns=clock)
    for k in range(10):
        clock.now_ns = k * 50_000_000  # far slower than its period: not judged
        timing.start()
        timing.sent()
    s = timing.summary()
    assert s.missed_periods == 0 and s.late_cycles == 0 and math.isnan(s.age_p50_s)
    assert "missed" not in s.line() and "sensor age p50 n/a" in s.line()
    assert s.as_dict()["age_p50_s"] is None


def test_timing_refuses_a_period_that_is_not_positive() -> None:
    with pytest.raises(ParameterError, match="period_s must be > 0"):
        LoopTiming(0.0)
    with pytest.raises(ParameterError, match="cycles must be an integer >= 0"):
        TimingSummary(0.001, True, -1, 0, 0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def test_cpu_time_is_kept_beside_compute_so_time_off_the_cpu_shows() -> None:
    clock, cpu = _Clock(), _Clock()
    timing = LoopTiming(0.002, clock_ns=clock, cpu_clock_ns=cpu)
    for k in range(10):
        clock.now_ns = k * 2_000_000
        timing.start()
        clock.now_ns += 500_000  # 0.5 ms from start to command sent ...
        cpu.now_ns += 200_000  # ... of which 0.2 ms on the CPU (0.3 ms preempted)
        timing.sent()
    s = timing.summary()
    assert s.compute_p50_s == pytest.approx(0.000501)
    assert s.cpu_p50_s == pytest.approx(0.000201) and s.cpu_p99_s == pytest.approx(0.000201)
    assert "compute p50 0.50 p99 0.50 max 0.50 ms (cpu p50 0.20 p99 0.20)" in s.line()
