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

from ftcomp.cli.hardware_options import add_hardware_arguments, open_hardware
from ftcomp.errors import FtcompError, ParameterError

__all__ = ["register", "run"]

#: Readings per pose when the robot drives.
DEFAULT_SAMPLES_PER_POSE = 500


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
    parser.add_argument(
        "--samples-per-pose",
        type=int,
        metavar="N",
        help=f"readings per pose (default {DEFAULT_SAMPLES_PER_POSE}; --manual: every reading "
        "of the still period)",
    )
    parser.add_argument(
        "--position-mm",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        help="robot-driven: the sensor origin for every pose, base frame [mm] (default: where "
        "it is at the start)",
    )
    parser.add_argument(
        "--move-s", type=float, default=2.0, help="about how long a move takes [s] (default 2)"
    )
    parser.add_argument(
        "--settle-max-s",
        type=float,
        default=5.0,
        help="longest wait for the arm to rest [s] (default 5)",
    )
    parser.add_argument("--still-s", type=float, default=1.0, help="--manual: still for [s] (1)")
    parser.add_argument(
        "--min-separation-deg",
        type=float,
        default=5.0,
        help="--manual: ignore a pose closer than this to a recorded one [deg] (5)",
    )
    parser.add_argument(
        "--drift-N-Nm",
        type=float,
        nargs=2,
        default=(0.1, 0.01),
        metavar=("FORCE_N", "TORQUE_NM"),
        help="readings count as still when their mean moves less than this between the two "
        "halves of a pose's window (default 0.1 N, 0.01 N*m)",
    )
    parser.add_argument(
        "--encoding",
        choices=("quaternion", "rotvec", "paper_euler"),
        default="quaternion",
        help="orientation columns to write (default quaternion)",
    )
    parser.add_argument("--force", action="store_true", help="replace an existing output file")
    parser.set_defaults(handler=run)


def _positive(name: str, value: float) -> float:
    if not (math.isfinite(value) and value > 0.0):
        raise ParameterError(f"{name} must be > 0, got {value:g}")
    return value


class _Output:
    """The sample CSV, rewritten after every pose (see the module docstring)."""

    def __init__(self, path: Path, encoding: str) -> None:
        from ftcomp.calibration.collect_live import PoseRecord

        self.path, self.encoding = path, encoding
        self.records: list[PoseRecord] = []

    def add(self, record: object) -> None:
        from scipy.spatial.transform import Rotation

        from ftcomp.calibration.collect_live import PoseRecord, samples_from_records
        from ftcomp.io.samples_csv import write_samples

        assert isinstance(record, PoseRecord)
        self.records.append(record)
        s = samples_from_records(self.records, str(self.path))
        write_samples(
            self.path,
            s.wrench_sensor,
            Rotation.from_matrix(s.R_base_sensor),
            encoding=self.encoding,  # type: ignore[arg-type]
            pose=s.pose,
            t=s.t,
        )

    def summary(self) -> str:
        n = sum(len(r.wrench_sensor) for r in self.records)
        return f"{self.path}: {len(self.records)} poses ({n} readings)"


def _announce(record: object, number: int, total: int, note: str = "") -> None:
    from ftcomp.calibration.collect_live import PoseRecord

    assert isinstance(record, PoseRecord)
    mean, scatter = record.mean, record.scatter
    print(
        f"pose {number}/{total} ({record.pose_id}{note}): {len(record.wrench_sensor)} readings, "
        f"mean F [{mean[0]:+.3f} {mean[1]:+.3f} {mean[2]:+.3f}] N, "
        f"M [{mean[3]:+.4f} {mean[4]:+.4f} {mean[5]:+.4f}] N*m; "
        f"scatter {scatter[:3].max():.3f} N, {scatter[3:].max():.4f} N*m",
        flush=True,
    )


