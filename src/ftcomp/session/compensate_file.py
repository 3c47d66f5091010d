"""Compensate a whole sample file: bias and tool gravity removed from every reading.

:func:`compensate_file` streams: the samples are read, compensated and written one block of rows
at a time (the next block read ahead in a worker thread, :func:`~ftcomp.session.read_ahead.
read_ahead`), so memory does not grow with the file (an hour at 7 kHz, 25 M rows, runs in a few
hundred MB). Input and output are CSV or Parquet by their extension. A CSV output repeats each
input line as it was and appends the contact wrench and load weight as ``% .9e`` (ten
significant digits); a Parquet output has the input columns and the extra columns
(:data:`EXTRA_COLUMNS`) as float64. The output appears only when every row has been written (a
temporary file renamed into place): an error leaves no file.
"""

from __future__ import annotations

import csv
import io
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO, Final

import numpy as np
from numpy.typing import NDArray

from ftcomp.arrays import freeze_field
from ftcomp.calibration_record import Calibration, TemperatureBiasDrift
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.config_fields import check_fields, param
from ftcomp.errors import InputFileError, ParameterError
from ftcomp.hardware.protocols import IMU_CHANNELS, TEMPERATURE_CHANNEL
from ftcomp.io.atomic import atomic_output, check_writable
from ftcomp.io.calibration_json import load_calibration
from ftcomp.io.numtext import format_rows
from ftcomp.io.sample_format import SampleBlock
from ftcomp.io.samples_csv import SampleCsvReader
from ftcomp.session.read_ahead import read_ahead

if TYPE_CHECKING:
    from ftcomp.io.parquet import ParquetSampleReader

__all__ = ["EXTRA_COLUMNS", "CompensateConfig", "CompensateResult", "compensate_file"]

#: Columns added to the input: the contact wrench (Eq. 22) and the load weight (Eq. 23).
EXTRA_COLUMNS = ("fx_ext", "fy_ext", "fz_ext", "tx_ext", "ty_ext", "tz_ext", "load_weight_N")

PathLike = str | os.PathLike[str]


@dataclass(frozen=True)
class CompensateConfig:
    """How to read and write.

    Attributes:
        force_range_N: the sensor's force range [N]: a reading beyond +-this is an error (a
            saturated sensor); None: no check.
        torque_range_Nm: same for the torques [N*m].
        overwrite: whether an existing output may be replaced (never the input).
        csv_chunk_bytes: bytes of a CSV input read per block (None: the reader's default).
        parquet_batch_rows: rows of a Parquet input read per block (None: the reader's default).
        accelerometer: take the tool's acceleration from the rows' accelerometer columns
            (``accel_x_m_s2``.., an IMU's in the sensor: the tool's weight under the apparent
            gravity they read, :class:`~ftcomp.compensation.compensator.GravityCompensator`).
    """

    force_range_N: float | None = param(
        None, gt=0.0, optional=True, unit="N", help="the sensor's force range per axis"
    )
    torque_range_Nm: float | None = param(
        None, gt=0.0, optional=True, unit="N*m", help="the sensor's torque range per axis"
    )
    overwrite: bool = False
    csv_chunk_bytes: int | None = param(
        None, gt=0, integer=True, optional=True, help="bytes of a CSV input read per block"
    )
    parquet_batch_rows: int | None = param(
        None, gt=0, integer=True, optional=True, help="rows of a Parquet input read per block"
    )
    accelerometer: bool = False

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class CompensateResult:
    """What was written.

    Attributes:
        output: the file written.
        rows: rows compensated.
        duration_s: wall-clock time of the whole run [s].
        load_weight_mean_N: mean load weight ``|F_contact|`` over all rows [N] (NaN without rows).
        load_weight_max_N: its largest value [N] (NaN without rows).
        contact_wrench_mean_sensor: mean contact wrench [N, N*m], sensor frame, (6,).
        t_range_s: first and last time stamp [s] when the calibration's bias drift was applied
            from them; None otherwise.
        temperature_range_C: the lowest and highest temperature [degC] when the calibration's
            bias was applied from the rows' ``temperature_C``; None otherwise.
        warnings: things that look wrong but were accepted (the input's, and rows beyond
            the bias drift's calibrated time range, where it is held, not extrapolated).
    """

    output: Path
    rows: int
    duration_s: float
    load_weight_mean_N: float
    load_weight_max_N: float
    contact_wrench_mean_sensor: NDArray[np.float64] = field(repr=False)
    t_range_s: tuple[float, float] | None = None
    warnings: tuple[str, ...] = ()
    temperature_range_C: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.rows, int) and self.rows >= 0):
            raise ParameterError(f"rows must be an integer >= 0, got {self.rows!r}")
        if not self.duration_s >= 0.0:
            raise ParameterError(f"duration_s must be >= 0, got {self.duration_s}")
        freeze_field(self, "contact_wrench_mean_sensor", (6,))


