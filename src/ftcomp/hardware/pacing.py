"""Pacing for hardware robots: wait for the next control period on the host's clock.

A real robot's :meth:`~ftcomp.hardware.protocols.Robot.wait_cycle` blocks until its next period
starts. :class:`RateLimiter` keeps that schedule on :func:`time.perf_counter`, reports its slack
and counts late periods, so a loop can treat a robot that falls behind as a fault
(``late_in_a_row``); it never raises itself. The same limiter holds any loop to wall-clock time
(:class:`ftcomp.control.loop.ControlCycle`).

Also here: the optional capabilities a backend may offer beyond the protocols (a loop asks with
``isinstance``): :class:`CountsLostPackets` for a streaming sensor that numbers its packets and
:class:`ChecksReachability` for a robot that can tell, before moving, whether it can reach a pose.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import ParameterError

_log = logging.getLogger(__name__)

__all__ = ["ChecksReachability", "CountsLostPackets", "RateLimiter", "on_host_clock"]


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


def on_host_clock(robot: object) -> bool:
    """Whether a robot's clock is the host's monotonic clock (that of sensors stamped on
    arrival): as it declares (``clock_name``), or else as its ``now_ns()`` reads (within 1 s)."""
    name = getattr(robot, "clock_name", None)
    if name is not None:
        return bool(name == "monotonic")
    now_ns = getattr(robot, "now_ns", None)
    return now_ns is not None and abs(now_ns() - time.monotonic_ns()) < 1_000_000_000


@runtime_checkable
class CountsLostPackets(Protocol):
    """A streaming sensor that numbers its packets and so knows how many never arrived."""

    @property
    def lost_packets(self) -> int:
        """Packets lost since the stream started."""
        ...

    @property
    def rate_hz(self) -> float:
        """The measured rate of arriving samples [Hz]."""
        ...


@runtime_checkable
class ChecksReachability(Protocol):
    """A robot that can check a target before moving (inverse kinematics, safety limits)."""

    def is_reachable(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64]
    ) -> bool:
        """Whether the TCP can be brought to this pose (base frame) within the robot's limits."""
        ...
