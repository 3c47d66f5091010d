"""``ftcomp poses design --count N -o poses.csv [--robot URI] [--max-tilt-deg D] [--keep FILE]``."""

from __future__ import annotations

import argparse
import csv
import io
import math

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.calibration.design import (
    PARAMETER_NAMES,
    candidate_orientations,
    design_poses,
    nominal_theta,
    order_for_travel,
    predicted_std_errors,
    tilt_from_down_rad,
)
from ftcomp.errors import FtcompError, ParameterError
from ftcomp.io.atomic import atomic_write_text, check_writable

__all__ = ["register"]

_UNITS = {"G": ("N", 1.0), "F0": ("N", 1.0), "M0": ("N·m", 1.0), "P": ("mm", 1000.0)}


def register(parser: argparse.ArgumentParser) -> None:
    """Add ``poses design`` and its arguments."""
    parser.description = "Calibration poses: design a set before recording."
    commands = parser.add_subparsers(
        dest="poses_command", metavar="POSES_COMMAND", required=True, help="design: a pose set"
    )
    design = commands.add_parser(
        "design",
        help="choose N orientations that minimise the joint method's parameter uncertainty",
        description=(
            "Choose N orientations that make the joint method's estimates of bias, weight, "
            "centre of gravity and tilt most precise (D-optimal on its Fisher information, "
            "greedy plus exchange), reachable by the robot, ordered to keep the travel short; "
            "prints the predicted standard error of every parameter beside the paper's nine "
            "poses'. The CSV (pose,qx,qy,qz,qw) is a --poses file for sim collect and record."
        ),
    )
    design.add_argument(
        "--count", type=int, required=True, metavar="N", help="how many new poses (required)"
    )
    design.add_argument(
        "-o", "--output", required=True, metavar="POSES.csv", help="the pose file to write"
    )
    design.add_argument(
        "--robot",
        metavar="URI",
        help="keep only poses this robot reaches (inverse kinematics within joint limits at "
        "the collection position; sim://...) (default: no reachability check)",
    )
    design.add_argument(
        "--max-tilt-deg",
        type=float,
        default=180.0,
        metavar="D",
        help="largest angle of the sensor's z axis from straight down [deg] (default: 180, any)",
    )
    design.add_argument(
        "--keep",
        metavar="FILE.csv",
        help="poses already recorded (a pose or sample file): the design extends them",
    )
    design.add_argument(
        "--force", action="store_true", help="replace an existing -o file (default: refuse)"
    )
    design.set_defaults(handler=run)


def _reachability(uri: str):  # type: ignore[no-untyped-def]
    """A check ``R -> bool`` by the robot's inverse kinematics, and the robot to close."""
    from ftcomp.hardware.registry import open_robot
    from ftcomp.sim.cell import COLLECTION_POSITION_BASE_M, SimCell

    robot = open_robot(uri)
    if not isinstance(robot, SimCell):
        robot.__exit__(None, None, None)
        raise ParameterError(
            f"--robot {uri}: the reachability check needs the simulated robot (sim://...)"
        )

    def reachable(R: NDArray[np.float64]) -> bool:
        try:
            robot.solve_ik(np.array(COLLECTION_POSITION_BASE_M), R)
        except FtcompError:
            return False
        return True

    return reachable, robot


def _csv(R: NDArray[np.float64], ids: list[str]) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["pose", "qx", "qy", "qz", "qw", "tilt_deg"])
    quat = Rotation.from_matrix(R).as_quat(canonical=True)
    for pid, q, tilt in zip(ids, quat, np.degrees(tilt_from_down_rad(R)), strict=True):
        writer.writerow([pid, *(f"{v:.12f}" for v in q), f"{tilt:.3f}"])
    return out.getvalue()


def _se_text(se: NDArray[np.float64], name: str) -> str:
    unit, scale = _UNITS[name]
    return ", ".join(f"{v * scale:.3g}" for v in se) + f" {unit}"


def run(args: argparse.Namespace) -> int:
    """Design, order, write, print the predicted standard errors."""
    from ftcomp import paper
    from ftcomp.io.poses_csv import read_pose_file

    if args.count < 1:
        raise ParameterError(f"--count {args.count}: must be at least 1")
    if not math.isfinite(args.max_tilt_deg) or not 0.0 < args.max_tilt_deg <= 180.0:
        raise ParameterError(f"--max-tilt-deg {args.max_tilt_deg:g}: must be in (0, 180]")
    inputs = [args.keep] if args.keep else []
    output = check_writable(args.output, overwrite=args.force, inputs=inputs)
    kept = read_pose_file(args.keep) if args.keep else None
    R_keep = kept.rotations.as_matrix().reshape(-1, 3, 3) if kept is not None else None
    theta = nominal_theta()
    candidates = candidate_orientations(args.max_tilt_deg)
    reachable, robot = _reachability(args.robot) if args.robot else (None, None)
    try:
        designed = design_poses(args.count, candidates, theta, keep=R_keep, reachable=reachable)
    finally:
        if robot is not None:
            robot.__exit__(None, None, None)
    n_keep = 0 if R_keep is None else len(R_keep)
    R_all = designed if R_keep is None else np.concatenate([R_keep, designed])
    order = order_for_travel(R_all, fixed_prefix=n_keep)
    R_all = R_all[order]
    taken = set(kept.ids) if kept is not None else set()
    fresh = (f"d{k}" for k in range(1, args.count + len(taken) + 1) if f"d{k}" not in taken)
    ids = [*(kept.ids if kept is not None else ()), *(next(fresh) for _ in range(args.count))]
    ids = [ids[i] for i in order]
    atomic_write_text(output, _csv(R_all, ids))
    ours = predicted_std_errors(R_all, theta)
    theirs = predicted_std_errors(paper.paper_poses().rotations.as_matrix(), theta)
    print(
        f"{len(R_all)} poses ({n_keep} kept, {args.count} designed, max tilt "
        f"{np.degrees(tilt_from_down_rad(R_all)).max():.1f} deg) written to {output}"
    )
    print("predicted standard errors, joint method, 500 readings per pose at the paper's noise:")
    print(f"  {'parameter':<10} {'these poses':<36} the paper's 9 poses")
    for name in PARAMETER_NAMES:
        print(f"  {name:<10} {_se_text(ours[name], name):<36} {_se_text(theirs[name], name)}")
    return 0
