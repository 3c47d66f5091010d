"""The sample CSV: F/T readings with the sensor's orientation, one row per reading.

Format: a header row and comma-delimited UTF-8 rows with the columns of
:mod:`ftcomp.io.sample_format` (the wrench, one orientation encoding, optional ``pose`` and
``t``; any other column is carried along). The rules and the messages are in that module,
shared with Parquet; this one reads and writes the CSV form.

**Reading.** Files of any length are read in chunks of whole lines (:mod:`ftcomp.io.chunks`)
with bounded memory. Each chunk is parsed by pyarrow's multi-threaded CSV parser into numpy
arrays and checked as a block; only a chunk that fails is parsed again cell by cell
(:func:`parse_rows`) to name the first bad cell: every problem is one
:class:`~ftcomp.errors.InputFileError` naming the file, the data row (1 = first row after the
header), the line and the column. :func:`read_samples` returns every row at once;
:func:`open_samples` streams blocks. Both also read ``.parquet`` sample files
(:mod:`ftcomp.io.parquet`), chosen by the file name, so a caller need not care which it got.

**Writing.** :func:`write_samples` writes readings atomically, values to ten significant digits
and time stamps to the nanosecond (:mod:`ftcomp.io.timestamps`).
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ftcomp.errors import InputFileError, ParameterError
from ftcomp.frames import ENCODING_COLUMNS, OrientationEncoding, encode_orientation
from ftcomp.io.chunks import (
    DEFAULT_CHUNK_BYTES,
    CsvRows,
    LineChunk,
    csv_rows,
    drop_blank_lines,
    iter_line_chunks,
    line_ends,
    open_text,
    read_first_line,
)
from ftcomp.io.sample_format import (
    OrientationCheck,
    SampleBlock,
    SampleLayout,
    check_header,
    check_row_limits,
    check_values,
    parse_number,
)
from ftcomp.io.tables import write_table
from ftcomp.io.timestamps import format_time
from ftcomp.samples import WRENCH_COLUMNS, Samples

if TYPE_CHECKING:
    from ftcomp.io.parquet import ParquetSampleReader

__all__ = [
    "ParsedRows",
    "SampleCsvReader",
    "open_samples",
    "parse_rows",
    "read_samples",
    "write_samples",
]

_ARROW_BLOCK_BYTES = 1 << 20  # pyarrow parses blocks of this size in parallel
_EXACT_LINES = 256  # a failing piece this small is parsed cell by cell to find the bad cell


def _fast_parse(
    text: bytes, rows: int, layout: SampleLayout, with_table: bool
) -> tuple[NDArray[np.float64], NDArray[np.str_] | None, Any] | None:
    """Parse ``rows`` whole non-blank CSV lines ``text`` with pyarrow; None if any row needs a
    closer look."""
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.csv as pcsv

    names = [f"c{i}" for i in range(len(layout.header))]
    index = layout.index
    numeric = {names[index[c]] for c in layout.numeric}
    wanted = [
        n
        for n in names
        if with_table or n in numeric or (layout.has_pose and n == names[index["pose"]])
    ]
    try:
        table = pcsv.read_csv(
            pa.BufferReader(text),
            read_options=pcsv.ReadOptions(column_names=names, block_size=_ARROW_BLOCK_BYTES),
            parse_options=pcsv.ParseOptions(newlines_in_values=False),
            convert_options=pcsv.ConvertOptions(
                column_types={n: pa.float64() if n in numeric else pa.string() for n in wanted},
                include_columns=wanted,
                null_values=[],
                strings_can_be_null=False,
                quoted_strings_can_be_null=False,
                check_utf8=False,
            ),
        )
    except (pa.ArrowException, ValueError):
        return None
    if table.num_rows != rows:
        return None
    values = np.empty((table.num_rows, len(layout.numeric)))
    for j, name in enumerate(layout.numeric):
        values[:, j] = table.column(names[index[name]]).to_numpy()
    if not check_values(values, layout):
        return None
    pose = None
    if layout.has_pose:
        ids = pc.utf8_trim_whitespace(table.column(names[index["pose"]]))
        if pc.min(pc.utf8_length(ids)).as_py() == 0:
            return None
        pose = np.asarray(ids.to_numpy(), dtype=str)
    return values, pose, table.rename_columns(list(layout.header)) if with_table else None


@dataclass(frozen=True)
class ParsedRows:
    """Rows parsed cell by cell: ``values`` (N, len(layout.numeric)), ``pose`` ids (or None),
    ``cells`` of every row as read, and ``text``: the rows as CSV lines ending in ``\\n``."""

    values: NDArray[np.float64]
    pose: list[str] | None
    cells: list[list[str]]
    text: bytes

    def table(self, layout: SampleLayout) -> Any:
        """Every column as a pyarrow table: the numeric ones as float64, the others as text."""
        import pyarrow as pa

        numeric = {name: j for j, name in enumerate(layout.numeric)}
        columns = [
            pa.array(self.values[:, numeric[name]])
            if name in numeric
            else pa.array([r[i] for r in self.cells], pa.string())
            for i, name in enumerate(layout.header)
        ]
        return pa.table(columns, names=list(layout.header))


def parse_rows(text: str, layout: SampleLayout, *, first_row: int, first_line: int) -> ParsedRows:
    """Parse CSV data rows one cell at a time, checking every rule; blank rows are skipped.

    Args:
        text: the rows (after the header).
        layout: the checked header.
        first_row: the data-row number of the first row (1 = first after the header).
        first_line: the physical line number of the text's first line.

    Raises:
        InputFileError: naming file, row, line and column of the first problem.
    """
    source, index = layout.source, layout.index
    numeric = [index[c] for c in layout.numeric]
    reader = csv.reader(io.StringIO(text))
    values: list[list[float]] = []
    poses: list[str] = []
    kept: list[list[str]] = []
    for cells in csv_rows(reader, lambda: f"{source}, row {first_row + len(kept)}", first_line):
        if not cells or all(not c.strip() for c in cells):
            continue
        where = f"{source}, row {first_row + len(kept)} (line {first_line - 1 + reader.line_num})"
        if len(cells) != len(layout.header):
            raise InputFileError(
                f"{where}: {len(cells)} cells but the header has {len(layout.header)} columns"
            )
        parsed = [
            parse_number(cells[i], f"{where}, column {name!r}")
            for i, name in zip(numeric, layout.numeric, strict=True)
        ]
        if layout.has_pose:
            pose_id = cells[index["pose"]].strip()
            if not pose_id:
                raise InputFileError(f"{where}, column 'pose': empty pose id")
            poses.append(pose_id)
        check_row_limits(parsed, layout, where)
        kept.append(cells)
        values.append(parsed)
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerows(kept)
    return ParsedRows(
        np.array(values, dtype=float).reshape(-1, len(layout.numeric)),
        poses if layout.has_pose else None,
        kept,
        out.getvalue().encode("utf-8"),
    )


@dataclass(frozen=True)
class _Rows:
    """Parsed rows: values (N, len(layout.numeric)), pose ids, table, text and its line ends."""

    values: NDArray[np.float64]
    pose: NDArray[np.str_] | None
    table: Any
    text: bytes
    ends: NDArray[np.intp]

    def then(self, other: _Rows) -> _Rows:
        """These rows followed by ``other``."""
        import pyarrow as pa

        return _Rows(
            np.concatenate([self.values, other.values]),
            None
            if self.pose is None or other.pose is None
            else np.concatenate([self.pose, other.pose]),
            None if self.table is None else pa.concat_tables([self.table, other.table]),
            self.text + other.text,
            np.concatenate([self.ends, other.ends + len(self.text)]),
        )


class SampleCsvReader:
    """A sample CSV read block by block, with bounded memory.

    The header is read and checked on opening; :meth:`blocks` yields checked
    :class:`~ftcomp.io.sample_format.SampleBlock` s. Use as a context manager.

    Args:
        path: the CSV file.
        force_range_N, torque_range_Nm: a reading beyond +-these is an error (saturation).
        chunk_bytes: bytes read at a time (default :data:`DEFAULT_CHUNK_BYTES`).
        with_text: keep each block's rows as CSV text (for writing them back out).
        with_table: also give each block's columns as a pyarrow table (for Parquet output).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        force_range_N: float | None = None,
        torque_range_Nm: float | None = None,
        chunk_bytes: int | None = None,
        with_text: bool = True,
        with_table: bool = False,
    ) -> None:
        self.source = str(path)
        self.rows = 0
        self._chunk_bytes = chunk_bytes or DEFAULT_CHUNK_BYTES
        self._with_text, self._with_table = with_text, with_table
        self._handle = open_text(path)
        try:
            where = f"{self.source}, header (line 1)"
            first = csv.reader([read_first_line(self._handle, self.source)])
            header = next(csv_rows(first, lambda: where, 1), [])
            if not any(cell.strip() for cell in header):
                expected = f"{','.join(WRENCH_COLUMNS)} and one orientation encoding"
                if self._rest_is_blank():
                    raise InputFileError(
                        f"{self.source}: empty file; expected a header with {expected}"
                    )
                raise InputFileError(
                    f"{where}: blank; the header ({expected}) must be the first line"
                )
            self.layout = check_header(
                header,
                self.source,
                where=where,
                force_range_N=force_range_N,
                torque_range_Nm=torque_range_Nm,
            )
        except BaseException:
            self._handle.close()
            raise
        self._orientation = OrientationCheck(self.layout)

    def _rest_is_blank(self) -> bool:
        return all(not c.data.strip() for c in iter_line_chunks(self._handle, self.source))

    @property
    def warnings(self) -> tuple[str, ...]:
        """What looked wrong but was accepted, over the blocks read so far."""
        return self._orientation.warnings

    def blocks(self) -> Iterator[SampleBlock]:
        """Every block of rows, in file order.

        Raises:
            InputFileError: at the first problem (naming row, line and column), or when the
                file has a header but no data rows.
        """
        for chunk in iter_line_chunks(
            self._handle, self.source, chunk_bytes=self._chunk_bytes, first_line=2
        ):
            block = self._block(chunk)
            if block is not None:
                yield block
        if self.rows == 0:
            raise InputFileError(f"{self.source}: a header but no data rows")

    def _parse(self, data: bytes, ends: NDArray[np.intp], first_row: int, first_line: int) -> _Rows:
        """Parse whole lines ``data`` (newlines at ``ends``): by pyarrow, or, where it fails, by
        halving until the failing piece is small enough to parse cell by cell cheaply."""
        layout = self.layout
        text, kept = drop_blank_lines(data, ends)
        parsed = _fast_parse(text, len(kept), layout, self._with_table) if text else None
        if parsed is not None:
            return _Rows(*parsed, text, kept)
        if len(ends) <= _EXACT_LINES or b'"' in data:  # quotes: a cell may span lines
            exact = parse_rows(
                data.decode("utf-8"), layout, first_row=first_row, first_line=first_line
            )
            return _Rows(
                exact.values,
                np.array(exact.pose, dtype=str) if exact.pose is not None else None,
                exact.table(layout) if self._with_table else None,
                exact.text,
                line_ends(exact.text),
            )
        half = len(ends) // 2
        cut = int(ends[half - 1]) + 1
        head = self._parse(data[:cut], ends[:half], first_row, first_line)
        tail = self._parse(
            data[cut:], ends[half:] - cut, first_row + len(head.values), first_line + half
        )
        return head.then(tail)

    def _block(self, chunk: LineChunk) -> SampleBlock | None:
        rows = self._parse(chunk.data, chunk.ends, self.rows + 1, chunk.first_line)
        if not len(rows.values):
            return None
        first_row = self.rows + 1
        self.rows += len(rows.values)
        k = 6 + len(ENCODING_COLUMNS[self.layout.encoding])
        return SampleBlock(
            first_row=first_row,
            wrench_sensor=np.ascontiguousarray(rows.values[:, :6]),
            R_base_sensor=self._orientation.rotations(rows.values[:, 6:k], first_row),
            t=rows.values[:, k].copy() if self.layout.has_t else None,
            pose=rows.pose,
            text=rows.text if self._with_text else None,
            text_ends=rows.ends if self._with_text else None,
            table=rows.table,
            byte_range=(chunk.start, chunk.stop),
        )

    def close(self) -> None:
        """Close the file."""
        self._handle.close()

    def __enter__(self) -> SampleCsvReader:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()