def _record_driven(args: argparse.Namespace, out: _Output) -> None:
    from ftcomp.calibration.collect_live import WrenchTolerance, record_poses
    from ftcomp.io.poses_csv import read_pose_file
    from ftcomp.paper import paper_poses

    poses = paper_poses() if args.poses == "paper" else read_pose_file(args.poses)
    n = args.samples_per_pose if args.samples_per_pose is not None else DEFAULT_SAMPLES_PER_POSE
    position = None if args.position_mm is None else [v * 1e-3 for v in args.position_mm]
    tolerance = WrenchTolerance(*args.drift_N_Nm)

    def on_pose(record: object) -> None:
        out.add(record)
        _announce(record, len(out.records), len(poses))

    with open_hardware(args) as (robot, sensor, mount):
        print(f"recording {len(poses)} poses of {poses.source}, {n} readings each", flush=True)
        record_poses(
            robot,
            sensor,
            poses,
            n,
            on_pose,
            mount=mount,
            position_base_m=position,
            move_duration_s=args.move_s,
            settle_max_s=args.settle_max_s,
            tolerance=tolerance,
        )


def _record_manual(args: argparse.Namespace, out: _Output) -> None:
    from ftcomp.calibration.collect_live import WrenchTolerance
    from ftcomp.calibration.collect_manual import ManualEvent, ManualRecorder, StillCriteria
    from ftcomp.control.loop import ControlCycle, run_loop

    try:
        total = int(args.poses)
    except ValueError:
        raise ParameterError(
            f"--manual needs --poses N (a number of poses), got {args.poses!r}"
        ) from None
    if total < 3:
        raise ParameterError(f"--poses must be >= 3 to separate bias from gravity, got {total}")
    criteria = StillCriteria(
        still_s=_positive("--still-s", args.still_s),
        wrench=WrenchTolerance(*args.drift_N_Nm),
        min_separation_rad=math.radians(args.min_separation_deg),
    )

    def on_event(event: ManualEvent) -> None:
        angle = math.degrees(event.angle_rad)
        if event.kind == "too_close":
            print(
                f"ignored: {angle:.1f} deg from pose {event.number} (< "
                f"{args.min_separation_deg:g} deg); move on",
                flush=True,
            )
            return
        out.add(event.record)
        note = "" if event.number == 1 else f", {angle:.0f} deg from the nearest"
        _announce(event.record, event.number, total, note)
        if event.number < total:
            print(f"move to a new pose and hold it still for {args.still_s:g} s", flush=True)

    with open_hardware(args) as (robot, sensor, mount):
        print(f"hold the arm still for {args.still_s:g} s at each of {total} poses", flush=True)
        recorder = ManualRecorder(
            sensor, total, criteria, on_event, samples_per_pose=args.samples_per_pose
        )
        run_loop(ControlCycle(robot, sensor, mount=mount), recorder)


def run(args: argparse.Namespace) -> int:
    """Record; on a fault after the first pose, keep the file and say why."""
    from ftcomp.io.atomic import check_writable

    output = check_writable(args.output, overwrite=args.force)
    for name, value in (("--move-s", args.move_s), ("--settle-max-s", args.settle_max_s)):
        _positive(name, value)
    for value in args.drift_N_Nm:
        _positive("--drift-N-Nm", value)
    if args.samples_per_pose is not None and args.samples_per_pose < 2:
        raise ParameterError(f"--samples-per-pose must be >= 2, got {args.samples_per_pose}")
    if not args.manual and args.poses.isdigit():
        raise ParameterError("--poses N needs --manual; the robot drives through paper|FILE.csv")
    out = _Output(output, args.encoding)
    try:
        (_record_manual if args.manual else _record_driven)(args, out)
    except KeyboardInterrupt:
        print(f"error: interrupted (Ctrl-C); {out.summary()}", file=sys.stderr)
        return 130
    except FtcompError as exc:
        if not out.records:
            raise
        print(f"error: {exc}; {out.summary()}", file=sys.stderr)
        return 1
    print(f"wrote {out.summary()}")
    return 0
