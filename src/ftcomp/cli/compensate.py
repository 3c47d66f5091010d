"""``ftcomp compensate SAMPLES.csv -c calibration.json -o out.csv``.

Streams: the samples are read, compensated and written one block of rows at a time, so memory
does not grow with the file (an hour at 7 kHz, 25 M rows, runs in a few hundred MB). Input and
output are CSV or Parquet by their extension. A CSV output repeats each input line as it was
and appends the contact wrench and load weight as ``% .9e`` (ten significant digits); a Parquet
output has the input columns and the extra columns as float64. The output appears only when
every row has been written (a temporary file renamed into place): an error leaves no file.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import os
import queue
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.typing import NDArray

from ftcomp.cli.common import add_range_argument, print_warnings
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.errors import ParameterError
from ftcomp.io.atomic import atomic_output, check_writable
from ftcomp.io.calibration_json import load_calibration
from ftcomp.io.numtext import format_rows
from ftcomp.io.sample_format import SampleBlock
from ftcomp.io.samples_csv import open_samples

__all__ = ["EXTRA_COLUMNS", "register"]

#: Columns added to the input: the contact wrench (Eq. 22) and the load weight (Eq. 23).
EXTRA_COLUMNS = ("fx_ext", "fy_ext", "fz_ext", "tx_ext", "ty_ext", "tz_ext", "load_weight_N")


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``compensate`` command's arguments to its parser."""
    parser.description = (
        "Remove sensor bias and tool gravity from every reading of a sample file (CSV, or "
        "Parquet when the name ends in .parquet); writes the input columns plus "
        + ",".join(EXTRA_COLUMNS)
        + ". Streams: any length of recording runs in bounded memory."
    )
    parser.add_argument(
        "samples",
        metavar="SAMPLES.csv",
        help="readings to compensate: sample CSV or .parquet with fx..tz [N, N·m] in the "
        "sensor frame and one orientation encoding (docs/files.md)",
    )
    parser.add_argument(
        "-c",
        "--calibration",
        required=True,
        metavar="CALIBRATION.json",
        help="calibration file from 'ftcomp calibrate' (bias, tool weight and centre of "
        "gravity, base tilt) (required)",
    )
    parser.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="OUT.csv",
        help="output CSV or .parquet: the input columns plus the contact wrench fx_ext..tz_ext "
        "[N, N·m] and load_weight_N [N] (required; never the input file)",
    )
    add_range_argument(parser)
    parser.add_argument(
        "--json",
        action="store_true",
        help="print a JSON summary (rows, mean and largest load weight, mean contact wrench) "
        "instead of one line",
    )
    parser.add_argument(
        "--force", action="store_true", help="replace an existing output file (default: refuse)"
    )
    parser.set_defaults(handler=run)


@dataclass
class _Summary:
    rows: int = 0
    weight_sum: float = 0.0
    weight_max: float = -np.inf
    contact_sum: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    t_min: float = np.inf
    t_max: float = -np.inf

    def add(self, contact: NDArray[np.float64], weight: NDArray[np.float64]) -> None:
        self.rows += len(weight)
        self.weight_sum += float(weight.sum())
        self.weight_max = max(self.weight_max, float(weight.max()))
        self.contact_sum += contact.sum(axis=0)


def _extra(
    block: SampleBlock, compensator: GravityCompensator, summary: _Summary
) -> NDArray[np.float64]:
    """The block's contact wrench and load weight, shape (N, 7)."""
    extra = np.empty((len(block), 7))
    t_s = block.t if compensator.bias_drift is not None else None
    if t_s is not None and len(t_s):
        summary.t_min = min(summary.t_min, float(t_s.min()))
        summary.t_max = max(summary.t_max, float(t_s.max()))
    contact = compensator.compensate(block.wrench_sensor, block.R_base_sensor, t_s=t_s)
    extra[:, :6] = contact
    np.sqrt(np.einsum("ij,ij->i", contact[:, :3], contact[:, :3]), out=extra[:, 6])
    summary.add(contact, extra[:, 6])
    return extra


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


