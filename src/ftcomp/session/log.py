"""A live session's CSV log: one header, one row per call, written atomically.

A live loop cannot hold its rows until the end (a run may last hours), nor leave half a file when
it is stopped: :class:`CsvLog` streams rows into a temporary file beside the target and renames
it into place when the session ends, whatever ended it (a fault, Ctrl-C): what was logged is
kept. The first column is a time stamp [s] written to the nanosecond; the others to
``digits`` significant digits (17: every float exactly, so a log replays bit for bit).

A :class:`LogObserver` sees the same rows as they are written (an MCAP log, a live view): the
session hands it every row with the row's stamp in integer nanoseconds on the session's clock,
and events (a pose recorded, a grasp, the end and why). :class:`ObserverThread` runs observers
off the control thread: the loop only puts the row on a queue, a worker thread serialises and
publishes it, so a slow observer costs the loop no period. One thing still joins the two
threads: the interpreter's lock. A worker busy in Python code (an MCAP chunk being indexed)
gives it up only every :func:`sys.getswitchinterval` (5 ms by default, longer than a 500 Hz
period), so while observers run the interval is lowered to :data:`SWITCH_INTERVAL_S`, and
restored when they close.
"""

from __future__ import annotations

import contextlib
import csv
import io
import os
import queue
import sys
import threading
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import BinaryIO, Protocol, runtime_checkable

from ftcomp.errors import ParameterError
from ftcomp.hardware.pacing import TimingSummary
from ftcomp.io.atomic import atomic_output, atomic_write_text
from ftcomp.io.timestamps import format_time

__all__ = [
    "SWITCH_INTERVAL_S",
    "CsvLog",
    "LogObserver",
    "ObserverThread",
    "csv_log",
    "save_timing",
    "timing_path",
]

#: The interpreter's thread switch interval while observers run [s]: about the longest the
#: control loop waits for the interpreter's lock when an observer is busy (a quarter of a
#: 500 Hz period, against 5 ms by default; shorter makes the two threads trade the lock so
#: often that the loop's own cycle grows, bench/bench_view.py).
SWITCH_INTERVAL_S = 5e-4


@runtime_checkable
class LogObserver(Protocol):
    """Sees a live session's log rows and events as they happen (an MCAP log, a live view).

    ``open`` comes first with the log's columns, then ``row`` and ``event`` calls in the order
    of the session, then ``close`` (also when a fault or Ctrl-C ended the session).
    """

    def open(self, columns: Sequence[str]) -> None:
        """The log's columns (the rows' layout)."""

    def row(self, t_ns: int, row: Sequence[float]) -> None:
        """One log row as written, and its stamp [ns] on the session's clock."""

    def event(self, t_ns: int, kind: str, text: str) -> None:
        """Something happened at ``t_ns`` [ns]: ``kind`` (``"pose"``, ``"grasp"``,
        ``"release"``, ``"contact"``, ``"end"``, ``"fault"``) and one line saying what."""

    def close(self) -> None:
        """The session ended: finish (idempotent)."""


