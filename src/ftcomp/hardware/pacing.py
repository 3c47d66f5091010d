"""How a live loop keeps time, in one place: its schedule, its lateness, its timing summary,
real-time scheduling and the garbage collector.

Every loop on the host's clock keeps time with this module: a hardware robot's
:meth:`~ftcomp.hardware.protocols.Robot.wait_cycle`, :func:`ftcomp.control.loop.run_loop` (the
one loop of ``ftcomp run``, ``stream`` and ``record``) and ``ftcomp twin``'s cell.

- :class:`RateLimiter` keeps a schedule on :func:`time.perf_counter`: it sleeps until the next
  period, reports its slack and how far the loop has fallen behind (``periods_behind``), so a
  loop can treat a robot that falls behind as a fault; it never raises itself.
  :class:`LatenessOfPacer` makes a robot that waits on its limiter report its lateness
  (:class:`~ftcomp.hardware.protocols.ReportsLateness`).
- :class:`LoopTiming` is told when each cycle starts and when its command has been sent, and
  keeps, without allocating per cycle (counts in preallocated 1 us histograms, a few integers):

  - **start lateness**: how late the cycle started against its schedule (a grid of one period
    from the first cycle, restarted after a missed period, as :class:`RateLimiter` does). A
    cycle that starts a whole period or more late has *missed* periods (``lateness // period``
    of them) and is logged with its lateness in ms;
  - **compute time**: from the cycle's start to its command sent (read, compensate, step, log
    row, command), what the period must hold; beside it the loop thread's **CPU time** over the
    same span (:func:`time.thread_time_ns`): compute minus CPU is time the thread was off the
    CPU (preempted by a higher priority, or waiting for the interpreter's lock);
  - **sensor age at use**: from the wrench sample's stamp (a Net F/T packet's arrival on the
    host clock) to the command that used it, on the robot's clock.

  :meth:`LoopTiming.summary` gives a :class:`TimingSummary` (cycles, missed periods,
  p50/p99/max of each figure, the worst stretch of late cycles), one line by
  :meth:`TimingSummary.line`, a block for a log by :meth:`TimingSummary.as_dict`. Lateness is
  only judged for a loop on wall-clock time (``paced=True``): a simulated cell's loop runs as
  fast as its physics and has no schedule.
- :func:`realtime_loop` is what a live loop on the host's clock asks of the process while it
  runs: real-time scheduling (SCHED_FIFO, as ur_rtde asks for its own loops) for the loop's
  thread and, a little lower, the process's other Python threads, so that a busy machine's
  ordinary processes cannot hold them off the CPU, and a short interpreter switch interval, so
  that a Python thread beside the loop (the observers' worker) hands the interpreter's lock back
  within a fraction of a period (the default, 5 ms, is 2.5 periods at 500 Hz), and a timer slack of
  1 ns, so that the limiter's sleep ends on time (an ordinary thread's default slack, 50 us,
  doubles its median wake-up delay). Where the OS refuses real-time scheduling (no
  CAP_SYS_NICE, an ``rtprio`` limit of 0, a container without it) it says so once, with how to
  allow it, and the loop runs at normal priority. A device client's native threads keep the
  scheduling their library gives them (libfranka raises its own control thread's; ur_rtde
  takes an ``rt_priority``): raised to the loop's, ur_rtde's receive thread, which polls its
  socket every 0.1 ms and at times ran 75 ms without a pause, took the twin's core (its cell
  late in 250-390 of 3000 periods a run; 0-7 left to them) and the one where the kernel's
  worker waited to hand a serial sensor's bytes on (a Bota Gen0 stream 77 ms silent), and
  numpy's and scipy's OpenBLAS workers, which spin up to 2^28 cycles between jobs, held a core
  for 80 ms (both traced with the kernel's sched_switch events, 2026-11-29).
- :class:`LoopClock` is all of it for one loop, as a context manager: on entry the collector's
  policy (what exists after the set-up collected once and frozen, automatic collection off, so
  that the loop's own garbage is collected in its slack, :meth:`LoopClock.collect`) and
  :func:`realtime_loop`; per cycle :meth:`~LoopClock.start`, :meth:`~LoopClock.sent` and
  :meth:`~LoopClock.wait` (or the robot's own wait); at the end :meth:`~LoopClock.summary`.
"""

