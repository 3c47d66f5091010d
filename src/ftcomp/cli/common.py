"""Small pieces the commands share: argument types and warning output."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from ftcomp.errors import ParameterError

if TYPE_CHECKING:
    from ftcomp.calibration_record import Calibration
    from ftcomp.session.run import RunResult
    from ftcomp.session.stream import StreamResult

    LiveResult = RunResult | StreamResult

__all__ = [
    "add_range_argument",
    "add_rebias_argument",
    "add_track_bias_argument",
    "check_rebias_argument",
    "live_end_lines",
    "parse_range",
    "print_warnings",
    "warn_live_drift",
]


def parse_range(text: str) -> tuple[float, float]:
    """``"250,6"`` -> ``(250.0, 6.0)``: a sensor's force [N] and torque [N*m] range, by its rule
    (:data:`ftcomp.samples.SENSOR_RANGE`)."""
    from ftcomp.config_fields import check_value
    from ftcomp.samples import SENSOR_RANGE

    try:
        values: Any = check_value("range", SENSOR_RANGE, [float(p) for p in text.split(",")])
    except (ValueError, ParameterError):
        raise argparse.ArgumentTypeError(
            f"expected FORCE_N,TORQUE_NM, two numbers {SENSOR_RANGE.rule()}, e.g. 250,6; "
            f"got {text!r}"
        ) from None
    return float(values[0]), float(values[1])


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


def warn_live_drift(calibration: Calibration, path: str, *, tracking: bool = False) -> None:
    """Say so when a calibration's bias drift in time will not be applied by a live loop (and,
    unless ``tracking`` (``--track-bias``) follows the bias from there, how to follow it); a
    bias that follows the temperature is applied live from each reading's."""
    drift = calibration.bias_drift
    if drift is not None and drift.name != "temperature":
        then = (
            "--track-bias follows the bias from there"
            if tracking
            else "to follow the bias since, add --track-bias or run ftcomp rebias at the start"
        )
        print_warnings(
            [
                f"{path}: the bias drift model is held at the end of its session live (its "
                f"times are the recording's clock, never extrapolated); {then}"
            ]
        )


def add_accelerometer_argument(
    parser: argparse.ArgumentParser,
    source: str = "a sensor with an IMU: Bota through bota-driver",
) -> None:
    """``--accelerometer``: the tool's (and a weighed load's) acceleration from the sensor's
    IMU (the ``accelerometer`` field of the run's, the stream's and compensate's configs;
    ``source``: where the readings come from, for the help)."""
    parser.add_argument(
        "--accelerometer",
        action="store_true",
        help="take the tool's acceleration (and a grasped load's) from the sensor's "
        f"accelerometer, so a moving tool's inertial force is compensated too ({source}; "
        "default: off, the tool held still at its pose's gravity)",
    )


def add_track_bias_argument(parser: argparse.ArgumentParser) -> None:
    """``--track-bias``: the bias follows the sensor while the arm is still and free (its
    thresholds, in the help, are :class:`~ftcomp.compensation.bias_tracking.BiasTrackingConfig`'s
    defaults)."""
    from ftcomp.compensation.bias_tracking import BiasTrackingConfig

    d = BiasTrackingConfig()
    parser.add_argument(
        "--track-bias",
        action="store_true",
        help="let the calibration's bias follow the sensor while the arm is still and nothing "
        f"touches the tool (compensated force < {d.contact_force_N:g} N and torque < "
        f"{d.contact_torque_Nm:g} N·m, orientation steady for {d.still_hold_s:g} s; at most "
        f"{d.max_rate_force_N_per_s:g} N/s, {d.max_correction_force_N:g} N in all); the log "
        "gains bias_updated (default: off; a steady contact lighter than "
        f"{d.contact_force_N:g} N would be taken for bias)",
    )


def add_rebias_argument(parser: argparse.ArgumentParser) -> None:
    """``--rebias-s``: the calibration's bias re-estimated from still readings at the start."""
    from ftcomp.cli.options import add_field_option
    from ftcomp.session.rebias_live import REBIAS_DURATION

    add_field_option(
        parser,
        REBIAS_DURATION,
        "rebias_s",
        "--rebias-s",
        default=None,
        none_means="the calibration's bias",
        metavar="SECONDS",
        help="first re-estimate the calibration's bias from SECONDS of readings with the arm "
        "still and nothing touching the tool (the tool model kept, gravity-aware; a drift "
        "model dropped), then start from the bias now; with --track-bias, tracking follows "
        "it from there",
    )


def check_rebias_argument(args: argparse.Namespace) -> None:
    """``--rebias-s`` needs a calibration (its range is checked by its rule,
    :data:`ftcomp.session.rebias_live.REBIAS_DURATION`)."""
    if args.rebias_s is not None and not args.calibration:
        raise ParameterError("--rebias-s needs the tool's calibration (-c)")


def live_end_lines(result: LiveResult) -> list[str]:
    """What every live command prints at its end besides its summary: the loop's timing line,
    the rows its observers dropped, what the bias tracking did, temperatures beyond a
    temperature bias model's range."""
    lines = [] if result.timing is None else [result.timing.line()]
    if result.observer_dropped_rows:
        lines.append(
            f"observers: {result.observer_dropped_rows} log rows dropped (their queue was full)"
        )
    c = result.bias_correction
    if c is not None:
        lines.append(
            f"bias tracking: {result.bias_updates} updates, the bias moved by [{c[0]:+.3f} "
            f"{c[1]:+.3f} {c[2]:+.3f}] N [{c[3]:+.4f} {c[4]:+.4f} {c[5]:+.4f}] N·m from the "
            "calibration's"
        )
    if result.temperature_outside:
        lines.append(f"temperature bias model: {result.temperature_outside}")
    return lines
