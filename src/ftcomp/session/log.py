"""A live session's CSV log: one header, one row per call, written atomically.

A live loop cannot hold its rows until the end (a run may last hours), nor leave half a file when
it is stopped: :class:`CsvLog` streams rows into a temporary file beside the target and renames
it into place when the session ends, whatever ended it (a fault, Ctrl-C): what was logged is
kept. The first column is a time stamp [s] written to the nanosecond; the others to
``digits`` significant digits (17: every float exactly, so a log replays bit for bit).
"""

from __future__ import annotations

import contextlib
import csv
from collections.abc import Iterator, Sequence
from pathlib import Path

from ftcomp.io.atomic import atomic_output
from ftcomp.io.timestamps import format_time

__all__ = ["CsvLog", "csv_log"]


class CsvLog:
    """Writes rows of ``columns`` (see :func:`csv_log`); ``rows`` counts them."""

    def __init__(self, handle: object, columns: Sequence[str], digits: int) -> None:
        self._writer = csv.writer(handle, lineterminator="\n")  # type: ignore[arg-type]
        self._writer.writerow(columns)
        self._format = f"{{:.{digits}g}}".format
        self.columns = tuple(columns)
        self.rows = 0

    def write(self, row: Sequence[float]) -> None:
        """One row: its first value a time stamp [s], the others numbers."""
        fmt = self._format
        self._writer.writerow([format_time(row[0]), *(fmt(v) for v in row[1:])])
        self.rows += 1


@contextlib.contextmanager
def csv_log(path: Path, columns: Sequence[str], *, digits: int = 10) -> Iterator[CsvLog]:
    """Open ``path`` as a :class:`CsvLog`, renamed into place when the block ends; on an
    exception out of the block nothing replaces ``path`` (a session catches its loop's faults
    inside the block, so what it logged is kept)."""
    with atomic_output(path) as tmp, tmp.open("w", encoding="utf-8", newline="") as handle:
        yield CsvLog(handle, columns, digits)
