"""A live one-line status for loops on hardware: rate, lost packets, contact force.

:class:`StatusLine` is a :func:`~ftcomp.control.loop.run_loop` sink: a few times a second it
rewrites one line on a terminal (``\\r``), e.g. ``1000 Hz | lost 3 | |F| 0.412 N | 1.2 / 2 s``.
Off a terminal (a pipe, a log file, a test) it stays silent.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from typing import TextIO

__all__ = ["StatusLine"]


class StatusLine:
    """The status line (see the module docstring).

    Args:
        count: readings so far (for the rate).
        lost: packets lost so far, or None when the sensor cannot tell.
        force_N: the current contact force to show [N] (NaN: not shown).
        elapsed_s: time since the start [s].
        total_s: the planned duration [s].
        stream: where to write (stderr).
        period_s: how often to refresh [s].
        extra: more to show at the end (e.g. the online load), "" for nothing.
    """

    def __init__(
        self,
        count: Callable[[], int],
        lost: Callable[[], int] | None,
        force_N: Callable[[], float],
        elapsed_s: Callable[[], float],
        total_s: float,
        *,
        stream: TextIO | None = None,
        period_s: float = 0.25,
        extra: Callable[[], str] | None = None,
    ) -> None:
        self.count, self.lost, self.force_N, self.extra = count, lost, force_N, extra
        self.elapsed_s, self.total_s = elapsed_s, total_s
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = self.stream.isatty()
        self.period_s = period_s
        self._last_t = time.monotonic()
        self._last_count = 0
        self.shown = False

    def text(self, rate_hz: float) -> str:
        """The line for a rate [Hz]."""
        parts = [f"{rate_hz:6.0f} Hz"]
        if self.lost is not None:
            parts.append(f"lost {self.lost()}")
        force = self.force_N()
        if math.isfinite(force):
            parts.append(f"|F| {force:.3f} N")
        parts.append(f"{self.elapsed_s():.1f} / {self.total_s:g} s")
        more = self.extra() if self.extra is not None else ""
        return " | ".join([*parts, more] if more else parts)

    def __call__(self, *_: object) -> None:
        """Refresh when due (a sink: arguments ignored)."""
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self._last_t < self.period_s:
            return
        count = self.count()
        rate = (count - self._last_count) / (now - self._last_t)
        self._last_t, self._last_count = now, count
        self.stream.write("\r" + self.text(rate) + "   ")
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        """End the line."""
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()
