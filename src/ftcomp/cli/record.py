"""``ftcomp record``: calibration readings from a real (or simulated) cell, as a sample CSV.

Robot-driven: ``ftcomp record --robot URI --sensor URI --poses paper|FILE.csv -o samples.csv``
moves through the poses (blocking moves at the robot's speed limit, every pose checked before
the first move when the robot can tell), waits until arm and readings are still and records
``--samples-per-pose`` readings at each.

By hand: ``ftcomp record --manual --poses N ...``: jog or free-drive the arm; each period held
still for ``--still-s`` is recorded and announced, one too close to an earlier pose is ignored.

The file is rewritten (atomically) after every pose, so Ctrl-C, a lost connection or a sensor
fault leaves a valid file with every pose recorded so far; the command then says how many and
exits non-zero (1, or 130 for Ctrl-C).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, get_args

from ftcomp.cli.hardware_options import add_hardware_arguments, open_hardware
from ftcomp.cli.live_status import PoseProgress, add_view_arguments
from ftcomp.cli.options import add_field_option, map_field, spec_default
from ftcomp.errors import ParameterError
from ftcomp.frames import OrientationEncoding
from ftcomp.session.hand_guided import StillCriteria
from ftcomp.session.pose_record import WrenchTolerance
from ftcomp.session.record import RobotDriven

if TYPE_CHECKING:
    from ftcomp.session.pose_record import PoseEvent
    from ftcomp.session.record import HandGuided, RecordConfig

__all__ = ["register", "run"]


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``record`` command's arguments to its parser."""
    parser.description = __doc__.split("\n\n", 1)[1].replace("``", "") if __doc__ else None
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    add_hardware_arguments(parser, robot_required=True)
    parser.add_argument(
        "-o", "--output", required=True, metavar="SAMPLES.csv", help="the sample CSV to write"
    )
    parser.add_argument(
        "--poses",
        default="paper",
        metavar="paper|FILE.csv|N",
        help="robot-driven: 'paper' (the paper's 9 poses) or a pose CSV; --manual: how many "
        "poses to record",
    )
    parser.add_argument("--manual", action="store_true", help="the user moves the arm")
    add_field_option(
        parser,
        RobotDriven,
        "samples_per_pose",
        default=None,
        metavar="N",
        help="readings per pose",
        none_means=f"{spec_default(RobotDriven, 'samples_per_pose')}; --manual: every reading "
        "of the still period",
    )
    parser.add_argument(
        "--position-mm",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        help="robot-driven: the sensor origin for every pose, base frame [mm] (default: where "
        "it is at the start)",
    )
    add_field_option(parser, RobotDriven, "move_duration_s", "--move-s")
    add_field_option(parser, RobotDriven, "settle_max_s")
    add_field_option(parser, StillCriteria, "still_s", help="--manual: still for")
    add_field_option(
        parser,
        StillCriteria,
        "min_separation_rad",
        "--min-separation-deg",
        scale=math.radians(1.0),
        unit="deg",
        help="--manual: ignore a pose closer than this to a recorded one",
    )
    force_N, torque_Nm = (spec_default(WrenchTolerance, f) for f in ("force_N", "torque_Nm"))
    parser.add_argument(
        "--drift-N-Nm",
        type=float,
        nargs=2,
        default=(force_N, torque_Nm),
        metavar=("FORCE_N", "TORQUE_NM"),
        help="readings count as still when their mean moves less than this between the two "
        f"halves of a pose's window (default {force_N:g} N, {torque_Nm:g} N*m)",
    )
    for field in ("force_N", "torque_Nm"):
        map_field(parser, field, "--drift-N-Nm")
    parser.add_argument(
        "--encoding",
        choices=get_args(OrientationEncoding),
        default="quaternion",
        help="orientation columns to write (default quaternion)",
    )
    parser.add_argument("--force", action="store_true", help="replace an existing output file")
    add_view_arguments(parser)
    parser.set_defaults(handler=run)


def _poses(n: int) -> str:
    """``"1 pose"``, ``"9 poses"``."""
    return f"{n} pose" if n == 1 else f"{n} poses"


