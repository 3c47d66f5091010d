"""``ftcomp calibrate-dynamic MOTION.csv -c calibration.json -o dynamic.json``: the tool's
inertia tensor from a recorded excitation trajectory (beyond the paper)."""

from __future__ import annotations

import argparse
import csv
import math

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.dynamic import ExcitationLimits, identify_inertia
from ftcomp.cli.common import print_warnings
from ftcomp.errors import InputFileError
from ftcomp.io.atomic import check_writable
from ftcomp.io.calibration_json import load_calibration
from ftcomp.io.dynamic_json import save_dynamic
from ftcomp.io.samples_csv import read_samples
from ftcomp.kinematics import INERTIA_PARAMETERS

__all__ = ["register"]

_POSITION_COLUMNS = ("px", "py", "pz")


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``calibrate-dynamic`` command's arguments to its parser."""
    parser.description = (
        "Identify the tool's inertia tensor (about its centre of gravity, sensor axes) from a "
        "recording of a short, fast excitation trajectory without contact, e.g. "
        "'ftcomp stream --pose' while the wrist swings about every axis. The static "
        "parameters (bias, weight, centre of gravity, tilt) stay those of the calibration. "
        "Kinematics: the recorded poses differentiated by a Savitzky-Golay filter."
    )
    parser.add_argument(
        "motion",
        metavar="MOTION.csv",
        help="one row per control cycle: t [s, evenly spaced], fx..tz [N, N·m, sensor frame], "
        "an orientation encoding (e.g. qx,qy,qz,qw) and the sensor origin px,py,pz [m, base "
        "frame]: the log of 'ftcomp stream' with a pose",
    )
    parser.add_argument(
        "-c",
        "--calibration",
        required=True,
        metavar="CALIBRATION.json",
        help="the tool's static calibration from 'ftcomp calibrate' (required)",
    )
    parser.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="DYNAMIC.json",
        help="the inertia tensor [kg·m²] with standard errors (required; never an input)",
    )
    parser.add_argument(
        "--min-duration-s",
        type=float,
        default=ExcitationLimits.min_duration_s,
        help="shortest recording accepted [s] (default %(default)s)",
    )
    parser.add_argument(
        "--min-alpha-rad-s2",
        type=float,
        default=ExcitationLimits.min_alpha_rad_s2,
        help="peak angular acceleration needed about each sensor axis [rad/s²] "
        "(default %(default)s)",
    )
    parser.add_argument(
        "--force", action="store_true", help="replace an existing output file (default: refuse)"
    )
    parser.set_defaults(handler=run)


def _positions(path: str, n: int) -> NDArray[np.float64]:
    """The px,py,pz columns [m] of every data row, (n, 3)."""
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        header = [h.strip() for h in next(reader, [])]
        missing = [c for c in _POSITION_COLUMNS if c not in header]
        if missing:
            raise InputFileError(
                f"{path}: no column {missing[0]!r}: the sensor origin px,py,pz [m] is needed "
                "for the linear acceleration"
            )
        cols = [header.index(c) for c in _POSITION_COLUMNS]
        out = np.empty((n, 3))
        row_no = 0
        for row_no, row in enumerate(reader, start=2):
            if row_no - 2 >= n:
                break
            for k, c in enumerate(cols):
                try:
                    value = float(row[c])
                except (IndexError, ValueError):
                    value = math.nan
                if not math.isfinite(value):
                    cell = row[c] if c < len(row) else ""
                    raise InputFileError(
                        f"{path}: row {row_no}, column {_POSITION_COLUMNS[k]}: "
                        f"{cell!r} is not a finite number"
                    )
                out[row_no - 2, k] = value
    return out


def run(args: argparse.Namespace) -> int:
    """Read, identify, write, print the tensor with its standard errors."""
    output = check_writable(
        args.output, overwrite=args.force, inputs=[args.motion, args.calibration]
    )
    calibration = load_calibration(args.calibration)
    samples = read_samples(args.motion)
    print_warnings(samples.warnings)
    if samples.t is None:
        raise InputFileError(f"{args.motion}: no time column t [s]: the kinematics need it")
    p = _positions(args.motion, len(samples))
    limits = ExcitationLimits(
        min_duration_s=args.min_duration_s, min_alpha_rad_s2=args.min_alpha_rad_s2
    )
    dynamic = identify_inertia(
        samples.t, samples.wrench_sensor, p, samples.R_base_sensor, calibration, limits=limits
    )
    save_dynamic(output, dynamic, overwrite=args.force)
    theta = dynamic.inertia_cog_kgm2[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]
    print(
        f"inertia from {dynamic.samples} readings over {dynamic.duration_s:.2f} s (peak angular "
        "acceleration "
        + ", ".join(f"{v:.1f}" for v in dynamic.peak_alpha_rad_s2)
        + " rad/s² about x, y, z):"
    )
    for name, value, error in zip(INERTIA_PARAMETERS, theta, dynamic.std_error_kgm2, strict=True):
        print(f"  {name}: {value:+.4e} ± {error:.1e} kg·m²")
    print(f"dynamic calibration written to {output}")
    return 0
