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
import csv
import math
import sys

from ftcomp.cli.common import warn_live_drift
from ftcomp.cli.hardware_options import add_hardware_arguments, open_hardware
from ftcomp.cli.live_status import StatusLine
from ftcomp.errors import FtcompError, ParameterError

#: How long the readings' rate is measured when --online-rate-hz is not given [s]: the value of
#: ftcomp.experiments.live_load.MEASURE_RATE_S (a test checks), here so --help needs no numpy.
_MEASURE_S = 0.5

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
    parser.add_argument(
        "--online-rate-hz",
        type=float,
        metavar="HZ",
        help="the sensor's sample rate, which times the grasp detector's windows [Hz] (default: "
        f"measured from the stamps of the first {_MEASURE_S:g} s of readings, held back and "
        "then logged)",
    )
    parser.add_argument("--seconds", type=float, required=True, help="how long to log [s]")
    parser.add_argument(
        "-o", "--output", required=True, metavar="LOG.csv", help="the log, one row per reading"
    )
    parser.add_argument("--force", action="store_true", help="replace an existing output file")
    parser.set_defaults(handler=run)


def _check_online(args: argparse.Namespace) -> None:
    if args.online_rate_hz is not None and not args.online_load:
        raise ParameterError("--online-rate-hz needs --online-load")
    if args.online_load and not args.calibration:
        raise ParameterError(
            "--online-load needs the tool's calibration: give -c CALIBRATION.json "
            "(from ftcomp calibrate)"
        )
    rate = args.online_rate_hz
    if rate is not None and not (math.isfinite(rate) and 0.0 < rate <= 100_000.0):
        raise ParameterError(f"--online-rate-hz must be in (0, 100000] Hz, got {rate:g}")


def _health_text(sensor: object) -> str:
    health = getattr(sensor, "stream_health", None)
    if health is None:
        return ""
    h = health()
    return (
        f"; lost {h['lost_packets']} packets of {h['received'] + h['lost_packets']} "
        f"(last RDT sequence {h['last_rdt_sequence']})"
    )


def run(args: argparse.Namespace) -> int:
    """Open, log until the time is up (or a fault), report."""
    from ftcomp.compensation.compensator import GravityCompensator
    from ftcomp.control.loop import ControlCycle, run_loop
    from ftcomp.experiments.live import StreamLogger, stream_columns
    from ftcomp.experiments.live_load import StreamLoad, event_lines, require_tool_weight
    from ftcomp.hardware.pacing import CountsLostPackets
    from ftcomp.hardware.replay import EndOfReplayError
    from ftcomp.io.atomic import atomic_output, check_writable
    from ftcomp.io.calibration_json import load_calibration
    from ftcomp.io.timestamps import format_row

    if not (math.isfinite(args.seconds) and args.seconds > 0.0):
        raise ParameterError(f"--seconds must be > 0, got {args.seconds:g}")
    _check_online(args)
    inputs = [args.calibration] if args.calibration else []
    output = check_writable(args.output, overwrite=args.force, inputs=inputs)
    calibration = load_calibration(args.calibration) if args.calibration else None
    if calibration is not None:
        warn_live_drift(calibration, args.calibration)
    model = calibration.model if calibration is not None else None
    if args.online_load and calibration is not None:
        require_tool_weight(calibration, args.calibration)
    if model is not None and args.robot is None:
        raise ParameterError(
            "compensation (-c) needs the sensor's pose: give --robot (ur://HOST, "
            "fixed://?rpy_deg=R,P,Y for a sensor held still, ...)"
        )
    fault, code = "", 0

    def check_pose(robot: object) -> None:
        if model is not None and not getattr(robot, "pose_known", True):
            raise ParameterError(
                f"{args.robot}: gives no pose to compensate with: add ?rpy_deg=R,P,Y (and xyz_mm)"
            )

    with open_hardware(args, check_pose) as (robot, sensor, mount):
        with_pose = args.robot is not None and getattr(robot, "pose_known", True)
        compensator = GravityCompensator(model) if model is not None else None
        online = None
        if args.online_load and calibration is not None:
            online = StreamLoad(calibration, args.online_rate_hz)
            compensator = None
        with atomic_output(output) as tmp, tmp.open("w", encoding="utf-8", newline="") as handle:
            writer = csv.writer(handle, lineterminator="\n")
            writer.writerow(
                stream_columns(
                    with_pose=with_pose,
                    compensated=model is not None,
                    online_load=online is not None,
                )
            )

            def write_row(row: object) -> None:
                writer.writerow(format_row(row))  # type: ignore[arg-type]

            logger = StreamLogger(
                sensor,
                write_row,
                args.seconds,
                with_pose=with_pose,
                compensator=compensator,
                online=online,
            )
            lost = sensor.lost_packets if isinstance(sensor, CountsLostPackets) else None
            status = StatusLine(
                lambda: logger.count,
                (lambda: sensor.lost_packets) if lost is not None else None,  # type: ignore[attr-defined]
                lambda: logger.contact_force_N,
                lambda: logger.elapsed_s,
                args.seconds,
                extra=online.status_text if online is not None else None,
            )
            cycle = ControlCycle(robot, sensor, mount=mount)  # the logger compensates
            try:
                run_loop(cycle, logger, sinks=[status])
            except EndOfReplayError:
                pass  # the recording ended: a normal end
            except KeyboardInterrupt:
                fault, code = "interrupted (Ctrl-C)", 130
            except FtcompError as exc:
                fault, code = str(exc), 1
            finally:
                logger.finish()
                status.close()
        health = _health_text(sensor)
    rate = logger.count / logger.elapsed_s if logger.elapsed_s > 0 else math.nan
    summary = (
        f"{logger.count} readings in {logger.elapsed_s:.2f} s ({rate:.0f} Hz) to {output}{health}"
    )
    if online is not None and online.rate_source:
        print(f"online load: rate {online.rate_Hz:.1f} Hz ({online.rate_source})")
        print("\n".join(event_lines(online.events)))
    if fault:
        print(f"error: {fault}; logged {summary}", file=sys.stderr)
        return code
    print(f"logged {summary}")
    return 0