def open_samples(
    path: str | os.PathLike[str],
    *,
    force_range_N: float | None = None,
    torque_range_Nm: float | None = None,
    with_text: bool = True,
    with_table: bool = False,
) -> SampleCsvReader | ParquetSampleReader:
    """A block reader for a sample file: Parquet if the name ends in ``.parquet``, else CSV."""
    if Path(path).suffix.lower() == ".parquet":
        from ftcomp.io.parquet import ParquetSampleReader

        return ParquetSampleReader(
            path,
            force_range_N=force_range_N,
            torque_range_Nm=torque_range_Nm,
            with_text=with_text,
            with_table=with_table,
        )
    return SampleCsvReader(
        path,
        force_range_N=force_range_N,
        torque_range_Nm=torque_range_Nm,
        with_text=with_text,
        with_table=with_table,
    )


def read_samples(
    path: str | os.PathLike[str],
    *,
    force_range_N: float | None = None,
    torque_range_Nm: float | None = None,
) -> Samples:
    """Read and check a sample file (CSV, or Parquet when the name ends in ``.parquet``).

    Args:
        path: the file.
        force_range_N: if given, a force reading beyond +-this [N] is an error (saturated sensor).
        torque_range_Nm: if given, a torque reading beyond +-this [N*m] is an error.

    Raises:
        InputFileError: naming file, row, line and column of the first problem found.
    """
    with open_samples(
        path, force_range_N=force_range_N, torque_range_Nm=torque_range_Nm, with_text=False
    ) as reader:
        blocks = list(reader.blocks())
        layout, warnings = reader.layout, reader.warnings
    rows: Sequence[tuple[str, ...]] = ()
    if isinstance(reader, SampleCsvReader):
        spans = [(*b.byte_range, b.first_row - 1, len(b)) for b in blocks if b.byte_range]
        rows = CsvRows(reader.source, spans)
    pose = [b.pose for b in blocks if b.pose is not None]
    t = [b.t for b in blocks if b.t is not None]
    return Samples(
        wrench_sensor=np.concatenate([b.wrench_sensor for b in blocks]),
        R_base_sensor=np.concatenate([b.R_base_sensor for b in blocks]),
        encoding=layout.encoding,
        pose=np.concatenate(pose) if layout.has_pose else None,
        t=np.concatenate(t) if layout.has_t else None,
        header=layout.header,
        rows=rows,
        source=reader.source,
        warnings=warnings,
    )


