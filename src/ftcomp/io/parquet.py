"""Sample files in Parquet: the same columns as the sample CSV, typed, read in row batches.

A Parquet sample file has the columns of :mod:`ftcomp.io.sample_format` (``fx..tz``, one
orientation encoding, optional ``pose`` and ``t``, any others carried along); numeric columns
must have a number type (integers are read as floats), ``pose`` any type (read as text). Long
recordings are smaller and far faster to read in Parquet than in CSV.

:class:`ParquetSampleReader` streams checked blocks like
:class:`~ftcomp.io.samples_csv.SampleCsvReader`; :class:`ParquetBlockWriter` writes tables one
row group at a time into an open binary file (e.g. from :func:`ftcomp.io.chunks.atomic_output`).
Errors name the file, the row (1 = first row) and the column.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from types import TracebackType
from typing import Any, BinaryIO

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pcsv
import pyarrow.parquet as pq

from ftcomp.errors import InputFileError
from ftcomp.frames import ENCODING_COLUMNS
from ftcomp.io.chunks import line_ends
from ftcomp.io.sample_format import (
    OrientationCheck,
    SampleBlock,
    check_header,
    check_values,
    first_bad_value,
)

__all__ = ["BATCH_ROWS", "ParquetBlockWriter", "ParquetSampleReader"]

#: Rows read at a time (and written per row group).
BATCH_ROWS = 131_072


def _is_number(kind: pa.DataType) -> bool:
    return bool(
        pa.types.is_integer(kind) or pa.types.is_floating(kind) or pa.types.is_decimal(kind)
    )


class ParquetSampleReader:
    """A Parquet sample file read batch by batch (same interface as ``SampleCsvReader``).

    Args:
        path: the ``.parquet`` file.
        force_range_N, torque_range_Nm: a reading beyond +-these is an error.
        batch_rows: rows per block (default :data:`BATCH_ROWS`).
        with_text: give each block's input columns as CSV lines too (for CSV output).
        with_table: give each block's input columns as a pyarrow table.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        force_range_N: float | None = None,
        torque_range_Nm: float | None = None,
        batch_rows: int | None = None,
        with_text: bool = False,
        with_table: bool = False,
    ) -> None:
        self.source = source = str(path)
        self.rows = 0
        self._batch_rows = batch_rows or BATCH_ROWS
        self._with_text, self._with_table = with_text, with_table
        try:
            self._file = pq.ParquetFile(path)
        except FileNotFoundError:
            raise InputFileError(f"{source}: no such file") from None
        except IsADirectoryError:
            raise InputFileError(f"{source}: is a directory, expected a Parquet file") from None
        except (pa.ArrowException, OSError) as exc:
            raise InputFileError(f"{source}: not a readable Parquet file ({exc})") from None
        schema = self._file.schema_arrow
        self.layout = check_header(
            schema.names,
            source,
            where=f"{source}, columns",
            force_range_N=force_range_N,
            torque_range_Nm=torque_range_Nm,
        )
        for name in self.layout.numeric:
            kind = schema.field(name).type
            if not _is_number(kind):
                raise InputFileError(f"{source}, column {name!r}: type {kind} is not a number type")
        self._orientation = OrientationCheck(self.layout)

    @property
    def warnings(self) -> tuple[str, ...]:
        """What looked wrong but was accepted, over the blocks read so far."""
        return self._orientation.warnings

    def _no_nulls(self, column: Any, name: str, first_row: int) -> None:
        if column.null_count:
            row = first_row + int(
                np.flatnonzero(column.is_null().to_numpy(zero_copy_only=False))[0]
            )
            raise InputFileError(f"{self.source}, row {row}, column {name!r}: empty (null) cell")

    def blocks(self) -> Iterator[SampleBlock]:
        """Every block of rows, in file order.

        Raises:
            InputFileError: at the first problem (naming row and column), or no rows at all.
        """
        layout = self.layout
        k = 6 + len(ENCODING_COLUMNS[layout.encoding])
        for batch in self._file.iter_batches(batch_size=self._batch_rows):
            n, first_row = batch.num_rows, self.rows + 1
            if not n:
                continue
            values = np.empty((n, len(layout.numeric)))
            for j, name in enumerate(layout.numeric):
                column = batch.column(name)
                self._no_nulls(column, name, first_row)
                values[:, j] = column.cast(pa.float64()).to_numpy(zero_copy_only=False)
            if not check_values(values, layout):
                first_bad_value(values, layout, first_row)
            pose = None
            if layout.has_pose:
                ids = batch.column("pose")
                self._no_nulls(ids, "pose", first_row)
                ids = pc.utf8_trim_whitespace(ids.cast(pa.string()))
                empty = np.flatnonzero(pc.utf8_length(ids).to_numpy(zero_copy_only=False) == 0)
                if empty.size:
                    raise InputFileError(
                        f"{self.source}, row {first_row + int(empty[0])}, column 'pose': "
                        "empty pose id"
                    )
                pose = np.asarray(ids.to_numpy(zero_copy_only=False), dtype=str)
            self.rows += n
            table = pa.Table.from_batches([batch])
            text = _csv_lines(table) if self._with_text else None
            yield SampleBlock(
                first_row=first_row,
                wrench_sensor=np.ascontiguousarray(values[:, :6]),
                R_base_sensor=self._orientation.rotations(values[:, 6:k], first_row),
                t=values[:, k].copy() if layout.has_t else None,
                pose=pose,
                text=text,
                text_ends=line_ends(text) if text is not None else None,
                table=table if self._with_table else None,
            )
        if self.rows == 0:
            raise InputFileError(f"{self.source}: no data rows")

    def close(self) -> None:
        """Close the file."""
        self._file.close()

    def __enter__(self) -> ParquetSampleReader:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()


def _csv_lines(table: Any) -> bytes:
    """A table's rows as CSV lines (no header), each ending in ``\\n``."""
    sink = pa.BufferOutputStream()
    pcsv.write_csv(table, sink, write_options=pcsv.WriteOptions(include_header=False))
    return bytes(sink.getvalue().to_pybytes())


class ParquetBlockWriter:
    """Writes tables of one schema as row groups of one Parquet file into ``handle``.

    Use as a context manager: leaving it writes the file's footer (a file is complete only
    then). Compression: zstd.
    """

    def __init__(self, handle: BinaryIO) -> None:
        self._handle = handle
        self._writer: Any = None

    def write(self, table: Any) -> None:
        """Append ``table`` (the first one fixes the schema)."""
        if self._writer is None:
            self._writer = pq.ParquetWriter(self._handle, table.schema, compression="zstd")
        self._writer.write_table(table)

    def __enter__(self) -> ParquetBlockWriter:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        if self._writer is not None:
            self._writer.close()
