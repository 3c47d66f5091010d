"""Pacing for hardware robots: wait for the next control period on the host's clock.

A real robot's :meth:`~ftcomp.hardware.protocols.Robot.wait_cycle` blocks until its next period
starts. :class:`Pacer` keeps that schedule on :func:`time.perf_counter` and counts late
periods, so a loop can treat a robot that falls behind as a fault
(``pacer.late_in_a_row``); it never raises itself. After a period missed by more than a whole
period the schedule restarts from now instead of trying to catch up.

Also here: the optional capabilities a backend may offer beyond the protocols (a loop asks with
``isinstance``): :class:`CountsLostPackets` for a streaming sensor that numbers its packets and
:class:`ChecksReachability` for a robot that can tell, before moving, whether it can reach a pose.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import ParameterError

__all__ = ["ChecksReachability", "CountsLostPackets", "Pacer", "on_host_clock"]


class Pacer:
    """Sleep until the next period of a fixed schedule.

    Args:
        period_s: the period [s], > 0.
        clock: time source [s] (for tests).
        sleep: sleep function [s] (for tests).

    Attributes:
        late: periods missed since the start; late_in_a_row: missed in a row up to now;
        worst_late_s: the largest lateness seen [s].
    """

    def __init__(
        self,
        period_s: float,
        *,
        clock: Callable[[], float] = time.perf_counter,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        if not period_s > 0.0:
            raise ParameterError(f"period_s must be > 0 s, got {period_s}")
        self.period_s = period_s
        self._clock = clock
        self._sleep = sleep
        self._next = clock() + period_s
        self.late = 0
        self.late_in_a_row = 0
        self.worst_late_s = 0.0

    def wait(self) -> None:
        """Block until the next period starts (at once when already late)."""
        now = self._clock()
        slack = self._next - now
        if slack >= 0.0:
            self.late_in_a_row = 0
            self._sleep(slack)
            self._next += self.period_s
            return
        self.late += 1
        self.late_in_a_row += 1
        self.worst_late_s = max(self.worst_late_s, -slack)
        self._next = now + self.period_s if -slack > self.period_s else self._next + self.period_s


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
