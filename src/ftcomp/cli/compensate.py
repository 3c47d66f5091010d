"""``ftcomp compensate SAMPLES.csv -c calibration.json -o out.csv``: parses, calls
:func:`ftcomp.session.compensate_file.compensate_file` (streaming, CSV or Parquet, the output
only when complete), prints a summary; a progress bar on a terminal (silent when piped).
"""

from __future__ import annotations

import argparse
import json

from ftcomp.cli.common import add_accelerometer_argument, add_range_argument, print_warnings
from ftcomp.cli.live_status import CallbackProgress
from ftcomp.session.compensate_file import EXTRA_COLUMNS

__all__ = ["register", "run"]


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
    add_accelerometer_argument(parser, "the rows' accel_x_m_s2, accel_y_m_s2, accel_z_m_s2")
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


def run(args: argparse.Namespace) -> int:
    """Compensate the file, then print the warnings and a summary."""
    from ftcomp.session.compensate_file import CompensateConfig, compensate_file

    force_range, torque_range = args.range if args.range else (None, None)
    config = CompensateConfig(
        force_range_N=force_range,
        torque_range_Nm=torque_range,
        overwrite=args.force,
        accelerometer=args.accelerometer,
    )
    parquet = str(args.samples).lower().endswith(".parquet")
    bar = CallbackProgress("rows read" if parquet else "MB read", 1.0 if parquet else 1e6)
    try:
        result = compensate_file(args.samples, args.output, args.calibration, config, bar)
    finally:
        bar.close()
    print_warnings(result.warnings)
    if args.json:
        summary = {
            "output": str(result.output),
            "rows": result.rows,
            "load_weight_N": {"mean": result.load_weight_mean_N, "max": result.load_weight_max_N},
            "contact_wrench_mean": result.contact_wrench_mean_sensor.tolist(),
        }
        print(json.dumps(summary, indent=2))
    else:
        print(f"{result.rows} rows compensated; written to {result.output}")
    return 0
