"""How a live loop kept time: per-cycle lateness, compute time and sensor age, and a summary.

:class:`LoopTiming` is told when each cycle starts and when its command has been sent, and keeps,
without allocating per cycle (counts in preallocated 1 us histograms, a few integers):

- **start lateness**: how late the cycle started against its schedule (a grid of one period from
  the first cycle, restarted after a missed period, as :class:`~ftcomp.hardware.pacing.
  RateLimiter` does). A cycle that starts a whole period or more late has *missed* periods
  (``lateness // period`` of them) and is logged with its lateness in ms;
- **compute time**: from the cycle's start to its command sent (read, compensate, step, log row,
  command), what the period must hold; beside it the loop thread's **CPU time** over the same
  span (:func:`time.thread_time_ns`): compute minus CPU is time the thread was off the CPU
  (preempted by a higher priority, or waiting for the interpreter's lock);
- **sensor age at use**: from the wrench sample's stamp (a Net F/T packet's arrival on the host
  clock) to the command that used it, on the robot's clock.

:meth:`LoopTiming.summary` gives a :class:`TimingSummary` (cycles, missed periods, p50/p99/max of
each figure, the worst stretch of late cycles), one line by :meth:`TimingSummary.line`, a block
for a log by :meth:`TimingSummary.as_dict`. Lateness is only judged for a loop on wall-clock time
(``paced=True``): a simulated cell's loop runs as fast as its physics and has no schedule.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import ParameterError

__all__ = ["LoopTiming", "TimingSummary"]

_log = logging.getLogger(__name__)

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
        clock_ns: the time source of lateness and compute time [ns] (for tests).
        cpu_clock_ns: the calling thread's CPU time [ns] (for tests).
    """

    def __init__(
        self,
        period_s: float,
        *,
        paced: bool = True,
        name: str = "control loop",
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
            if self._logged_at_ns is None or now - self._logged_at_ns >= _LOG_EVERY_NS:
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