from __future__ import annotations

import contextlib
import gc
import logging
import math
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from types import TracebackType
from typing import Final

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.protocols import HOST_CLOCK, Robot

_log = logging.getLogger(__name__)

__all__ = [
    "LOOP_PRIORITY",
    "LOOP_SWITCH_INTERVAL_S",
    "WORKER_PRIORITY",
    "LatenessOfPacer",
    "LoopClock",
    "LoopTiming",
    "RateLimiter",
    "TimingSummary",
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
    ``restart_after_s`` (a whole period by default) the schedule restarts from now instead of
    trying to catch up; a shorter one is caught up by the next periods.

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
        restart_after_s: an overrun longer than this is a stall: the schedule restarts from
            now [s], >= the period (None: one period).
    """

    def __init__(
        self,
        period_s: float,
        *,
        name: str = "loop",
        clock: Callable[[], float] = time.perf_counter,
        sleep: Callable[[float], None] = time.sleep,
        log_overruns: bool = True,
        restart_after_s: float | None = None,
    ) -> None:
        if not period_s > 0.0:
            raise ParameterError(f"period_s must be > 0 s, got {period_s}")
        restart = period_s if restart_after_s is None else restart_after_s
        if not (math.isfinite(restart) and restart >= period_s):
            raise ParameterError(
                f"restart_after_s must be >= the period ({period_s:g} s), got {restart_after_s}"
            )
        self.period_s = period_s
        self.restart_after_s = restart
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
        if -slack > self.restart_after_s:  # a stall: a new schedule from now, the time lost owed
            self._behind_s -= slack
            self._next = now + self.period_s
        else:  # the schedule kept: the next period is shorter by the overrun
            self._next += self.period_s
        return slack

    def wait_at_rest(
        self, is_still: Callable[[], bool], hold_s: float, max_duration_s: float, robot: str
    ) -> float:
        """A robot's ``settle``: poll ``is_still()`` once a period until it has held for
        ``hold_s`` [s]; return the time taken [s].

        Raises:
            HardwareError: not still for ``hold_s`` within ``max_duration_s`` [s] (the message
                starts with ``robot``, its URI).
        """
        t0 = self._clock()
        still_since: float | None = None
        while True:
            now = self._clock()
            if is_still():
                still_since = now if still_since is None else still_since
                if now - still_since >= hold_s:
                    return now - t0
            else:
                still_since = None
            if now - t0 > max_duration_s:
                raise HardwareError(
                    f"{robot}: the arm did not come to rest within {max_duration_s:g} s"
                )
            self.sleep()

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


@contextlib.contextmanager
def realtime_loop(priority: int = LOOP_PRIORITY, *, realtime: bool = True) -> Iterator[bool]:
    """While the block runs: the switch interval at :data:`LOOP_SWITCH_INTERVAL_S` and, with
    ``realtime``, SCHED_FIFO at ``priority`` for the calling thread and at
    :data:`WORKER_PRIORITY` for the other Python threads (the sensors' readers, the observers'
    worker): each holds the interpreter's lock in turn, and one that an ordinary process
    preempts while it holds the lock would stall the loop and the readers behind it (seen: a
    view's worker under a busy loop on each core aged the Net F/T's data past the stale
    limit). A device client's native threads are left as their library set them (module
    docstring). All undone on exit. Yields whether real-time scheduling was
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
            for tid in python:
                with contextlib.suppress(OSError):  # a thread that just ended
                    if tid and os.sched_getscheduler(tid) == os.SCHED_OTHER:  # not its own
                        os.sched_setscheduler(tid, os.SCHED_FIFO, worker)
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


#: Histogram range [us]: 1 us bins up to 100 ms; longer values land in the last bin (their
#: maximum is kept exactly).
_BINS = 100_000
#: A late cycle is logged at most this often [ns] (the summary counts them all).
_LOG_EVERY_NS: Final = 1_000_000_000