class ObserverThread:
    """Runs observers on a worker thread: the caller's ``row`` only queues (a LogObserver).

    The rows and events reach the observers in order; :meth:`close` waits until they have all
    been handed on, closes the observers and raises the first error an observer raised (the
    session itself goes on: a failing log is no reason to stop the arm). While it runs the
    interpreter's switch interval is at most :data:`SWITCH_INTERVAL_S` (module docstring).

    The queue is bounded: an observer slower than the loop (a view on a loaded machine) would
    otherwise grow it without end. Beyond ``max_queued_rows`` rows waiting, a new row is
    dropped (never an event) and counted in :attr:`dropped_rows`; the loop is never held up.

    Args:
        observers: the observers.
        max_queued_rows: rows that may wait (20000: 20 s at 1 kHz), >= 1.
    """

    def __init__(self, observers: Sequence[LogObserver], max_queued_rows: int = 20_000) -> None:
        if not (isinstance(max_queued_rows, int) and max_queued_rows >= 1):
            raise ParameterError(f"max_queued_rows must be an integer >= 1, got {max_queued_rows}")
        self.max_queued_rows = max_queued_rows
        #: Rows dropped because the queue was full.
        self.dropped_rows = 0
        self.observers = tuple(observers)
        self._switch_s = sys.getswitchinterval()
        sys.setswitchinterval(min(self._switch_s, SWITCH_INTERVAL_S))
        self._queue: queue.SimpleQueue[tuple[str, tuple[object, ...]] | None] = queue.SimpleQueue()
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._work, name="ftcomp-observers", daemon=True)
        self._thread.start()
        self._closed = False

    def _work(self) -> None:
        while True:
            item = self._queue.get()
            if item is None:
                return
            if self._error is not None:
                continue  # drain: an observer failed, the rest is dropped
            name, args = item
            try:
                for observer in self.observers:
                    getattr(observer, name)(*args)
            except BaseException as exc:  # handed to close(), raised on the caller's thread
                self._error = exc

    def open(self, columns: Sequence[str]) -> None:
        """Queue the columns."""
        self._queue.put(("open", (tuple(columns),)))

    def row(self, t_ns: int, row: Sequence[float]) -> None:
        """Queue one row (the caller must not change ``row`` afterwards); drop it when
        ``max_queued_rows`` are waiting."""
        if self._queue.qsize() >= self.max_queued_rows:
            self.dropped_rows += 1
            return
        self._queue.put(("row", (t_ns, row)))

    def event(self, t_ns: int, kind: str, text: str) -> None:
        """Queue an event."""
        self._queue.put(("event", (t_ns, kind, text)))

    def close(self) -> None:
        """Hand on what is queued, close the observers, raise an observer's error."""
        if self._closed:
            return
        self._closed = True
        self._queue.put(None)  # the end
        self._thread.join()
        sys.setswitchinterval(self._switch_s)
        errors: list[BaseException] = [] if self._error is None else [self._error]
        for observer in self.observers:
            try:
                observer.close()
            except BaseException as exc:
                errors.append(exc)
        if errors:
            raise errors[0]