def _fmt(value: float) -> str:
    return f"{value:.10g}"


def write_samples(
    path: str | os.PathLike[str],
    wrench_sensor: ArrayLike,
    rotations: Rotation,
    *,
    encoding: OrientationEncoding,
    pose: ArrayLike | None = None,
    t: ArrayLike | None = None,
    extras: Mapping[str, ArrayLike] | None = None,
) -> None:
    """Write readings as a sample CSV, atomically.

    Args:
        path: output file (replaced if it exists: callers decide whether that is allowed).
        wrench_sensor: [N, N*m], sensor frame, shape (N, 6).
        rotations: ``R_base_sensor`` of each row (N rotations).
        encoding: the orientation encoding to write.
        pose: optional pose id per row, shape (N,).
        t: optional time stamp per row [s], shape (N,).
        extras: a sensor's extra channels (name with its unit -> one value per row, (N,)), the
            last columns, in the mapping's order (:attr:`~ftcomp.samples.Samples.extras`).
    """
    wrench = np.asarray(wrench_sensor, dtype=float).reshape(-1, 6)
    orient = encode_orientation(rotations, encoding).reshape(len(wrench), -1)
    header: list[str] = []
    columns: list[list[str]] = []
    if pose is not None:
        header.append("pose")
        columns.append([str(p) for p in np.asarray(pose).ravel()])
    if t is not None:
        header.append("t")
        columns.append([format_time(v) for v in np.asarray(t, dtype=float).ravel()])
    header.extend(ENCODING_COLUMNS[encoding])
    columns.extend([_fmt(v) for v in orient[:, j]] for j in range(orient.shape[1]))
    header.extend(WRENCH_COLUMNS)
    columns.extend([_fmt(v) for v in wrench[:, j]] for j in range(6))
    for name, values in (extras or {}).items():
        if name in header:
            raise ParameterError(f"write_samples: extra channel {name!r} is a sample column")
        header.append(name)
        columns.append([_fmt(v) for v in np.asarray(values, dtype=float).ravel()])
    if any(len(col) != len(wrench) for col in columns):
        raise ParameterError(
            "write_samples: pose, t, rotations and extras must have one entry per row"
        )
    write_table(path, header, list(zip(*columns, strict=True)))
