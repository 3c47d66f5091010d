"""Pacing for hardware robots: wait for the next control period on the host's clock.

A real robot's :meth:`~ftcomp.hardware.protocols.Robot.wait_cycle` blocks until its next period
starts. :class:`RateLimiter` keeps that schedule on :func:`time.perf_counter`, reports its slack
and how far the loop has fallen behind, so a loop can treat a robot that falls behind as a fault
(``periods_behind``); it never raises itself. The same limiter holds any loop to wall-clock time
(:class:`ftcomp.control.loop.ControlCycle`). :class:`LatenessOfPacer` makes a robot that waits on
its limiter report its lateness (:class:`~ftcomp.hardware.protocols.ReportsLateness`).

:func:`realtime_loop` is what a live loop on the host's clock asks of the process while it runs
(:func:`ftcomp.control.loop.run_loop` enters it): real-time scheduling (SCHED_FIFO, as ur_rtde
asks for its own loops) for the loop's thread and the device clients' native reader threads, so
that a busy machine's ordinary processes cannot hold them off the CPU, and a short interpreter
switch interval, so that a Python thread beside the loop (the observers' worker) hands the
interpreter's lock back within a fraction of a period (the default, 5 ms, is 2.5 periods at
500 Hz), and a timer slack of 1 ns, so that the limiter's sleep ends on time (an ordinary
thread's default slack, 50 us, doubles its median wake-up delay). Where the OS refuses
real-time scheduling (no CAP_SYS_NICE, an ``rtprio`` limit of 0, a container without it) it says
so once, with how to allow it, and the loop runs at normal priority.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator

from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import HOST_CLOCK, Robot

_log = logging.getLogger(__name__)

__all__ = [
    "LOOP_PRIORITY",
    "LOOP_SWITCH_INTERVAL_S",
    "WORKER_PRIORITY",
    "LatenessOfPacer",
    "RateLimiter",
    "on_host_clock",
    "realtime_loop",
]

#: The SCHED_FIFO priority a live loop asks for: low (above every ordinary process and above
#: ``ftcomp twin``'s threads, which stand for hardware outside the machine and so never take the
#: CPU from the loop; below the kernel's own real-time threads).
LOOP_PRIORITY = 5

#: The SCHED_FIFO priority of the other Python threads while a live loop runs (below the loop
#: and the readers, above every ordinary process: see :func:`realtime_loop`).
WORKER_PRIORITY = 1

#: The interpreter's switch interval while a live loop runs [s] (Python's default: 5 ms).
LOOP_SWITCH_INTERVAL_S = 2e-4

#: How to allow real-time scheduling, said once when it is refused.
_HOW_TO_ALLOW = (
    "real-time priority refused ({why}): the loop runs at normal priority, and a busy machine "
    "can make it miss periods; allow it with `sudo setcap cap_sys_nice+ep {python}` or an "
    "rtprio limit (`ulimit -r {priority}`; /etc/security/limits.conf: `USER - rtprio "
    "{priority}`; in a container: --cap-add SYS_NICE)"
)
_said_refused = False


class RateLimiter:
    """Hold a loop to a fixed period of wall-clock time (``time.perf_counter``).

    Call :meth:`sleep` once per cycle, after the cycle's work: it sleeps until the next period
    starts and returns the slack (negative when the cycle overran). An overrun is logged with its
    lateness (at most once a second) and counted; it never raises. After an overrun of more than
    a whole period the schedule restarts from now instead of trying to catch up.

    How far the loop has fallen behind (:attr:`periods_behind`) is the time a stall took from
    the schedule, paid back by the slack of the periods after it: a stall of N periods puts
    the loop N periods behind, a few periods on time clear it, and a loop that overruns every
    period falls further behind each time. Overruns shorter than a period in a row (a wake-up
    or two late under load) leave it where it was: the kept schedule already carries them. The
    schedule starts when the limiter is made; a loop starts it again with :meth:`restart`, so
    that its set-up is no stall (:func:`ftcomp.control.loop.run_loop` does).

    Args:
        period_s: the loop period [s], > 0.
        name: names the loop in log messages.
        clock: the time source [s] (for tests).
        sleep: the sleep function [s] (for tests).
        log_overruns: log each overrun (at most once a second); a robot backend that lets its
            loop judge lateness (``periods_behind``) passes False.
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
        #: Cycles that overran since the start.
        self.overruns = 0
        self._behind_s = 0.0
        #: The most negative slack seen [s].
        self.worst_slack_s = 0.0

    def sleep(self) -> float:
        """Wait for the next period; return the slack [s]."""
        now = self._clock()
        slack = self._next - now
        self.slack_s = slack
        if slack >= 0.0:
            self._behind_s = max(0.0, self._behind_s - slack)  # idle time pays back a stall
            self._sleep(slack)
            self._next += self.period_s
            return slack
        self.overruns += 1
        self.worst_slack_s = min(self.worst_slack_s, slack)
        if self._log_overruns and now - self._last_log >= 1.0:
            _log.warning("%s is late by %.1f ms", self.name, -slack * 1e3)
            self._last_log = now
        if -slack > self.period_s:  # a stall: a new schedule from now, the time lost owed
            self._behind_s -= slack
            self._next = now + self.period_s
        else:  # the schedule kept: the next period is shorter by the overrun
            self._next += self.period_s
        return slack

    def restart(self) -> None:
        """A new schedule from now with nothing owed: a loop starts (the time since the last
        :meth:`sleep`, a pause between two loops on one robot, is no stall)."""
        self._next = self._clock() + self.period_s
        self._behind_s = 0.0

    @property
    def periods_behind(self) -> int:
        """Whole periods the loop has fallen behind its schedule, net of the slack since (see
        the class docstring)."""
        return int(self._behind_s / self.period_s + 1e-9)  # a stall of N periods: N, not N - 1


