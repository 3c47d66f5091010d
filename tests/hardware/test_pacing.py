"""Time in one place, on fake clocks: LoopTiming (lateness against the schedule, missed periods
logged with their lateness, compute time and sensor age percentiles, the summary line), the
RateLimiter (slack, overruns, no raise, stalls), and a LoopClock around a loop (its schedule,
the collector kept out of its cycles)."""

from __future__ import annotations

import gc
import math

import pytest

from ftcomp.errors import ParameterError
from ftcomp.hardware.pacing import LoopClock, LoopTiming, RateLimiter, TimingSummary


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


class _Seconds:
    def __init__(self) -> None:
        self.now = 0.0
        self.slept: list[float] = []

    def __call__(self) -> float:
        return self.now

    def sleep(self, s: float) -> None:
        self.slept.append(s)
        self.now += s


def test_rate_limiter_sleeps_the_slack_and_counts_overruns_without_raising(
    caplog: pytest.LogCaptureFixture,
) -> None:
    clock = _Seconds()
    limiter = RateLimiter(0.01, name="test loop", clock=clock, sleep=clock.sleep)
    clock.now += 0.004  # a cycle's work
    assert limiter.sleep() == pytest.approx(0.006, abs=1e-12)
    assert clock.now == pytest.approx(0.01, abs=1e-12)
    clock.now += 0.013  # an overrun by 3 ms
    assert limiter.sleep() == pytest.approx(-0.003, abs=1e-12)
    assert limiter.overruns == 1 and limiter.periods_behind == 0  # the kept schedule carries it
    assert "test loop is late by 3.0 ms" in caplog.text
    clock.now += 0.001
    assert limiter.sleep() > 0 and limiter.periods_behind == 0
    assert limiter.worst_slack_s == pytest.approx(-0.003, abs=1e-12)


def test_overruns_shorter_than_a_period_in_a_row_leave_the_loop_on_schedule() -> None:
    # Under load a 1 kHz run once stopped as "10 periods missed in a row" with no period
    # missed: ten cycles in a row a little late. Each overran; together they lost half a period.
    clock = _Seconds()
    limiter = RateLimiter(0.001, clock=clock, sleep=clock.sleep, log_overruns=False)
    for _ in range(10):
        clock.now += 0.00105  # a slow patch: every cycle 50 us over its period
        limiter.sleep()
        assert limiter.periods_behind == 0
    assert limiter.overruns == 10
    clock.now += 0.0004
    assert limiter.sleep() == pytest.approx(0.0001, abs=1e-9)  # back on the kept schedule
    assert limiter.periods_behind == 0


def test_a_stall_puts_the_loop_behind_by_its_length_and_the_slack_after_pays_it_back() -> None:
    clock = _Seconds()
    limiter = RateLimiter(0.001, clock=clock, sleep=clock.sleep, log_overruns=False)
    clock.now += 0.5  # the loop's set-up, then the loop starts the schedule
    limiter.restart()
    clock.now += 0.0004
    limiter.sleep()
    assert limiter.periods_behind == 0
    clock.now += 0.0115  # a stall: 10.5 ms past the end of the first period
    limiter.sleep()
    assert limiter.periods_behind == 10
    for expected in (9, 9, 8, 8, 7):  # cycles of 0.4 ms: 0.6 ms of slack each
        clock.now += 0.0004
        limiter.sleep()
        assert limiter.periods_behind == expected
    for _ in range(30):
        clock.now += 0.0004
        limiter.sleep()
    assert limiter.periods_behind == 0


def test_a_restart_forgives_the_pause_before_a_loop() -> None:
    clock = _Seconds()
    limiter = RateLimiter(0.001, clock=clock, sleep=clock.sleep, log_overruns=False)
    clock.now += 0.0004
    limiter.sleep()  # a first loop's cycle
    clock.now += 0.5  # a pause before the next loop on the same robot: no stall of that loop
    limiter.restart()
    clock.now += 0.0004
    assert limiter.sleep() == pytest.approx(0.0006, abs=1e-9)
    assert limiter.periods_behind == 0


def test_a_loop_that_overruns_every_period_falls_further_behind() -> None:
    clock = _Seconds()
    limiter = RateLimiter(0.001, clock=clock, sleep=clock.sleep, log_overruns=False)
    behind = []
    for _ in range(60):
        clock.now += 0.0015  # each cycle takes one and a half periods
        limiter.sleep()
        behind.append(limiter.periods_behind)
    assert behind == sorted(behind) and behind[-1] >= 20


def test_rate_limiter_restarts_its_schedule_after_a_long_stall() -> None:
    clock = _Seconds()
    limiter = RateLimiter(0.01, clock=clock, sleep=clock.sleep)
    clock.now += 0.5
    limiter.sleep()
    clock.now += 0.002
    assert limiter.sleep() == pytest.approx(0.008, abs=1e-12)  # no burst to catch up


def test_a_limiter_may_catch_up_lateness_shorter_than_its_restart_threshold() -> None:
    clock = _Seconds()
    limiter = RateLimiter(0.002, clock=clock, sleep=clock.sleep, restart_after_s=0.05)
    clock.now += 0.012  # 10 ms late: kept, the next periods run back to back to catch up
    limiter.sleep()
    assert limiter.sleep() < 0.0 and limiter.periods_behind == 0
    clock.now += 0.2  # a stall past 50 ms: a new schedule from now, no burst
    limiter.sleep()
    clock.now += 0.001
    assert limiter.sleep() == pytest.approx(0.001, abs=1e-12)
    with pytest.raises(ParameterError, match="restart_after_s must be >= the period"):
        RateLimiter(0.002, restart_after_s=0.001)


def test_a_loop_clock_keeps_a_schedule_from_its_start_and_times_every_cycle() -> None:
    clock = _Clock()
    slept: list[float] = []

    def sleep(s: float) -> None:
        slept.append(s)
        clock.now_ns += round(s * 1e9)

    loop = LoopClock(0.002, name="test loop", realtime=False, clock_ns=clock, sleep=sleep)
    clock.now_ns = 5_000_000_000  # the set-up: no stall of the loop
    with loop:
        for _ in range(3):
            loop.start()
            clock.now_ns += 500_000  # the cycle's work
            loop.sent(1_000_000)
            assert loop.wait() == pytest.approx(0.0015, abs=1e-9)
    s = loop.summary()
    assert s.cycles == 3 and s.missed_periods == 0 and not loop.realtime
    assert s.age_p50_s == pytest.approx(0.001001)
    assert slept[1:] == pytest.approx([0.0015] * 3)  # after the pause that follows the set-up


def test_a_paced_loop_clock_freezes_the_set_up_and_collects_only_in_the_slack() -> None:
    assert gc.isenabled()
    frozen = gc.get_freeze_count()
    with LoopClock(0.002, realtime=False) as loop:
        assert not gc.isenabled() and gc.get_freeze_count() > frozen
        garbage = [[k] for k in range(3 * gc.get_threshold()[0])]
        del garbage
        loop.collect()
        assert gc.get_count()[0] < gc.get_threshold()[0]
    assert gc.isenabled() and gc.get_freeze_count() == frozen


def test_an_unpaced_loop_clock_leaves_the_collector_alone() -> None:
    with LoopClock(0.002, paced=False):
        assert gc.isenabled()
