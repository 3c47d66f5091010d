"""Text files in pieces: chunks of whole lines, so memory does not grow with the file.

A recording of an hour at 7 kHz is 25 million rows; :func:`iter_line_chunks` reads it a chunk of
whole lines at a time (written out again through :func:`ftcomp.io.atomic.atomic_output`), and
:class:`CsvRows` gives its rows' cells by reading the chunk that holds them again.

Chunks are normalised the way Python's text mode reads a file: ``\\r\\n`` and lone ``\\r`` become
``\\n``. Line numbers count physical lines, as :mod:`csv` does.
"""

from __future__ import annotations

import bisect
import csv
import io
import os
import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any, BinaryIO, NoReturn, overload

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import InputFileError

__all__ = [
    "DEFAULT_CHUNK_BYTES",
    "MAX_HEADER_BYTES",
    "MAX_LINE_BYTES",
    "CsvRows",
    "LineChunk",
    "csv_rows",
    "drop_blank_lines",
    "iter_line_chunks",
    "line_ends",
    "open_text",
    "read_first_line",
]

#: Bytes read at a time: large enough to amortise per-chunk work, small enough to keep a
#: chunk's parsed arrays well under 100 MB.
DEFAULT_CHUNK_BYTES = 8 << 20

#: The longest line read [bytes]; a longer one (or endless input without a line end, such as
#: ``/dev/zero``) is an error, so memory stays bounded. It also keeps every cell within the
#: :mod:`csv` module's field limit (131,072 characters).
MAX_LINE_BYTES = 128 << 10
#: The longest header line read [bytes]: room for about 100,000 short column names.
MAX_HEADER_BYTES = 1 << 20

_BOM = b"\xef\xbb\xbf"
_BLANK_LINES = re.compile(rb"\n\n+")


@dataclass(frozen=True)
class LineChunk:
    """Whole lines of a file.

    Attributes:
        data: the lines, newlines normalised to ``\\n``, ending in ``\\n``.
        ends: the position of every ``\\n`` in ``data`` (one per physical line).
        first_line: the physical line number of the chunk's first line (1 = the file's first).
        start: byte offset of the chunk in the file; ``stop``: one past its end.
    """

    data: bytes
    ends: NDArray[np.intp]
    first_line: int
    start: int
    stop: int


def line_ends(data: bytes) -> NDArray[np.intp]:
    """The positions of every ``\\n`` in ``data``."""
    return np.flatnonzero(np.frombuffer(data, dtype=np.uint8) == ord("\n"))


def open_text(path: str | os.PathLike[str], kind: str = "CSV") -> BinaryIO:
    """Open a file for chunked reading; errors name the file.

    Raises:
        InputFileError: missing, a directory, or unreadable.
    """
    source = str(path)
    try:
        return open(path, "rb")  # the caller closes it
    except FileNotFoundError:
        raise InputFileError(f"{source}: no such file") from None
    except IsADirectoryError:
        raise InputFileError(f"{source}: is a directory, expected a {kind} file") from None
    except OSError as exc:
        raise InputFileError(f"{source}: cannot read ({exc.strerror})") from None


def _normalise(data: bytes, source: str) -> bytes:
    if not data.isascii():
        try:
            data.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise InputFileError(f"{source}: not UTF-8 text ({exc.reason})") from None
    if b"\r" in data:
        data = data.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    return data


def iter_line_chunks(
    handle: BinaryIO,
    source: str,
    *,
    chunk_bytes: int = DEFAULT_CHUNK_BYTES,
    first_line: int = 1,
    max_line_bytes: int = MAX_LINE_BYTES,
) -> Iterator[LineChunk]:
    """Chunks of whole lines from ``handle``'s current position to the end.

    A chunk ends at a newline that is not inside a quoted field (the count of ``"`` before it
    is even), so a CSV record is never split. A leading UTF-8 byte-order mark is dropped.

    Raises:
        InputFileError: the text is not UTF-8, or a line is longer than ``max_line_bytes``.
    """
    position = handle.tell()
    pending = b""
    line = first_line
    at_start = position == 0
    while True:
        block = handle.read(chunk_bytes)
        data = pending + block
        if at_start and data.startswith(_BOM):
            data, position = data[len(_BOM) :], position + len(_BOM)
        at_start = False
        cut = _cut(data) if block else len(data)
        if not cut and block:
            if len(data) > max_line_bytes:
                _too_long(source, line, max_line_bytes)
            pending = data  # no complete record yet: read on
            continue
        text = _normalise(data[:cut], source)
        if text and not text.endswith(b"\n"):
            text += b"\n"
        if text:
            ends = line_ends(text)
            lengths = np.diff(ends, prepend=-1)
            if lengths.max() > max_line_bytes + 1:
                _too_long(
                    source, line + int(np.argmax(lengths > max_line_bytes + 1)), max_line_bytes
                )
            yield LineChunk(text, ends, line, position, position + cut)
            line += len(ends)
        position += cut
        pending = data[cut:]
        if not block:
            return


def _too_long(source: str, line: int, limit: int) -> NoReturn:
    raise InputFileError(
        f"{source}, line {line}: longer than {limit} bytes, the limit of a line (a sample "
        "row is a few hundred bytes): not a sample file"
    )


