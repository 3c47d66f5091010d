"""``ftcomp poses design --count N -o poses.csv [--robot URI | --urdf FILE] [--max-tilt-deg D]
[--keep FILE]``."""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import math
import sys
from collections.abc import Callable
from pathlib import Path

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
from ftcomp.calibration.reachable_design import (
    Reachability,
    Visit,
    design_reachable_poses,
    plan_visit,
)
from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import ChecksReachability, MovesInJointSpace, Robot
from ftcomp.io.atomic import atomic_write_text, check_writable
from ftcomp.samples import PoseList

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
            "poses'. The CSV (pose,qx,qy,qz,qw; with --robot or --urdf also x_m,y_m,z_m, the "
            "position the poses were checked at) is a --poses file for sim collect and record."
        ),
    )
    design.add_argument(
        "--count", type=int, required=True, metavar="N", help="how many new poses (required)"
    )
    design.add_argument(
        "-o", "--output", required=True, metavar="POSES.csv", help="the pose file to write"
    )
    reach = design.add_mutually_exclusive_group()
    reach.add_argument(
        "--robot",
        metavar="URI",
        help="keep only poses this robot reaches by its own check (a robot that has one: "
        "sim://..., ur://HOST), its TCP taken as the sensor frame, at --position-mm or where "
        "the TCP is now; the file then lists that position (default: no reachability check)",
    )
    reach.add_argument(
        "--urdf",
        metavar="ROBOT.urdf",
        help="keep only poses this robot description reaches: inverse kinematics of the chain "
        "from --base-link to --tip-link within the URDF's joint limits, the tip at "
        "--position-mm; the file then lists that position (x_m,y_m,z_m) (default: no "
        "reachability check)",
    )
    design.add_argument(
        "--base-link",
        metavar="LINK",
        help="with --urdf: the robot's base link, the frame of the poses (default: the URDF's "
        "root link)",
    )
    design.add_argument(
        "--tip-link",
        metavar="LINK",
        help="with --urdf: the sensor's measuring frame, whose orientations the file lists "
        "(default: the URDF's one leaf link that a movable joint leads to)",
    )
    design.add_argument(
        "--position-mm",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        help="with --urdf or --robot: the tip's origin for every pose, base frame [mm], as "
        "record's --position-mm (default with --robot: where the TCP is now; with --urdf: in "
        "front of the robot at shoulder height, half the chain's length from the first joint "
        "towards the tip at the zero configuration, or, if out of reach, the tip at the middle "
        "of every joint's range; printed)",
    )
    design.add_argument(
        "--max-tilt-deg",
        type=float,
        default=180.0,
        metavar="D",
        help="largest angle of the sensor's z axis from straight down [deg] (default: 180, any)",
    )
    design.add_argument(
        "--max-spin-deg",
        type=float,
        default=90.0,
        metavar="D",
        help="largest turn of the sensor about its own axis from the orientation tilting it "
        "straight from down gives [deg] (default: 90, a half-turn band: a robot's last wrist "
        "joint then does not wind to its limit along the moves from pose to pose; 180: any)",
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


def _position_m(position_mm: list[float]) -> NDArray[np.float64]:
    """``--position-mm X Y Z`` as metres."""
    p = np.array(position_mm) / 1000.0
    if not np.isfinite(p).all():
        raise ParameterError(f"--position-mm {position_mm}: need three finite numbers X Y Z [mm]")
    return p


def _urdf_reach(args: argparse.Namespace) -> tuple[Reachability, str]:
    """The reach check by the URDF chain's inverse kinematics, and its description."""
    from ftcomp.chain_ik import ChainIk, mid_configuration
    from ftcomp.ros2.urdf import UrdfChain
    from ftcomp.ros2.urdf_ik import front_position

    chain = UrdfChain(args.urdf, args.base_link, args.tip_link)
    ik = ChainIk(chain)
    given = args.position_mm is not None
    p = _position_m(args.position_mm) if given else front_position(chain)
    if not given and ik.solve(p) is None:  # a short or odd chain
        p = ik.pose(mid_configuration(chain))[0]
    if ik.solve(p) is None:
        where = (
            "--position-mm " + " ".join(f"{v:g}" for v in args.position_mm)
            if given
            else "the default position"
        )
        raise ParameterError(
            f"{where} {np.round(p, 4).tolist()} m: the tip link {chain.tip_link!r} "
            f"of {args.urdf} cannot reach it within the joint limits"
        )
    reach = Reachability(
        lambda p, R: ik.solve(p, R) is not None,
        p,
        source=f"--urdf {chain.source}",
        who="the URDF's inverse kinematics",
    )
    describe = (
        f"{chain.source}, {chain.base_link} -> {chain.tip_link} ({len(chain.joint_names)} joints)"
    )
    return reach, describe


def _robot_visit(robot: Robot) -> Callable[..., Visit] | None:
    """The visit check of a robot that moves in joint space, from its joints now."""
    if not isinstance(robot, MovesInJointSpace):
        return None
    q_start = robot.joint_positions_rad()
    return lambda p, R: plan_visit(p, R, q_start, robot.inverse_kinematics)


def _robot_reach(args: argparse.Namespace, robot: Robot) -> tuple[Reachability, str]:
    """The reach check by the robot's own (its TCP taken as the sensor frame)."""
    if not isinstance(robot, ChecksReachability):
        raise ParameterError(
            f"--robot {args.robot}: this robot cannot check whether it reaches a pose "
            "(sim://... and ur://HOST can); give one of those, or --urdf ROBOT.urdf"
        )
    given = args.position_mm is not None
    # Where the TCP is now, to the micrometre the pose file keeps (and without a -0).
    p = _position_m(args.position_mm) if given else np.round(robot.pose().p_base_tcp, 6) + 0.0
    reach = Reachability(robot.is_reachable, p, source=f"--robot {args.robot}", who=args.robot)
    return reach, args.robot


def _csv(R: NDArray[np.float64], ids: list[str], p: NDArray[np.float64] | None) -> str:
    """The pose file; with positions ``p`` (N, 3) [m] also ``x_m,y_m,z_m``."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    at = ["x_m", "y_m", "z_m"] if p is not None else []
    writer.writerow(["pose", "qx", "qy", "qz", "qw", *at, "tilt_deg"])
    quat = Rotation.from_matrix(R).as_quat(canonical=True)
    for k, (pid, q, tilt) in enumerate(
        zip(ids, quat, np.degrees(tilt_from_down_rad(R)), strict=True)
    ):
        xyz = [f"{v:.6f}" for v in p[k]] if p is not None else []
        writer.writerow([pid, *(f"{v:.12f}" for v in q), *xyz, f"{tilt:.3f}"])
    return out.getvalue()


def _se_text(se: NDArray[np.float64], name: str) -> str:
    unit, scale = _UNITS[name]
    return ", ".join(f"{v * scale:.3g}" for v in se) + f" {unit}"


def run(args: argparse.Namespace) -> int:
    """Design, order, write, print the predicted standard errors (with ``--robot``, the robot is
    open, as a context manager, until the design is written)."""
    from ftcomp.io.poses_csv import read_pose_file

    for flag in ("base_link", "tip_link"):
        if getattr(args, flag) is not None and args.urdf is None:
            raise ParameterError(f"--{flag.replace('_', '-')} needs --urdf")
    if args.position_mm is not None and args.urdf is None and args.robot is None:
        raise ParameterError("--position-mm needs --urdf or --robot")
    inputs = [f for f in (args.keep, args.urdf) if f]
    output = check_writable(args.output, overwrite=args.force, inputs=inputs)
    kept = read_pose_file(args.keep) if args.keep else None
    with contextlib.ExitStack() as stack:
        reach: tuple[Reachability, str] | None = None
        visit = None
        if args.urdf:
            reach = _urdf_reach(args)
        elif args.robot:
            from ftcomp.hardware.registry import open_robot

            robot = stack.enter_context(open_robot(args.robot))
            reach = _robot_reach(args, robot)
            visit = _robot_visit(robot)
        return _design(args, output, kept, reach, visit)


def _design(
    args: argparse.Namespace,
    output: Path,
    kept: PoseList | None,
    reach_described: tuple[Reachability, str] | None,
    visit: Callable[..., Visit] | None = None,
) -> int:
    """Design ``args.count`` poses after ``kept``, write them to ``output``, print; with
    ``visit`` (a robot that moves in joint space), in the order of a visit checked from the
    arm's joints now, any pose it cannot reach left out with a line."""
    from ftcomp import paper

    R_keep = kept.rotations.as_matrix().reshape(-1, 3, 3) if kept is not None else None
    theta = nominal_theta()
    candidates = candidate_orientations(args.max_tilt_deg, max_spin_deg=args.max_spin_deg)
    reach = reach_described[0] if reach_described is not None else None
    if reach is None:
        designed = design_poses(args.count, candidates, theta, keep=R_keep)
    else:
        designed = design_reachable_poses(args.count, candidates, theta, keep=R_keep, reach=reach)
    n_keep = 0 if R_keep is None else len(R_keep)
    R_all = designed if R_keep is None else np.concatenate([R_keep, designed])
    order = order_for_travel(R_all, fixed_prefix=n_keep)
    R_all = R_all[order]
    taken = set(kept.ids) if kept is not None else set()
    fresh = (f"d{k}" for k in range(1, args.count + len(taken) + 1) if f"d{k}" not in taken)
    ids = [*(kept.ids if kept is not None else ()), *(next(fresh) for _ in range(args.count))]
    ids = [ids[i] for i in order]
    p_all = None  # with a reach check: where each pose is reached (kept poses: their own)
    if reach is not None:
        p_all = np.tile(reach.p, (len(R_all), 1))
        if kept is not None and kept.positions_base_m is not None:
            p_all[:n_keep] = kept.positions_base_m
        p_all = p_all[order]
    checked = None
    if visit is not None and p_all is not None:
        checked = visit(p_all, R_all)
        for i, why in checked.left_out:
            print(f"warning: pose {ids[i]} left out: {why}", file=sys.stderr)
        keep_order = list(checked.order)
        R_all, p_all = R_all[keep_order], p_all[keep_order]
        ids = [ids[i] for i in keep_order]
    atomic_write_text(output, _csv(R_all, ids, p_all))
    ours = predicted_std_errors(R_all, theta)
    theirs = predicted_std_errors(paper.paper_poses().rotations.as_matrix(), theta)
    print(
        f"{len(R_all)} poses ({n_keep} kept, {args.count} designed, max tilt "
        f"{np.degrees(tilt_from_down_rad(R_all)).max():.1f} deg) written to {output}"
    )
    if reach_described is not None and p_all is not None:
        reach, describe = reach_described
        print(reach.summary(describe))
        if checked is not None:
            print(
                f"visit: {len(checked.order)} poses by joint moves from the arm's joints now, "
                "each to the inverse kinematics nearest the joints before it, every joint within "
                f"its range (largest joint move {math.degrees(checked.largest_move_rad):.0f} deg)"
            )
        for pid, R, p in zip(ids, R_all, p_all, strict=True):
            if pid in taken and not reach.reaches(p, R):
                print(
                    f"warning: kept pose {pid}: {reach.who} does not reach it "
                    f"with the tip at {np.round(p, 4).tolist()} m",
                    file=sys.stderr,
                )
    print("predicted standard errors, joint method, 500 readings per pose at the paper's noise:")
    print(f"  {'parameter':<10} {'these poses':<36} the paper's 9 poses")
    for name in PARAMETER_NAMES:
        print(f"  {name:<10} {_se_text(ours[name], name):<36} {_se_text(theirs[name], name)}")
    return 0