@dataclass(frozen=True)
class TimingSummary:
    """How a loop kept time (see the module docstring). Times in seconds.

    Attributes:
        period_s: the loop's period [s].
        paced: whether lateness was judged (a wall-clock loop); False: a simulated loop.
        cycles: cycles timed.
        missed_periods: periods in which no cycle started (0 when not paced).
        late_cycles: cycles that started one period or more late.
        worst_late_in_a_row: the longest run of such cycles back to back (the worst stretch).
        worst_gap_s: the longest time between two cycle starts [s].
        lateness_p99_s, lateness_max_s: start lateness [s].
        compute_p50_s, compute_p99_s, compute_max_s: compute time [s].
        age_p50_s, age_p99_s, age_max_s: sensor age at use [s] (NaN: no sample stamps).
        realtime: whether the loop ran with real-time scheduling.
        cpu_p50_s, cpu_p99_s: the loop thread's CPU time over the compute span [s] (NaN: not
            measured).
    """

    period_s: float
    paced: bool
    cycles: int
    missed_periods: int
    late_cycles: int
    worst_late_in_a_row: int
    worst_gap_s: float
    lateness_p99_s: float
    lateness_max_s: float
    compute_p50_s: float
    compute_p99_s: float
    compute_max_s: float
    age_p50_s: float
    age_p99_s: float
    age_max_s: float
    realtime: bool = False
    cpu_p50_s: float = math.nan
    cpu_p99_s: float = math.nan

    def __post_init__(self) -> None:
        if not self.period_s > 0.0:
            raise ParameterError(f"period_s must be > 0, got {self.period_s}")
        for name in ("cycles", "missed_periods", "late_cycles", "worst_late_in_a_row"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 0):
                raise ParameterError(f"{name} must be an integer >= 0, got {value!r}")

    @property
    def missed_fraction(self) -> float:
        """Missed periods over the periods the loop ran (cycles + missed); 0 without cycles."""
        total = self.cycles + self.missed_periods
        return self.missed_periods / total if total else 0.0

    def line(self) -> str:
        """One line: ``timing: N cycles at P ms, M missed periods (x %), compute ...``."""

        def ms(v: float) -> str:
            return "n/a" if math.isnan(v) else f"{v * 1e3:.2f}"

        text = f"timing: {self.cycles} cycles at {self.period_s * 1e3:g} ms"
        if self.paced:
            text += " (real-time)" if self.realtime else " (normal priority)"
            text += (
                f", {self.missed_periods} missed periods ({self.missed_fraction:.2%}), "
                f"start late p99 {ms(self.lateness_p99_s)} max {ms(self.lateness_max_s)} ms"
            )
        text += (
            f"; compute p50 {ms(self.compute_p50_s)} p99 {ms(self.compute_p99_s)} "
            f"max {ms(self.compute_max_s)} ms"
            + (
                ""
                if math.isnan(self.cpu_p50_s)
                else f" (cpu p50 {ms(self.cpu_p50_s)} p99 {ms(self.cpu_p99_s)})"
            )
            + f"; sensor age p50 {ms(self.age_p50_s)} "
            f"p99 {ms(self.age_p99_s)} max {ms(self.age_max_s)} ms"
        )
        if self.paced:
            text += (
                f"; worst stretch {self.worst_late_in_a_row} late in a row, "
                f"longest gap {ms(self.worst_gap_s)} ms"
            )
        return text

    def as_dict(self) -> dict[str, float | int | bool | None]:
        """The fields by name (a log's timing block; NaN, a figure not known, as None)."""
        return {
            k: None if isinstance(v, float) and math.isnan(v) else v
            for k, v in asdict(self).items()
        }


def _percentile_s(hist: NDArray[np.int64], q: float, n: int) -> float:
    """The ``q`` quantile [s] of ``n`` values counted in 1 us bins (the bin's upper edge)."""
    if n == 0:
        return math.nan
    k = int(np.searchsorted(np.cumsum(hist), math.ceil(q * n)))
    return (k + 1) * 1e-6