@dataclass
class _Totals:
    """Running sums over the blocks, for the result."""

    rows: int = 0
    weight_sum: float = 0.0
    weight_max: float = -np.inf
    contact_sum: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    t_min: float = np.inf
    t_max: float = -np.inf
    T_min: float = np.inf
    T_max: float = -np.inf

    def add(self, contact: NDArray[np.float64], weight: NDArray[np.float64]) -> None:
        self.rows += len(weight)
        self.weight_sum += float(weight.sum())
        self.weight_max = max(self.weight_max, float(weight.max()))
        self.contact_sum += contact.sum(axis=0)


def _extra(
    block: SampleBlock,
    compensator: GravityCompensator,
    totals: _Totals,
    source: str,
    accelerometer: bool,
) -> NDArray[np.float64]:
    """The block's contact wrench and load weight, shape (N, 7) (``accelerometer``: the tool's
    acceleration from the block's accelerometer columns)."""
    extra = np.empty((len(block), 7))
    t_s = block.t if compensator.time_drift is not None else None
    if t_s is not None and len(t_s):
        totals.t_min = min(totals.t_min, float(t_s.min()))
        totals.t_max = max(totals.t_max, float(t_s.max()))
    temperature = (
        _finite_column(block, TEMPERATURE_CHANNEL, source, _TEMPERATURE_IS)
        if compensator.needs_temperature
        else None
    )
    if temperature is not None and len(temperature):
        totals.T_min = min(totals.T_min, float(temperature.min()))
        totals.T_max = max(totals.T_max, float(temperature.max()))
    specific_force = (
        np.column_stack([_finite_column(block, c, source, _ACCELERATION_IS) for c in _ACCEL])
        if accelerometer
        else None
    )
    contact = compensator.compensate(
        block.wrench_sensor,
        block.R_base_sensor,
        t_s=t_s,
        temperature_C=temperature,
        specific_force_mps2=specific_force,
    )
    extra[:, :6] = contact
    np.sqrt(np.einsum("ij,ij->i", contact[:, :3], contact[:, :3]), out=extra[:, 6])
    totals.add(contact, extra[:, 6])
    return extra


#: The accelerometer's columns, x y z [m/s^2].
_ACCEL: Final = IMU_CHANNELS[:3]
#: What each of these columns' cells must be, for the message of one that is not.
_TEMPERATURE_IS: Final = (
    "a finite temperature [degC] (the calibration's bias follows the sensor's temperature)"
)
_ACCELERATION_IS: Final = "a finite acceleration [m/s^2] (accelerometer)"


def _finite_column(block: SampleBlock, name: str, source: str, what: str) -> NDArray[np.float64]:
    """The block's column ``name``, (N,), each a finite number (else an InputFileError naming
    the row and saying it is not ``what``)."""
    import pyarrow as pa

    column = block.table.column(name)
    try:
        values = np.asarray(column.cast(pa.float64()).to_numpy(zero_copy_only=False), float)
    except (pa.ArrowException, ValueError):
        values = np.array([_number(cell) for cell in column.to_pylist()])
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        k = int(bad[0])
        raise InputFileError(
            f"{source}, row {block.first_row + k}, column {name!r}: {column[k].as_py()!r} "
            f"is not {what}"
        )
    return values


def _number(cell: object) -> float:
    """A cell as a float, NaN when it is not a number."""
    try:
        return float(cell)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return math.nan