def _config(args: argparse.Namespace) -> RecordConfig:
    """The session the options ask for (checked by the library's records)."""
    from ftcomp.session.record import HandGuided, RecordConfig, RobotDriven

    tolerance = WrenchTolerance(*args.drift_N_Nm)
    plan: RobotDriven | HandGuided
    if args.manual:
        try:
            n_poses = int(args.poses)
        except ValueError:
            raise ParameterError(
                f"--manual needs --poses N (a number of poses), got {args.poses!r}"
            ) from None
        still = StillCriteria(
            still_s=args.still_s,
            wrench=tolerance,
            min_separation_rad=math.radians(args.min_separation_deg),
        )
        plan = HandGuided(n_poses, still, samples_per_pose=args.samples_per_pose)
    else:
        import numpy as np

        from ftcomp.io.poses_csv import read_pose_file
        from ftcomp.paper import paper_poses

        if args.poses.isdigit():
            raise ParameterError(
                "--poses N needs --manual; the robot drives through paper|FILE.csv"
            )
        given = {} if args.samples_per_pose is None else {"samples_per_pose": args.samples_per_pose}
        plan = RobotDriven(
            paper_poses() if args.poses == "paper" else read_pose_file(args.poses),
            **given,
            position_base_m=(
                None if args.position_mm is None else np.array(args.position_mm) * 1e-3
            ),
            move_duration_s=args.move_s,
            settle_max_s=args.settle_max_s,
            tolerance=tolerance,
        )
    return RecordConfig(Path(args.output), plan, encoding=args.encoding, overwrite=args.force)


def _announce(event: PoseEvent, plan: RobotDriven | HandGuided) -> None:
    """One line per event; by hand, what to do next."""
    from ftcomp.session.record import HandGuided

    by_hand = plan if isinstance(plan, HandGuided) else None
    angle = math.degrees(event.angle_rad)
    if event.record is None:  # a hand-guided still period too close to a recorded pose
        limit_deg = math.degrees(by_hand.still.min_separation_rad) if by_hand else 0.0
        print(
            f"ignored: {angle:.1f} deg from pose {event.number} (< {limit_deg:g} deg); move on",
            flush=True,
        )
        return
    note = f", {angle:.0f} deg from the nearest" if by_hand and event.number > 1 else ""
    record = event.record
    mean, scatter = record.mean, record.scatter
    print(
        f"pose {event.number}/{plan.n_poses} ({record.pose_id}{note}): "
        f"{len(record.wrench_sensor)} readings, "
        f"mean F [{mean[0]:+.3f} {mean[1]:+.3f} {mean[2]:+.3f}] N, "
        f"M [{mean[3]:+.4f} {mean[4]:+.4f} {mean[5]:+.4f}] N*m; "
        f"scatter {scatter[:3].max():.3f} N, {scatter[3:].max():.4f} N*m",
        flush=True,
    )
    if by_hand and event.number < plan.n_poses:
        print(f"move to a new pose and hold it still for {by_hand.still.still_s:g} s", flush=True)


def run(args: argparse.Namespace) -> int:
    """Record; on a fault after the first pose, keep the file and say why."""
    from ftcomp.io.atomic import check_writable
    from ftcomp.session.record import RobotDriven, record
    from ftcomp.views.live import session_observers

    check_writable(args.output, overwrite=args.force)  # before connecting to anything
    if args.log is not None:
        check_writable(args.log, overwrite=args.force, inputs=[args.output])
    config = _config(args)
    plan = config.plan
    if isinstance(plan, RobotDriven):
        intro = (
            f"recording {_poses(plan.n_poses)} of {plan.poses.source}, "
            f"{plan.samples_per_pose} readings each"
        )
    else:
        intro = f"hold the arm still for {plan.still.still_s:g} s at each of {_poses(plan.n_poses)}"
    with (
        session_observers(args.log, args.view, overwrite=args.force) as observers,
        open_hardware(args) as (robot, sensor, mount),
    ):
        print(intro, flush=True)
        progress = PoseProgress("poses", plan.n_poses)

        def on_event(event: PoseEvent) -> None:
            _announce(event, plan)
            if event.record is not None:
                progress.advance()

        def on_skip(line: str) -> None:
            print(f"warning: {line}", file=sys.stderr, flush=True)

        try:
            result = record(
                robot,
                sensor,
                config,
                mount=mount,
                on_event=on_event,
                observers=observers,
                on_skip=on_skip,
            )
        finally:
            progress.close()
    summary = f"{result.output}: {_poses(result.poses_recorded)} ({result.readings} readings)"
    if result.timing is not None:
        print(result.timing.line())
    if result.ended == "complete":
        print(f"wrote {summary}")
        return 0
    print(f"error: {result.reason}; {summary}", file=sys.stderr)
    return 130 if result.ended == "interrupted" else 1