def _prefetched(blocks: Iterator[SampleBlock]) -> Iterator[SampleBlock]:
    """``blocks``, with the next one read and parsed in a worker thread meanwhile.

    Parsing (pyarrow, numpy) and formatting (numpy) release the GIL, so the two overlap on two
    cores. An error in the worker is raised here, at the block where it happened.
    """
    ready: queue.Queue[tuple[SampleBlock | None, BaseException | None]] = queue.Queue(maxsize=1)
    stop = threading.Event()

    def hand_over(item: tuple[SampleBlock | None, BaseException | None]) -> bool:
        while not stop.is_set():  # never block for good: the consumer may have left
            try:
                ready.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def work() -> None:
        try:
            for block in blocks:
                if not hand_over((block, None)):
                    return
            hand_over((None, None))
        except BaseException as exc:  # raised again in the consumer
            hand_over((None, exc))

    worker = threading.Thread(target=work, name="ftcomp-read", daemon=True)
    worker.start()
    try:
        while True:
            block, error = ready.get()
            if error is not None:
                raise error
            if block is None:
                return
            yield block
    finally:
        stop.set()
        worker.join()


def _stream(
    reader: Any, compensator: GravityCompensator, output: Path, to_parquet: bool
) -> _Summary:
    """Compensate every block of ``reader`` into ``output``, atomically."""
    summary = _Summary()
    with atomic_output(output) as tmp, tmp.open("wb") as handle:
        if to_parquet:
            import pyarrow as pa

            from ftcomp.io.parquet import ParquetBlockWriter

            with ParquetBlockWriter(handle) as writer:
                for block in _prefetched(reader.blocks()):
                    extra = _extra(block, compensator, summary)
                    table = block.table
                    for j, name in enumerate(EXTRA_COLUMNS):
                        table = table.append_column(name, pa.array(extra[:, j]))
                    writer.write(table)
        else:
            header = io.StringIO()
            csv.writer(header, lineterminator="\n").writerow(
                (*reader.layout.header, *EXTRA_COLUMNS)
            )
            handle.write(header.getvalue().encode("utf-8"))
            for block in _prefetched(reader.blocks()):
                extra = _extra(block, compensator, summary)
                _csv_block(handle, block, extra)
    return summary


def run(args: argparse.Namespace) -> int:
    """Read, compensate and write, block by block."""
    samples = Path(args.samples)
    output = Path(args.output)
    if output.resolve() == samples.resolve() or (
        output.exists() and samples.exists() and os.path.samefile(output, samples)
    ):
        raise ParameterError(f"{output}: the output would replace the input samples")
    output = check_writable(output, overwrite=args.force, inputs=(samples, args.calibration))
    calibration = load_calibration(args.calibration)
    force_range, torque_range = args.range if args.range else (None, None)
    to_parquet = output.suffix.lower() == ".parquet"
    with open_samples(
        args.samples,
        force_range_N=force_range,
        torque_range_Nm=torque_range,
        with_text=not to_parquet,
        with_table=to_parquet,
    ) as reader:
        clash = [c for c in EXTRA_COLUMNS if c in reader.layout.header]
        if clash:
            raise ParameterError(
                f"{reader.source}: already has column {clash[0]!r}; compensate raw readings only"
            )
        drift = calibration.bias_drift
        if drift is not None and not reader.layout.has_t:
            raise ParameterError(
                f"{reader.source}: the calibration has a {drift.name} bias drift, applied from "
                "each row's time: the file has no 't' (or 't_ns') column"
            )
        summary = _stream(reader, GravityCompensator(calibration), output, to_parquet)
    print_warnings(reader.warnings)
    if drift is not None and (summary.t_min < drift.t_min_s or summary.t_max > drift.t_max_s):
        print_warnings(
            [
                f"rows at t = {summary.t_min:.6g} .. {summary.t_max:.6g} s lie outside the "
                f"calibrated time range {drift.t_min_s:.6g} .. {drift.t_max_s:.6g} s: the "
                f"{drift.name} bias drift is extrapolated there (re-bias with ftcomp rebias)"
            ]
        )
    if args.json:
        result = {
            "output": str(output),
            "rows": summary.rows,
            "load_weight_N": {
                "mean": summary.weight_sum / summary.rows,
                "max": summary.weight_max,
            },
            "contact_wrench_mean": (summary.contact_sum / summary.rows).tolist(),
        }
        print(json.dumps(result, indent=2))
    else:
        print(f"{summary.rows} rows compensated; written to {output}")
    return 0
