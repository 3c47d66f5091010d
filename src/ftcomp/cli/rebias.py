"""``ftcomp rebias CALIBRATION.json STILL.csv -o new.json``: re-estimate only the bias."""

from __future__ import annotations

import argparse

from ftcomp.calibration.rebias import bias_of, rebias
from ftcomp.cli.common import print_warnings
from ftcomp.io.atomic import check_writable
from ftcomp.io.calibration_json import load_calibration, save_calibration
from ftcomp.io.samples_csv import read_samples
from ftcomp.samples import WRENCH_COLUMNS

__all__ = ["register"]


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``rebias`` command's arguments to its parser."""
    parser.description = (
        "Re-estimate only the sensor bias of a calibration from a few seconds of still readings "
        "at any pose without contact, the tool model (weight, centre of gravity, tilt) kept: "
        "a gravity-aware tare, the cure for bias drift. Writes a new calibration file (a bias "
        "drift model in the old one is dropped: the new bias is the bias now)."
    )
    parser.add_argument("calibration", metavar="CALIBRATION.json", help="the calibration to update")
    parser.add_argument(
        "still",
        metavar="STILL.csv",
        help="sample CSV of still readings without contact (fx..tz [N, N·m], sensor frame, "
        "one orientation encoding; the recorded frame's if the calibration has a mount)",
    )
    parser.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="NEW.json",
        help="the updated calibration file (required; never one of the inputs)",
    )
    parser.add_argument(
        "--force", action="store_true", help="replace an existing output file (default: refuse)"
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Load, re-estimate the bias, write, print old and new bias."""
    output = check_writable(
        args.output, overwrite=args.force, inputs=[args.calibration, args.still]
    )
    calibration = load_calibration(args.calibration)
    samples = read_samples(args.still)
    print_warnings(samples.warnings)
    new = rebias(calibration, samples)
    save_calibration(output, new)
    old_bias, _ = bias_of(calibration)
    new_bias, se = bias_of(new)
    print(f"bias re-estimated from {len(samples)} readings (tool model kept):")
    for name, old, value, error in zip(WRENCH_COLUMNS, old_bias, new_bias, se, strict=True):
        unit = "N" if name.startswith("f") else "N·m"
        print(f"  {name}: {old:+.5f} -> {value:+.5f} ± {error:.5f} {unit}")
    if calibration.bias_drift is not None:
        print_warnings([f"the {calibration.bias_drift.name} bias drift model was dropped"])
    print(f"calibration written to {output}")
    return 0
