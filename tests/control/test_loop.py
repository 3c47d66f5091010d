"""The one control loop: rate limiter (slack, overruns, no raise) and a cycle that stops the
robot on every exit."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.control.loop import ControlCycle, LoopOverrunError, RateLimiter, Reading, run_loop
from ftcomp.hardware.protocols import Mount

sys.path.insert(0, str(Path(__file__).parents[1] / "experiments"))
from fake_cell import PAPER_MODEL, R_DOWN, FakeCell


class _Clock:
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
    clock = _Clock()
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
    clock = _Clock()
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
    clock = _Clock()
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
    clock = _Clock()
    limiter = RateLimiter(0.001, clock=clock, sleep=clock.sleep, log_overruns=False)
    clock.now += 0.0004
    limiter.sleep()  # a first loop's cycle
    clock.now += 0.5  # a pause before the next loop on the same robot: no stall of that loop
    limiter.restart()
    clock.now += 0.0004
    assert limiter.sleep() == pytest.approx(0.0006, abs=1e-9)
    assert limiter.periods_behind == 0


def test_a_loop_that_overruns_every_period_falls_further_behind() -> None:
    clock = _Clock()
    limiter = RateLimiter(0.001, clock=clock, sleep=clock.sleep, log_overruns=False)
    behind = []
    for _ in range(60):
        clock.now += 0.0015  # each cycle takes one and a half periods
        limiter.sleep()
        behind.append(limiter.periods_behind)
    assert behind == sorted(behind) and behind[-1] >= 20


def test_rate_limiter_restarts_its_schedule_after_a_long_stall() -> None:
    clock = _Clock()
    limiter = RateLimiter(0.01, clock=clock, sleep=clock.sleep)
    clock.now += 0.5
    limiter.sleep()
    clock.now += 0.002
    assert limiter.sleep() == pytest.approx(0.008, abs=1e-12)  # no burst to catch up


def test_a_cycle_reads_compensates_and_the_loop_ends_when_the_step_says_so() -> None:
    cell = FakeCell(1500.0)
    cell.move_to_clearance(0.05)  # hanging in free air: the contact wrench is the load
    cycle = ControlCycle(cell, cell, compensator=GravityCompensator(PAPER_MODEL))
    seen: list[Reading] = []

    def step(reading: Reading) -> np.ndarray | None:
        seen.append(reading)
        return None if len(seen) == 5 else np.zeros(6)

    stats = run_loop(cycle, step)
    assert stats.cycles == 4 and len(seen) == 5
    force_base = R_DOWN @ seen[-1].wrench_contact_sensor[:3]
    np.testing.assert_allclose(force_base, [0.0, 0.0, -cell.weight], atol=1e-9)
    assert seen[1].now_ns - seen[0].now_ns == 1_000_000


def test_the_loop_stops_the_robot_when_the_step_raises() -> None:
    cell = FakeCell(1500.0)
    cycle = ControlCycle(cell, cell, mount=Mount())
    calls = []

    def step(reading: Reading) -> np.ndarray | None:
        calls.append(reading)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return np.array([0.0, 0.0, -0.01, 0.0, 0.0, 0.0])

    with pytest.raises(KeyboardInterrupt):
        run_loop(cycle, step)
    assert cell.v_cmd == 0.0  # stopped before the exception left the loop


def test_a_loop_that_keeps_overrunning_is_a_fault_and_stops_the_robot() -> None:
    clock = _Clock()
    cell = FakeCell(1500.0)
    limiter = RateLimiter(0.001, clock=clock, sleep=clock.sleep)
    cycle = ControlCycle(cell, cell, rate_limiter=limiter, max_late_cycles=3)

    def slow_step(reading: Reading) -> np.ndarray | None:
        clock.now += 0.004  # every cycle's work takes 4 periods
        return np.array([0.0, 0.0, -0.01, 0.0, 0.0, 0.0])

    with pytest.raises(LoopOverrunError, match="fell 3 of its 1 ms periods behind"):
        run_loop(cycle, slow_step)
    assert cell.v_cmd == 0.0