def _csv_block(handle: BinaryIO, block: SampleBlock, extra: NDArray[np.float64]) -> None:
    """Write each line of the block's text with its ``extra`` row appended."""
    import pyarrow as pa
    import pyarrow.compute as pc

    text, ends, n = block.text, block.text_ends, len(extra)
    if text is None or ends is None:
        raise RuntimeError("compensate: the samples were read without their text")
    if len(ends) != n:  # a quoted cell spans lines: join row by row
        rows = list(csv.reader(io.StringIO(text.decode("utf-8"))))
        data, offsets = format_rows(extra)
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="")
        for i, row in enumerate(rows):
            writer.writerow(row)
            out.write(bytes(data[offsets[i] : offsets[i + 1]]).decode("ascii") + "\n")
        handle.write(out.getvalue().encode("utf-8"))
        return
    # Line i is text[ends[i-1]:ends[i]], i.e. "\n" + its cells (the first has no "\n"): joined
    # with its extra cells, the whole block is one buffer; it only lacks the final "\n".
    lines = pa.LargeStringArray.from_buffers(
        n, pa.py_buffer(np.concatenate([[0], ends]).astype(np.int64)), pa.py_buffer(text)
    )
    data, offsets = format_rows(extra)
    cells = pa.LargeStringArray.from_buffers(n, pa.py_buffer(offsets), pa.py_buffer(data))
    joined = pc.binary_join_element_wise(lines, cells, pa.scalar("", pa.large_string()))
    bounds = np.frombuffer(joined.buffers()[1], dtype=np.int64)[joined.offset :][[0, n]]
    handle.write(memoryview(joined.buffers()[2])[bounds[0] : bounds[1]])
    handle.write(b"\n")


def _write(
    reader: SampleCsvReader | ParquetSampleReader,
    compensator: GravityCompensator,
    output: Path,
    to_parquet: bool,
    progress: Callable[[int], None],
    accelerometer: bool,
) -> _Totals:
    """Compensate every block of ``reader`` into ``output``, atomically; ``progress`` is told
    how far the input has been read after each block (bytes of a CSV, rows of Parquet)."""
    totals = _Totals()
    with atomic_output(output) as tmp, tmp.open("wb") as handle:
        if to_parquet:
            import pyarrow as pa

            from ftcomp.io.parquet import ParquetBlockWriter

            with ParquetBlockWriter(handle) as writer:
                for block in read_ahead(reader.blocks()):
                    extra = _extra(block, compensator, totals, reader.source, accelerometer)
                    table = block.table
                    for j, name in enumerate(EXTRA_COLUMNS):
                        table = table.append_column(name, pa.array(extra[:, j]))
                    writer.write(table)
                    progress(totals.rows)
        else:
            header = io.StringIO()
            csv.writer(header, lineterminator="\n").writerow(
                (*reader.layout.header, *EXTRA_COLUMNS)
            )
            handle.write(header.getvalue().encode("utf-8"))
            for block in read_ahead(reader.blocks()):
                extra = _extra(block, compensator, totals, reader.source, accelerometer)
                _csv_block(handle, block, extra)
                progress(block.byte_range[1] if block.byte_range else totals.rows)
    return totals


def _open(
    path: Path, config: CompensateConfig, *, to_parquet: bool, columns: bool = False
) -> SampleCsvReader | ParquetSampleReader:
    """A block reader for ``path`` (Parquet by its extension, else CSV), keeping what the
    output needs: the rows' text for a CSV output, their columns for a Parquet one (and with
    ``columns`` for either: a column beyond the sample's, the temperature, is read)."""
    open_reader: Callable[..., SampleCsvReader | ParquetSampleReader]
    if path.suffix.lower() == ".parquet":
        from ftcomp.io.parquet import ParquetSampleReader

        open_reader = partial(ParquetSampleReader, batch_rows=config.parquet_batch_rows)
    else:
        open_reader = partial(SampleCsvReader, chunk_bytes=config.csv_chunk_bytes)
    return open_reader(
        path,
        force_range_N=config.force_range_N,
        torque_range_Nm=config.torque_range_Nm,
        with_text=not to_parquet,
        with_table=to_parquet or columns,
    )


def _input_size(path: Path) -> int:
    """How far a whole read goes, in :func:`compensate_file`'s progress units: the rows of a
    Parquet file (from its footer), the bytes of a CSV."""
    if path.suffix.lower() == ".parquet":
        import pyarrow.parquet as pq

        return int(pq.ParquetFile(path).metadata.num_rows)
    return path.stat().st_size