def _cut(data: bytes) -> int:
    """Where to end a chunk: after the last newline outside a quoted field (0: none)."""
    cut = data.rfind(b"\n") + 1
    if cut and b'"' in data and data.count(b'"', 0, cut) % 2:
        # A quoted field is open: end before the line of the last quote (which opened it),
        # unless the quotes are stray ones that never balance.
        before = data.rfind(b"\n", 0, data.rfind(b'"', 0, cut)) + 1
        if before and not data.count(b'"', 0, before) % 2:
            return before
    return cut


def read_first_line(handle: BinaryIO, source: str) -> str:
    """The first line of a file (without its line end or a byte-order mark), as text.

    Leaves ``handle`` at the start of the second line.

    Raises:
        InputFileError: the line is not UTF-8, or longer than :data:`MAX_HEADER_BYTES`.
    """
    start = handle.tell()
    raw = handle.readline(MAX_HEADER_BYTES + 2)
    cr = raw.find(b"\r")
    if (cr if cr >= 0 else len(raw.rstrip(b"\n"))) > MAX_HEADER_BYTES:
        raise InputFileError(
            f"{source}, header (line 1): longer than {MAX_HEADER_BYTES} bytes (no line end): "
            "not a sample file"
        )
    if cr >= 0 and raw[cr + 1 : cr + 2] != b"\n":  # lines end in a lone CR (old Mac files)
        handle.seek(start + cr + 1)
    raw = raw[:cr] if cr >= 0 else raw.rstrip(b"\n")
    if start == 0 and raw.startswith(_BOM):
        raw = raw[len(_BOM) :]
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputFileError(f"{source}: not UTF-8 text ({exc.reason})") from None


def drop_blank_lines(data: bytes, ends: NDArray[np.intp]) -> tuple[bytes, NDArray[np.intp]]:
    """``data`` (ending in ``\\n``, its newlines at ``ends``) without its empty lines, and the
    new line ends."""
    if not len(ends) or (ends[0] and not np.any(np.diff(ends) == 1)):
        return data, ends
    data = _BLANK_LINES.sub(b"\n", data)
    data = data[1:] if data.startswith(b"\n") else data
    return data, line_ends(data)


class CsvRows(Sequence[tuple[str, ...]]):
    """The cells of every data row of a sample CSV, read again from the file when asked for.

    :attr:`Samples.rows` of a file read by :func:`ftcomp.read_samples`: keeping millions of rows
    as Python strings would cost gigabytes, so only the place of each chunk in the file is kept,
    and a chunk is parsed again (by :mod:`csv`, blank rows skipped) when one of its rows is
    asked for.

    Raises:
        InputFileError: on access, when the file has changed since it was read.
    """

    def __init__(self, path: str, spans: Sequence[tuple[int, int, int, int]]) -> None:
        self._path = path
        self._spans = list(spans)  # (byte start, byte stop, first row index, row count)
        self._firsts = [s[2] for s in self._spans]
        self._len = sum(s[3] for s in self._spans)
        self._stat = self._fingerprint()
        self._cached: tuple[int, list[tuple[str, ...]]] | None = None

    def _fingerprint(self) -> tuple[int, int]:
        try:
            stat = os.stat(self._path)
        except OSError as exc:
            raise InputFileError(
                f"{self._path}: cannot read its rows again ({exc.strerror})"
            ) from None
        return stat.st_size, stat.st_mtime_ns

    def _span_rows(self, k: int) -> list[tuple[str, ...]]:
        if self._cached is not None and self._cached[0] == k:
            return self._cached[1]
        if self._fingerprint() != self._stat:
            raise InputFileError(f"{self._path}: changed since it was read; read it again")
        start, stop, _, _ = self._spans[k]
        with open(self._path, "rb") as handle:
            handle.seek(start)
            data = handle.read(stop - start)
        text = data.decode("utf-8").replace("\r\n", "\n").replace("\r", "\n")
        where = f"{self._path}, bytes {start}-{stop}"
        rows = [
            tuple(cells)
            for cells in csv_rows(csv.reader(io.StringIO(text)), lambda: where, 1)
            if cells and any(c.strip() for c in cells)
        ]
        self._cached = (k, rows)
        return rows

    def __len__(self) -> int:
        return self._len

    def __iter__(self) -> Iterator[tuple[str, ...]]:
        for k in range(len(self._spans)):
            yield from self._span_rows(k)

    @overload
    def __getitem__(self, i: int) -> tuple[str, ...]: ...
    @overload
    def __getitem__(self, i: slice) -> list[tuple[str, ...]]: ...
    def __getitem__(self, i: int | slice) -> tuple[str, ...] | list[tuple[str, ...]]:
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(self._len))]
        if i < 0:
            i += self._len
        if not 0 <= i < self._len:
            raise IndexError(f"row index {i} out of range ({self._len} rows)")
        k = bisect.bisect_right(self._firsts, i) - 1
        return self._span_rows(k)[i - self._spans[k][2]]


def csv_rows(reader: Any, where: Callable[[], str], first_line: int) -> Iterator[list[str]]:
    """The rows of a :func:`csv.reader` over text whose first line is ``first_line``; a
    :class:`csv.Error` (a cell beyond the field limit, a NUL byte) becomes an
    :class:`InputFileError` naming ``where()`` (the row) and the line."""
    while True:
        try:
            cells = next(reader)
        except StopIteration:
            return
        except csv.Error as exc:
            line = first_line - 1 + reader.line_num
            raise InputFileError(f"{where()} (line {line}): not a CSV row ({exc})") from None
        yield cells