class LatenessOfPacer:
    """The :class:`~ftcomp.hardware.protocols.ReportsLateness` capability of a robot whose
    :meth:`~ftcomp.hardware.protocols.Robot.wait_cycle` waits on its ``pacer`` (a mixin)."""

    pacer: RateLimiter

    def restart_schedule(self) -> None:
        """A loop starts: the pacer's schedule from now, nothing owed
        (:meth:`RateLimiter.restart`)."""
        self.pacer.restart()

    @property
    def periods_behind(self) -> int:
        """Control periods the loop has fallen behind (:attr:`RateLimiter.periods_behind`)."""
        return self.pacer.periods_behind

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
    arrival), as it declares (:attr:`~ftcomp.hardware.protocols.Robot.clock_name`; a stand-in
    that declares none is not)."""
    return getattr(robot, "clock_name", None) == HOST_CLOCK


_PR_SET_TIMERSLACK = 29


def _timer_slack(ns: int) -> None:
    """Set the calling thread's timer slack [ns] (Linux; 0: back to the default, 50 us, by
    which an ordinary thread's sleep may overrun to let the kernel batch wake-ups)."""
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None).prctl(_PR_SET_TIMERSLACK, ctypes.c_ulong(ns), 0, 0, 0)


def _comm(path: str) -> str:
    try:
        with open(path, encoding="utf-8") as handle:
            return handle.read().strip()
    except OSError:
        return ""


def _native_threads() -> list[int]:
    """The ids of this process's threads not started by :mod:`threading` and left unnamed (a
    device client's native readers, ur_rtde's and pynetft's, carry the process's name), without
    the calling one; a named native thread (a view server's ``tokio-rt-worker``) is left as it
    is."""
    try:
        tids = {int(t) for t in os.listdir("/proc/self/task")}
    except OSError:
        return []
    python = {t.native_id for t in threading.enumerate()}
    name = _comm("/proc/self/comm")
    return sorted(t for t in tids - python if _comm(f"/proc/self/task/{t}/comm") == name)


@contextlib.contextmanager
def realtime_loop(priority: int = LOOP_PRIORITY, *, realtime: bool = True) -> Iterator[bool]:
    """While the block runs: the switch interval at :data:`LOOP_SWITCH_INTERVAL_S` and, with
    ``realtime``, SCHED_FIFO at ``priority`` for the calling thread and the device clients'
    native threads (module docstring), and at :data:`WORKER_PRIORITY` for the other Python
    threads (the observers' worker): each holds the interpreter's lock in turn, and one that an
    ordinary process preempts while it holds the lock would stall the loop and the readers
    behind it (seen: a view's worker under a busy loop on each core aged the Net F/T's data
    past the stale limit). All undone on exit. Yields whether real-time scheduling was
    granted (a refusal is logged once per process, with how to allow it).
    """
    global _said_refused
    switch = sys.getswitchinterval()
    sys.setswitchinterval(min(switch, LOOP_SWITCH_INTERVAL_S))
    _timer_slack(1)  # the loop's sleeps end on time (a real-time thread has no slack anyway)
    granted: list[int] = []
    if realtime and hasattr(os, "sched_setscheduler"):
        param = os.sched_param(priority)
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, param)
            granted.append(0)
        except OSError as exc:
            if not _said_refused:
                _said_refused = True
                _log.warning(
                    _HOW_TO_ALLOW.format(
                        why=exc.strerror or exc, python=sys.executable, priority=priority
                    )
                )
        if granted:
            worker = os.sched_param(WORKER_PRIORITY)
            me = threading.get_native_id()
            python = [t.native_id for t in threading.enumerate() if t.native_id != me]
            for tids, chosen in ((_native_threads(), param), (python, worker)):
                for tid in tids:
                    with contextlib.suppress(OSError):  # a thread that just ended
                        if tid and os.sched_getscheduler(tid) == os.SCHED_OTHER:  # not its own
                            os.sched_setscheduler(tid, os.SCHED_FIFO, chosen)
                            granted.append(tid)
    try:
        yield bool(granted)
    finally:
        sys.setswitchinterval(switch)
        _timer_slack(0)
        normal = os.sched_param(0) if granted else None
        for tid in granted:
            with contextlib.suppress(OSError):
                os.sched_setscheduler(tid, os.SCHED_OTHER, normal)  # type: ignore[arg-type]