def compensate_file(
    samples: PathLike,
    output: PathLike,
    calibration: Calibration | PathLike,
    config: CompensateConfig | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> CompensateResult:
    """Remove sensor bias and tool gravity from every reading of ``samples`` into ``output``.

    Args:
        samples: a sample CSV, or Parquet when the name ends in ``.parquet``: fx..tz [N, N*m] in
            the sensor frame and one orientation encoding (docs/files.md); a ``t`` column when
            the calibration has a bias drift in time, a ``temperature_C`` column [degC] when
            its bias follows the sensor's temperature.
        output: CSV, or Parquet by its extension: the input columns plus
            :data:`EXTRA_COLUMNS` (contact wrench [N, N*m], sensor frame, and load weight [N]).
            Never ``samples``, nor the calibration file.
        calibration: the calibration, or its file (``ftcomp calibrate``'s JSON).
        config: ranges, block sizes and the overwrite policy (defaults: no range check,
            the readers' block sizes, never replace a file).
        progress: called after each block with ``(done, total)``: how far the input has been
            read and its whole size, in bytes of a CSV or rows of a Parquet file (e.g. for a
            progress bar; default: none).

    Returns:
        The :class:`CompensateResult` (rows, time, means, warnings).

    Raises:
        ParameterError: the output is an input, exists without ``config.overwrite`` or cannot
            be written; the input already has a compensated column; the calibration's bias
            drift needs a time (or temperature) column the input lacks, or ``accelerometer``
            the accelerometer's columns.
        InputFileError, CalibrationFileError: naming the file (and row, column) at fault.
    """
    config = config if config is not None else CompensateConfig()
    start = time.monotonic()
    source, out = Path(samples), Path(output)
    if out.resolve() == source.resolve() or (
        out.exists() and source.exists() and os.path.samefile(out, source)
    ):
        raise ParameterError(f"{out}: the output would replace the input samples")
    inputs: tuple[PathLike, ...] = (source,)
    if not isinstance(calibration, Calibration):
        inputs = (source, calibration)
    out = check_writable(out, overwrite=config.overwrite, inputs=inputs)
    if not isinstance(calibration, Calibration):
        calibration = load_calibration(calibration)
    to_parquet = out.suffix.lower() == ".parquet"
    drift = calibration.bias_drift
    heat = isinstance(drift, TemperatureBiasDrift)
    columns = heat or config.accelerometer
    with _open(source, config, to_parquet=to_parquet, columns=columns) as reader:
        clash = [c for c in EXTRA_COLUMNS if c in reader.layout.header]
        if clash:
            raise ParameterError(
                f"{reader.source}: already has column {clash[0]!r}; compensate raw readings only"
            )
        if heat and TEMPERATURE_CHANNEL not in reader.layout.header:
            raise ParameterError(
                f"{reader.source}: the calibration's bias follows the sensor's temperature "
                f"(bias_drift temperature), applied from each row's temperature: the file has "
                f"no {TEMPERATURE_CHANNEL!r} column"
            )
        missing = [c for c in _ACCEL if c not in reader.layout.header]
        if config.accelerometer and missing:
            raise ParameterError(
                f"{reader.source}: accelerometer: the tool's acceleration is read from each "
                f"row's {', '.join(_ACCEL)}: the file has no {missing[0]!r} column",
                field="accelerometer",
            )
        if drift is not None and not heat and not reader.layout.has_t:
            raise ParameterError(
                f"{reader.source}: the calibration has a {drift.name} bias drift, applied from "
                "each row's time: the file has no 't' (or 't_ns') column"
            )
        size = _input_size(source) if progress is not None else 0

        def done(n: int) -> None:
            if progress is not None:
                progress(n, size)

        compensator = GravityCompensator(calibration)
        totals = _write(reader, compensator, out, to_parquet, done, config.accelerometer)
    warnings = list(reader.warnings)
    t_range = (
        (totals.t_min, totals.t_max) if drift is not None and not heat and totals.rows else None
    )
    T_range = (totals.T_min, totals.T_max) if heat and totals.rows else None
    outside = None
    if isinstance(drift, TemperatureBiasDrift):
        outside = drift.outside(totals.T_min, totals.T_max) if totals.rows else None
    elif drift is not None:
        outside = drift.outside(totals.t_min, totals.t_max)
    if outside is not None:
        warnings.append(outside)
    rows = totals.rows
    return CompensateResult(
        output=out,
        rows=rows,
        duration_s=time.monotonic() - start,
        load_weight_mean_N=totals.weight_sum / rows if rows else math.nan,
        load_weight_max_N=totals.weight_max if rows else math.nan,
        contact_wrench_mean_sensor=totals.contact_sum / rows if rows else np.full(6, np.nan),
        t_range_s=t_range,
        warnings=tuple(warnings),
        temperature_range_C=T_range,
    )
