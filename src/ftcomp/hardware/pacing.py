"""Pacing for hardware robots: wait for the next control period on the host's clock.

A real robot's :meth:`~ftcomp.hardware.protocols.Robot.wait_cycle` blocks until its next period
starts. :class:`RateLimiter` keeps that schedule on :func:`time.perf_counter`, reports its slack
and counts late periods, so a loop can treat a robot that falls behind as a fault
(``late_in_a_row``); it never raises itself. The same limiter holds any loop to wall-clock time
(:class:`ftcomp.control.loop.ControlCycle`). :class:`LatenessOfPacer` makes a robot that waits on
its limiter report its lateness (:class:`~ftcomp.hardware.protocols.ReportsLateness`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import HOST_CLOCK, Robot

_log = logging.getLogger(__name__)

__all__ = ["LatenessOfPacer", "RateLimiter", "on_host_clock"]


class RateLimiter:
    """Hold a loop to a fixed period of wall-clock time (``time.perf_counter``).

    Call :meth:`sleep` once per cycle, after the cycle's work: it sleeps until the next period
    starts and returns the slack (negative when the cycle overran). An overrun is logged with its
    lateness (at most once a second) and counted; it never raises. After an overrun of more than
    a whole period the schedule restarts from now instead of trying to catch up.

    Args:
        period_s: the loop period [s], > 0.
        name: names the loop in log messages.
        clock: the time source [s] (for tests).
        sleep: the sleep function [s] (for tests).
        log_overruns: log each overrun (at most once a second); a robot backend that lets its
            loop judge lateness (``late_in_a_row``) passes False.
    """

    def __init__(
        self,
        period_s: float,
        *,
        name: str = "loop",
        clock: Callable[[], float] = time.perf_counter,
        sleep: Callable[[float], None] = time.sleep,
        log_overruns: bool = True,
    ) -> None:
        if not period_s > 0.0:
            raise ParameterError(f"period_s must be > 0 s, got {period_s}")
        self.period_s = period_s
        self.name = name
        self._clock = clock
        self._sleep = sleep
        self._log_overruns = log_overruns
        self._next = clock() + period_s
        self._last_log = -float("inf")
        #: Slack of the last cycle [s] (negative: it overran by that much).
        self.slack_s = 0.0
        #: Cycles that overran since the start, and in a row up to now.
        self.overruns = 0
        self.late_in_a_row = 0
        #: The most negative slack seen [s].
        self.worst_slack_s = 0.0

    def sleep(self) -> float:
        """Wait for the next period; return the slack [s]."""
        now = self._clock()
        slack = self._next - now
        self.slack_s = slack
        if slack >= 0.0:
            self.late_in_a_row = 0
            self._sleep(slack)
            self._next += self.period_s
            return slack
        self.overruns += 1
        self.late_in_a_row += 1
        self.worst_slack_s = min(self.worst_slack_s, slack)
        if self._log_overruns and now - self._last_log >= 1.0:
            _log.warning("%s is late by %.1f ms", self.name, -slack * 1e3)
            self._last_log = now
        self._next = now + self.period_s if -slack > self.period_s else self._next + self.period_s
        return slack


class LatenessOfPacer:
    """The :class:`~ftcomp.hardware.protocols.ReportsLateness` capability of a robot whose
    :meth:`~ftcomp.hardware.protocols.Robot.wait_cycle` waits on its ``pacer`` (a mixin)."""

    pacer: RateLimiter

    @property
    def late_in_a_row(self) -> int:
        """Control periods missed in a row up to now."""
        return self.pacer.late_in_a_row

    @property
    def late_cycles(self) -> int:
        """Cycles that overran their period since the start."""
        return self.pacer.overruns

    @property
    def worst_lateness_s(self) -> float:
        """The largest overrun seen [s] (0 when none)."""
        return max(0.0, -self.pacer.worst_slack_s)


def on_host_clock(robot: Robot) -> bool:
    """Whether a robot's clock is the host's monotonic clock (that of sensors stamped on
    arrival), as it declares (:attr:`~ftcomp.hardware.protocols.Robot.clock_name`)."""
    return robot.clock_name == HOST_CLOCK
