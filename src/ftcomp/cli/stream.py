"""``ftcomp stream``: log a sensor's readings at its own rate, raw and compensated.

``ftcomp stream --sensor URI [--robot URI] [-c calibration.json [--online-load]] --seconds S
-o log.csv``

Every reading is one row (``t`` on the session's clock, ``fx..tz`` raw, sensor frame); with a
robot the sensor's pose (``qx..qw``, ``px..pz``), and with a calibration the contact wrench
(``cfx..ctz``). Compensation needs the pose: give ``--robot`` (an arm, or ``fixed://?rpy_deg=..``
for a sensor held still). A terminal shows a live line: rate, lost packets, contact force.
A fault or Ctrl-C keeps what was logged and exits non-zero (1, or 130).

``--online-load`` weighs what the gripper grasps while streaming: grasp and release are detected
on the compensated wrench, the load's mass and centre of gravity estimated, and once converged
removed from the contact wrench too. The log gains ``load_state`` (0 empty, 1 estimating,
2 holding), ``load_kg``, ``load_kg_std``, ``load_cx_m..load_cz_m`` (sensor frame) and
``load_c_std_m``; the end lists the events. Start with the gripper empty: a load held from the
start is no step and counts as contact.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from ftcomp.cli.common import (
    add_accelerometer_argument,
    add_rebias_argument,
    add_track_bias_argument,
    check_rebias_argument,
    live_end_lines,
    warn_live_drift,
)
from ftcomp.cli.hardware_options import add_hardware_arguments, open_hardware
from ftcomp.cli.live_status import StatusLine, add_view_arguments
from ftcomp.cli.options import add_field_option
from ftcomp.compensation.pipeline import MEASURE_RATE_S
from ftcomp.errors import ParameterError
from ftcomp.session.stream import StreamConfig

if TYPE_CHECKING:
    from ftcomp.hardware.protocols import Robot, StreamHealth

__all__ = ["register", "run"]


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``stream`` command's arguments to its parser."""
    parser.description = __doc__.split("\n\n", 1)[1].replace("``", "") if __doc__ else None
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    add_hardware_arguments(parser, robot_required=False)
    parser.add_argument(
        "-c",
        "--calibration",
        metavar="CALIBRATION.json",
        help="also log the contact wrench (default: the raw readings only)",
    )
    parser.add_argument(
        "--online-load",
        action="store_true",
        help="weigh a grasped load online and compensate it too (needs -c and a pose; "
        "default: off, the tool alone)",
    )
    add_field_option(
        parser,
        StreamConfig,
        "online_rate_hz",
        metavar="HZ",
        none_means=f"measured from the stamps of the first {MEASURE_RATE_S:g} s of readings, held "
        "back and then logged",
    )
    add_accelerometer_argument(parser)
    add_track_bias_argument(parser)
    add_rebias_argument(parser)
    add_field_option(parser, StreamConfig, "duration_s", "--seconds", required=True)
    parser.add_argument(
        "-o", "--output", required=True, metavar="LOG.csv", help="the log, one row per reading"
    )
    parser.add_argument("--force", action="store_true", help="replace an existing output file")
    add_view_arguments(parser)
    parser.set_defaults(handler=run)


def _health_text(health: StreamHealth | None) -> str:
    if health is None:
        return ""
    return (
        f"; lost {health.lost_packets} packets of {health.received + health.lost_packets} "
        f"(last RDT sequence {health.last_sequence})"
    )


def run(args: argparse.Namespace) -> int:
    """Open, stream, report."""
    from ftcomp.compensation.bias_tracking import BiasTrackingConfig
    from ftcomp.io.atomic import check_writable
    from ftcomp.io.calibration_json import load_calibration
    from ftcomp.session.online_load import event_lines
    from ftcomp.session.rebias_live import rebias_still
    from ftcomp.session.stream import stream
    from ftcomp.views.live import session_observers

    if args.online_rate_hz is not None and not args.online_load:
        raise ParameterError("--online-rate-hz needs --online-load")
    if args.track_bias and (args.online_load or not args.calibration):
        raise ParameterError("--track-bias needs the tool's calibration (-c) and not --online-load")
    if args.online_load and not args.calibration:
        raise ParameterError(
            "--online-load needs the tool's calibration: give -c CALIBRATION.json "
            "(from ftcomp calibrate)"
        )
    check_rebias_argument(args)
    rate = args.online_rate_hz
    config = StreamConfig(
        args.seconds,
        with_pose=args.robot is not None,
        online_load=args.online_load,
        online_rate_hz=rate,
        track_bias=BiasTrackingConfig() if args.track_bias else None,
        accelerometer=args.accelerometer,
    )
    inputs = [args.calibration] if args.calibration else []
    output = check_writable(args.output, overwrite=args.force, inputs=inputs)
    if args.log is not None:
        check_writable(args.log, overwrite=args.force, inputs=[*inputs, args.output])
    calibration = load_calibration(args.calibration) if args.calibration else None
    if calibration is not None and args.rebias_s is None:  # a re-bias drops the drift model
        warn_live_drift(calibration, args.calibration, tracking=args.track_bias)
    if calibration is not None and args.robot is None:
        raise ParameterError(
            "compensation (-c) needs the sensor's pose: give --robot (ur://HOST, "
            "fixed://?rpy_deg=R,P,Y for a sensor held still, ...)"
        )

    def check_pose(robot: Robot) -> None:
        if calibration is not None and not robot.pose_known:
            raise ParameterError(
                f"{args.robot}: gives no pose to compensate with: add ?rpy_deg=R,P,Y (and xyz_mm)"
            )

    status = StatusLine()
    with (
        session_observers(args.log, args.view, overwrite=args.force) as observers,
        open_hardware(args, check_pose) as (robot, sensor, mount),
    ):
        if calibration is not None and args.rebias_s is not None:
            rebiased = rebias_still(robot, sensor, calibration, args.rebias_s, mount=mount)
            print(rebiased.line(), flush=True)
            calibration = rebiased.calibration
        try:
            result = stream(
                robot,
                sensor,
                config,
                output,
                calibration=calibration,
                mount=mount,
                on_progress=status,
                source=args.calibration or "",
                observers=observers,
            )
        finally:
            status.close()
    summary = (
        f"{result.readings} readings in {result.elapsed_s:.2f} s ({result.rate_hz:.0f} Hz) "
        f"to {output}{_health_text(result.health)}"
    )
    lines = live_end_lines(result)
    timing, health = result.timing, result.health
    if timing is not None and timing.missed_periods and health and not health.lost_packets:
        lines[0] += "; no reading lost (each cycle logs the readings buffered since the last)"
    for line in lines:
        print(line)
    if result.online_rate_source:
        print(f"online load: rate {result.online_rate_hz:.1f} Hz ({result.online_rate_source})")
        print("\n".join(event_lines(list(result.load_events))))
    if result.faulted:
        print(f"error: {result.message}; logged {summary}", file=sys.stderr)
        return 130 if result.outcome == "interrupted" else 1
    print(f"logged {summary}")
    return 0
