"""Time stamps as text, in every file ftcomp writes: to the nanosecond, fixed-point.

Ten significant digits (``%.10g``, the other values' format) of a clock that has run for hours,
or of a Unix time, drop the milliseconds: a stream log once had equal stamps. So a time stamp
[s] is written with nine decimals, whatever its size. The sample files' ``t`` column
(:func:`ftcomp.io.samples_csv.write_samples`) and the rows of the ``stream`` and ``run`` logs
(:func:`format_row`) use it.
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["format_row", "format_time"]


def format_time(t_s: float) -> str:
    """A time stamp [s] as text to the nanosecond: fixed-point, because ten significant digits
    of a clock that has run for hours (or of a Unix time) would drop the milliseconds."""
    return f"{t_s:.9f}"


def format_row(row: Sequence[float]) -> list[str]:
    """One log row as text, its first value a time stamp [s]: the time to the nanosecond
    (:func:`format_time`), every other value to ten significant digits (``%.10g``)."""
    return [format_time(row[0]), *(f"{v:.10g}" for v in row[1:])]
