"""``ftcomp compensate SAMPLES.csv -c calibration.json -o out.csv``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from ftcomp.cli.common import parse_range, print_warnings
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.errors import ParameterError
from ftcomp.io.atomic import check_writable
from ftcomp.io.calibration_json import load_calibration
from ftcomp.io.samples_csv import read_samples, write_table

__all__ = ["EXTRA_COLUMNS", "register"]

#: Columns added to the input: the contact wrench (Eq. 22) and the load weight (Eq. 23).
EXTRA_COLUMNS = ("fx_ext", "fy_ext", "fz_ext", "tx_ext", "ty_ext", "tz_ext", "load_weight_N")


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``compensate`` command's arguments to its parser."""
    parser.description = (
        "Remove sensor bias and tool gravity from every reading of a sample CSV; "
        "writes the input columns plus " + ",".join(EXTRA_COLUMNS) + "."
    )
    parser.add_argument("samples", metavar="SAMPLES.csv")
    parser.add_argument("-c", "--calibration", required=True, metavar="CALIBRATION.json")
    parser.add_argument("-o", "--output", required=True, metavar="OUT.csv")
    parser.add_argument("--range", metavar="FORCE_N,TORQUE_NM", type=parse_range)
    parser.add_argument("--json", action="store_true", help="print a JSON summary")
    parser.add_argument("--force", action="store_true", help="replace an existing output file")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Read, compensate, write."""
    output = check_writable(args.output, overwrite=args.force)
    if output.resolve() == Path(args.samples).resolve():
        raise ParameterError(f"{output}: the output would replace the input samples")
    calibration = load_calibration(args.calibration)
    force_range, torque_range = args.range if args.range else (None, None)
    samples = read_samples(args.samples, force_range_N=force_range, torque_range_Nm=torque_range)
    print_warnings(samples.warnings)
    clash = [c for c in EXTRA_COLUMNS if c in samples.header]
    if clash:
        raise ParameterError(
            f"{samples.source}: already has column {clash[0]!r}; compensate raw readings only"
        )
    compensator = GravityCompensator(calibration)
    contact = compensator.compensate(samples.wrench_sensor, samples.R_base_sensor)
    weight = np.linalg.norm(contact[:, :3], axis=1)
    extra = np.column_stack([contact, weight])
    rows = [
        (*row, *(f"{v:.10g}" for v in ext)) for row, ext in zip(samples.rows, extra, strict=True)
    ]
    write_table(output, (*samples.header, *EXTRA_COLUMNS), rows)
    if args.json:
        summary = {
            "output": str(output),
            "rows": len(rows),
            "load_weight_N": {"mean": float(weight.mean()), "max": float(weight.max())},
            "contact_wrench_mean": contact.mean(axis=0).tolist(),
        }
        print(json.dumps(summary, indent=2))
    else:
        print(f"{len(rows)} rows compensated; written to {output}")
    return 0
