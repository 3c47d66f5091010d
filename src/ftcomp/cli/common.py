"""Small pieces the commands share: argument types and warning output."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Iterable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ftcomp.calibration_record import Calibration

__all__ = ["add_range_argument", "parse_range", "print_warnings", "warn_live_drift"]


def parse_range(text: str) -> tuple[float, float]:
    """``"250,6"`` -> ``(250.0, 6.0)``: a sensor's force [N] and torque [N*m] range."""
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 2 or not all(math.isfinite(v) and v > 0 for v in values):
        raise argparse.ArgumentTypeError(
            f"expected FORCE_N,TORQUE_NM with two positive numbers, e.g. 250,6; got {text!r}"
        )
    return values[0], values[1]


def print_warnings(warnings: Iterable[str]) -> None:
    """One ``warning: ...`` line per warning, on stderr."""
    for warning in warnings:
        print(f"warning: {warning}", file=sys.stderr)


def add_range_argument(parser: argparse.ArgumentParser) -> None:
    """``--range FORCE_N,TORQUE_NM``: readings beyond the sensor's range are bad input."""
    parser.add_argument(
        "--range",
        metavar="FORCE_N,TORQUE_NM",
        type=parse_range,
        help="sensor range [N],[N·m], e.g. 250,6: a reading beyond it is an error "
        "(default: no check)",
    )


def warn_live_drift(calibration: Calibration, path: str) -> None:
    """Say so when a calibration's bias drift will not be applied by a live loop."""
    if calibration.bias_drift is not None:
        print_warnings(
            [
                f"{path}: the bias drift model is not applied live (its times are the "
                "recording's clock); the bias at the end of the calibration is used: run "
                "ftcomp rebias at the start of a session"
            ]
        )