class LoopTiming:
    """Per-cycle timing of one loop (see the module docstring).

    Call :meth:`start` when a cycle starts and :meth:`sent` once its command has been sent.

    Args:
        period_s: the loop's period [s], > 0.
        paced: judge start lateness (a loop on wall-clock time).
        name: names the loop in the log message of a late cycle.
        log_late: log late cycles (at most one line a second); off for a loop whose late
            cycles lose nothing (a logger that reads every buffered reading): they are still
            counted.
        clock_ns: the time source of lateness and compute time [ns] (for tests).
        cpu_clock_ns: the calling thread's CPU time [ns] (for tests).
    """

    def __init__(
        self,
        period_s: float,
        *,
        paced: bool = True,
        name: str = "control loop",
        log_late: bool = True,
        clock_ns: Callable[[], int] = time.perf_counter_ns,
        cpu_clock_ns: Callable[[], int] = time.thread_time_ns,
    ) -> None:
        if not (math.isfinite(period_s) and period_s > 0.0):
            raise ParameterError(f"period_s must be > 0 s, got {period_s}")
        self.period_s = period_s
        self.paced = paced
        #: Whether the loop runs with real-time scheduling (set by its runner).
        self.realtime = False
        self.name = name
        self.log_late = log_late
        self._clock = clock_ns
        self._cpu_clock = cpu_clock_ns
        self._period_ns = round(period_s * 1e9)
        self._compute = np.zeros(_BINS + 1, dtype=np.int64)
        self._cpu = np.zeros(_BINS + 1, dtype=np.int64)
        self._age = np.zeros(_BINS + 1, dtype=np.int64)
        self._late = np.zeros(_BINS + 1, dtype=np.int64)
        self.cycles = 0
        self.aged = 0
        self.missed_periods = 0
        self.late_cycles = 0
        #: Cycles in a row up to now that started a period or more late.
        self.late_in_a_row = 0
        self.worst_late_in_a_row = 0
        self._start_ns = 0
        self._start_cpu_ns = 0
        self._due_ns: int | None = None
        self._last_start_ns: int | None = None
        self._worst_gap_ns = 0
        self._max_compute_ns = 0
        self._max_age_ns = -1
        self._max_late_ns = 0
        self._logged_at_ns: int | None = None
        self._unlogged = 0

    def start(self) -> None:
        """A cycle starts now: judge its lateness (a missed period is logged, at most one line
        a second: the next one counts those in between)."""
        self._start_cpu_ns = self._cpu_clock()
        now = self._clock()
        self._start_ns = now
        if not self.paced:
            return
        last = self._last_start_ns
        if last is not None and now - last > self._worst_gap_ns:
            self._worst_gap_ns = now - last
        self._last_start_ns = now
        due = self._due_ns
        if due is None:
            self._due_ns = now + self._period_ns
            self._late[0] += 1
            return
        late = now - due
        if late < 0:
            late = 0
        self._late[min(late // 1000, _BINS)] += 1
        if late > self._max_late_ns:
            self._max_late_ns = late
        if late >= self._period_ns:
            missed = late // self._period_ns
            self.missed_periods += missed
            self.late_cycles += 1
            self.late_in_a_row += 1
            if self.late_in_a_row > self.worst_late_in_a_row:
                self.worst_late_in_a_row = self.late_in_a_row
            # At most one line a second: the write is the loop's own (stderr, a pipe that may
            # be read slowly or not at all, and then blocks), and a loaded host makes hundreds
            # of late cycles a second (a twin logging each one filled its pipe and stopped).
            since = None if self._logged_at_ns is None else now - self._logged_at_ns
            if self.log_late and (since is None or since >= _LOG_EVERY_NS):
                _log.warning(
                    "%s: cycle %d started %.1f ms late (periods missed: %d)%s",
                    self.name,
                    self.cycles,
                    late * 1e-6,
                    missed,
                    f"; {self._unlogged} more late cycles since the last line"
                    if self._unlogged
                    else "",
                )
                self._logged_at_ns, self._unlogged = now, 0
            else:
                self._unlogged += 1
            self._due_ns = now + self._period_ns  # a new schedule from now, no burst
        else:
            self.late_in_a_row = 0
            self._due_ns = due + self._period_ns

    def sent(self, sensor_age_ns: int | None = None) -> None:
        """The cycle's command has been sent; ``sensor_age_ns``: the robot's clock now minus the
        sample's stamp [ns] (None: not known)."""
        compute = self._clock() - self._start_ns
        cpu = self._cpu_clock() - self._start_cpu_ns
        self.cycles += 1
        self._compute[min(compute // 1000, _BINS)] += 1
        self._cpu[min(max(cpu, 0) // 1000, _BINS)] += 1
        if compute > self._max_compute_ns:
            self._max_compute_ns = compute
        if sensor_age_ns is not None:
            age = sensor_age_ns if sensor_age_ns > 0 else 0
            self.aged += 1
            self._age[min(age // 1000, _BINS)] += 1
            if age > self._max_age_ns:
                self._max_age_ns = age

    def summary(self) -> TimingSummary:
        """The figures so far."""
        n, lateness_n = self.cycles, int(self._late.sum())
        return TimingSummary(
            period_s=self.period_s,
            paced=self.paced,
            cycles=n,
            missed_periods=int(self.missed_periods),
            late_cycles=self.late_cycles,
            worst_late_in_a_row=self.worst_late_in_a_row,
            worst_gap_s=self._worst_gap_ns * 1e-9,
            lateness_p99_s=_percentile_s(self._late, 0.99, lateness_n),
            lateness_max_s=self._max_late_ns * 1e-9,
            compute_p50_s=_percentile_s(self._compute, 0.5, n),
            compute_p99_s=_percentile_s(self._compute, 0.99, n),
            compute_max_s=self._max_compute_ns * 1e-9 if n else math.nan,
            age_p50_s=_percentile_s(self._age, 0.5, self.aged),
            age_p99_s=_percentile_s(self._age, 0.99, self.aged),
            age_max_s=self._max_age_ns * 1e-9 if self.aged else math.nan,
            realtime=self.realtime,
            cpu_p50_s=_percentile_s(self._cpu, 0.5, n),
            cpu_p99_s=_percentile_s(self._cpu, 0.99, n),
        )


#: A paced loop's pause between its set-up and its first cycle [s].
_AFTER_SETUP_S = 0.01


def _collect_in_slack() -> None:
    """The collection the interpreter would have started by itself (its thresholds), run by a
    loop whose automatic collection is off (:class:`LoopClock`) after its cycle's command has
    been sent instead of in the middle of a cycle."""
    young, middle, old = gc.get_count()
    threshold0, threshold1, threshold2 = gc.get_threshold()
    if young < threshold0:
        return
    gc.collect(2 if old >= threshold2 else 1 if middle >= threshold1 else 0)


class LoopClock:
    """Time for one live loop (module docstring): its timing, its schedule, real-time
    scheduling and the collector, as a context manager around the loop (not its set-up).

    Per cycle: :meth:`start`, the cycle's work, :meth:`sent` once its output has left, then
    either :meth:`wait` (a loop that keeps its own period: the twin's cell) or :meth:`collect`
    and the robot's own wait (:func:`ftcomp.control.loop.run_loop`: a hardware robot waits on
    its pacer, a simulated one steps its physics).

    A paced loop (on the host's clock) keeps the garbage collector out of its cycles: on entry
    what exists (the set-up) is collected once and frozen (:func:`gc.freeze`), so the
    collections the loop's own garbage needs scan only that (a few objects) instead of every
    object of the process (tens of milliseconds with numpy, scipy, MuJoCo and a client library
    loaded), and automatic collection is off: :meth:`collect` runs the collection the
    interpreter would have started, between cycles. It runs in :func:`realtime_loop` at
    ``priority`` (SCHED_FIFO where the OS allows it, with ``realtime``). All undone on exit (a
    caller's own freeze stays). An unpaced loop (a simulated cell) is only timed.

    Args:
        period_s: the loop's period [s], > 0.
        paced: the loop runs on the host's clock: lateness judged, the collector's policy,
            real-time scheduling.
        name: names the loop in the log message of a late cycle.
        priority: the SCHED_FIFO priority asked for (:data:`LOOP_PRIORITY`).
        realtime: ask for real-time scheduling (a paced loop only).
        restart_after_s: :meth:`wait` restarts its schedule from now once the loop is this far
            behind [s] (None: one period; shorter lateness is caught up). See
            :class:`RateLimiter`.
        log_late: log late cycles (:class:`LoopTiming`).
        clock_ns: the time source [ns] (for tests).
        cpu_clock_ns: the loop thread's CPU time [ns] (for tests).
        sleep: the sleep function [s] (for tests).

    Attributes:
        timing: the per-cycle figures (:class:`LoopTiming`).
        pacer: the schedule :meth:`wait` keeps (:class:`RateLimiter`).
    """

    def __init__(
        self,
        period_s: float,
        *,
        paced: bool = True,
        name: str = "control loop",
        priority: int = LOOP_PRIORITY,
        realtime: bool = True,
        restart_after_s: float | None = None,
        log_late: bool = True,
        clock_ns: Callable[[], int] = time.perf_counter_ns,
        cpu_clock_ns: Callable[[], int] = time.thread_time_ns,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        self.timing = LoopTiming(
            period_s,
            paced=paced,
            name=name,
            log_late=log_late,
            clock_ns=clock_ns,
            cpu_clock_ns=cpu_clock_ns,
        )
        self.pacer = RateLimiter(
            period_s,
            name=name,
            clock=lambda: clock_ns() * 1e-9,
            sleep=sleep,
            log_overruns=False,  # the timing logs late cycles
            restart_after_s=restart_after_s,
        )
        self.period_s = period_s
        self.paced = paced
        self.name = name
        self.priority = priority
        self.realtime_asked = realtime
        self._sleep = sleep
        self._exit: contextlib.ExitStack | None = None

    @property
    def realtime(self) -> bool:
        """Whether the loop runs with real-time scheduling (known once entered)."""
        return self.timing.realtime

    def __enter__(self) -> LoopClock:
        if self._exit is not None:
            raise ParameterError(f"{self.name}: its clock is running already")
        stack = contextlib.ExitStack()
        if self.paced:
            automatic, frozen_before = gc.isenabled(), gc.get_freeze_count()

            def restore() -> None:
                if automatic:
                    gc.enable()
                if not frozen_before:  # a caller's own freeze stays
                    gc.unfreeze()

            gc.collect()
            gc.freeze()
            gc.disable()  # collected in the slack instead (collect)
            stack.callback(restore)
        try:
            self.timing.realtime = stack.enter_context(
                realtime_loop(self.priority, realtime=self.paced and self.realtime_asked)
            )
            if self.paced:
                # The device clients' readers deliver what arrived while the set-up (the
                # collection above: 50-80 ms) held the interpreter's lock: the first cycle's
                # reading was once older than the stale limit, a healthy stream stopped.
                self._sleep(_AFTER_SETUP_S)
        except BaseException:
            stack.close()
            raise
        self.pacer.restart()  # the schedule starts with the loop: its set-up is no stall
        self._exit = stack
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        stack, self._exit = self._exit, None
        if stack is not None:
            stack.close()

    def start(self) -> None:
        """A cycle starts now (its lateness judged: :meth:`LoopTiming.start`)."""
        self.timing.start()

    def sent(self, sensor_age_ns: int | None = None) -> None:
        """The cycle's output has left (:meth:`LoopTiming.sent`); ``sensor_age_ns``: the
        robot's clock now minus the sample's stamp [ns] (None: not known)."""
        self.timing.sent(sensor_age_ns)

    def collect(self) -> None:
        """In the slack after a cycle's output: the collection the interpreter would have
        started (a paced loop; nothing otherwise)."""
        if self.paced:
            _collect_in_slack()

    def wait(self) -> float:
        """:meth:`collect`, then sleep until the next period starts (a schedule one period
        apart from entry, restarted from now after a stall longer than ``restart_after_s``);
        the slack [s] (negative: the cycle overran)."""
        self.collect()
        return self.pacer.sleep()

    def summary(self) -> TimingSummary:
        """The timing so far (:meth:`LoopTiming.summary`)."""
        return self.timing.summary()