class CsvLog:
    """Writes rows of ``columns`` (see :func:`csv_log`); ``rows`` counts them.

    A row is formatted, counted and kept in memory with no call between the count and the
    keeping, so a Ctrl-C (Python raises it only at a call or a loop's jump) lands before both or
    after both; kept bytes go to the file by unbuffered writes, each resynchronised from the
    file's offset, so a Ctrl-C inside one (or just after it returned) loses and repeats nothing.
    Python's buffered text file raised it from inside a row's write while handing a full buffer
    on, and dropped that row after it was counted (a stream stopped by Ctrl-C, 234 rows in a log
    that said 235).

    Args:
        handle: the file, open for unbuffered binary writing (``open(path, "wb", buffering=0)``).
        columns: the header.
        digits: significant digits of the numbers after the first column.
        observer: also sees every row (after it is kept).
    """

    #: Kept bytes are handed to the file once this many are waiting (and when the log ends).
    WRITE_BYTES = 1 << 16

    def __init__(
        self,
        handle: BinaryIO,
        columns: Sequence[str],
        digits: int,
        observer: LogObserver | None = None,
    ) -> None:
        header = io.StringIO()
        csv.writer(header, lineterminator="\n").writerow(columns)
        self._fd = handle.fileno()
        self._written = os.lseek(self._fd, 0, os.SEEK_CUR)
        self._kept = bytearray(header.getvalue().encode())
        self._format = f"{{:.{digits}g}}".format
        self.columns = tuple(columns)
        self.rows = 0
        self.observer = observer
        self._later: list[tuple[Sequence[float], int | None]] = []

    def write(self, row: Sequence[float], t_ns: int | None = None) -> None:
        """One row: its first value a time stamp [s], the others numbers; ``t_ns``: the row's
        exact stamp [ns] for the observer (default: the first value in nanoseconds)."""
        fmt = self._format
        line = ",".join([format_time(row[0]), *(fmt(v) for v in row[1:])]) + "\n"
        data = line.encode()
        # Counted, then kept, with no call between (the class docstring).
        self.rows += 1
        self._kept += data
        if self.observer is not None:
            self.observer.row(round(row[0] * 1e9) if t_ns is None else t_ns, row)
        if len(self._kept) >= self.WRITE_BYTES:
            self.write_kept()

    def write_kept(self) -> None:
        """Hand every kept byte to the file (the class docstring)."""
        while True:
            # what the file took of the kept bytes, a write cut short by Ctrl-C included
            took = os.lseek(self._fd, 0, os.SEEK_CUR) - self._written
            del self._kept[:took]
            self._written += took
            if not self._kept:
                return
            os.write(self._fd, self._kept)

    def write_later(self, row: Sequence[float], t_ns: int | None = None) -> None:
        """Keep a row (as :meth:`write` takes it) for the next :meth:`flush`: a control loop
        keeps the row's formatting (about 30 us for a run's 30 numbers, 0.1 ms at p99) off the
        command's path and flushes in its slack (``run_loop(in_slack=[log.flush])``)."""
        self._later.append((row, t_ns))

    def flush(self) -> None:
        """Write the rows kept by :meth:`write_later`, in order. A row leaves the list once it
        is kept for the file (:attr:`rows` counts it), so a flush cut short (Ctrl-C lands anywhere
        in the loop, its slack too) leaves the rest, the interrupted row included, for the
        next one: no row written twice, none lost."""
        later = self._later
        if later:
            done = 0
            try:
                for row, t_ns in later:
                    before = self.rows
                    try:
                        self.write(row, t_ns)
                    finally:
                        if self.rows != before:
                            done += 1
            finally:
                del later[:done]

    def event(self, t_ns: int, kind: str, text: str) -> None:
        """Tell the observer of an event (see :meth:`LogObserver.event`); no row is written."""
        if self.observer is not None:
            self.observer.event(t_ns, kind, text)

    @property
    def dropped_rows(self) -> int:
        """Rows the observers did not see (their queue was full, :class:`ObserverThread`)."""
        observer = self.observer
        return observer.dropped_rows if isinstance(observer, ObserverThread) else 0


def timing_path(log_path: Path) -> Path:
    """Where a session's timing block goes: beside its CSV log, ``run.csv`` ->
    ``run.timing.json`` (a block inside the CSV would break its readers)."""
    return log_path.with_name(log_path.stem + ".timing.json")


def save_timing(log_path: Path, timing: TimingSummary, *, log: CsvLog | None = None) -> Path:
    """Write a session's timing block (:meth:`TimingSummary.as_dict`, its one line, and with
    ``log`` the rows its observers dropped) beside its log (:func:`timing_path`, atomically);
    return the block's path."""
    import json

    path = timing_path(log_path)
    document: dict[str, object] = {
        "format": "ftcomp.timing/1",
        "log": log_path.name,
        "line": timing.line(),
    }
    document.update(timing.as_dict())
    if log is not None:
        document["observer_dropped_rows"] = log.dropped_rows
    atomic_write_text(path, json.dumps(document, indent=2, allow_nan=False, default=str) + "\n")
    return path


@contextlib.contextmanager
def csv_log(
    path: Path,
    columns: Sequence[str],
    *,
    digits: int = 10,
    observers: Sequence[LogObserver] = (),
) -> Iterator[CsvLog]:
    """Open ``path`` as a :class:`CsvLog`, renamed into place when the block ends; on an
    exception out of the block nothing replaces ``path`` (a session catches its loop's faults
    inside the block, so what it logged is kept). ``observers`` see every row too, on an
    :class:`ObserverThread` (opened here, closed when the block ends)."""
    thread = ObserverThread(observers) if observers else None
    try:
        with atomic_output(path) as tmp, tmp.open("wb", buffering=0) as handle:
            if thread is not None:
                thread.open(columns)
            log = CsvLog(handle, columns, digits, thread)
            try:
                yield log
            finally:
                log.flush()
                log.write_kept()
    finally:
        if thread is not None:
            thread.close()
