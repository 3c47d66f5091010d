"""``ftcomp sim collect``: static calibration readings from the simulated cell, with the truth.

``ftcomp sim collect --poses paper|FILE.csv --samples-per-pose 500 [--load-kg X]
[--tilt-deg U V] [--no-gripper] [--seed N] -o samples.csv [--truth truth.json]``
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from scipy.spatial.transform import Rotation

from ftcomp import paper
from ftcomp.cli.options import add_field_option
from ftcomp.errors import ParameterError
from ftcomp.frames import ENCODING_COLUMNS
from ftcomp.io.atomic import atomic_write_text, check_writable
from ftcomp.io.calibration_json import model_to_dict
from ftcomp.io.samples_csv import write_samples
from ftcomp.session.record import RobotDriven
from ftcomp.sim.cell_config import CellConfig

__all__ = ["register", "robot_uri", "run"]


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``collect`` command's arguments to its parser."""
    parser.description = (
        "Drive the simulated arm to each pose, wait until it is still and record the F/T "
        "sensor's readings (sample CSV for 'ftcomp calibrate'); with --truth, also write the "
        "parameters the cell was built with, to score a calibration against."
    )
    parser.add_argument(
        "--poses",
        default="paper",
        metavar="paper|FILE.csv",
        help="'paper' for the 9 poses of the paper's Table 1, or a CSV with one orientation "
        "encoding's columns (as in the sample CSV), an optional pose column and optional "
        "x_m,y_m,z_m sensor positions [m] (default: paper)",
    )
    add_field_option(
        parser,
        RobotDriven,
        "samples_per_pose",
        metavar="N",
        help="readings recorded at each pose (as many as the paper by default), at the sensor's "
        "1.2 kHz",
    )
    add_field_option(
        parser,
        CellConfig,
        "load_kg",
        metavar="X",
        help="a load to grasp",
        none_means="none, the empty gripper",
    )
    add_field_option(
        parser,
        CellConfig,
        "tilt_deg",
        nargs=2,
        default=paper.TILT_DEG,
        metavar=("U", "V"),
        help="base mounting tilt, R_world_base = Rx(U) Ry(V), the paper's by default",
    )
    parser.add_argument(
        "--no-gripper",
        action="store_true",
        help="the bare sensing end, to measure its own weight (default: with the gripper)",
    )
    add_field_option(parser, CellConfig, "seed")
    parser.add_argument(
        "--encoding",
        choices=tuple(ENCODING_COLUMNS),
        default="paper_euler",
        help="orientation columns to write: quaternion qx,qy,qz,qw; rotvec rx,ry,rz [rad]; "
        "paper_euler alpha_deg,beta_deg,gamma_deg (default: paper_euler)",
    )
    parser.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="SAMPLES.csv",
        help="the sample CSV to write (required)",
    )
    parser.add_argument(
        "--truth",
        metavar="TRUTH.json",
        help="also write the cell's true parameters under the calibration-file keys, with a "
        "'simulation' section; not a calibration file (nothing was identified): read it with "
        "ftcomp.io.calibration_json.model_from_dict (default: not written)",
    )
    parser.add_argument(
        "--force", action="store_true", help="replace existing output files (default: refuse)"
    )
    parser.set_defaults(handler=run)


def _check_args(args: argparse.Namespace) -> None:
    if args.load_kg is not None and args.no_gripper:
        raise ParameterError("--load-kg needs the gripper: drop --no-gripper")
    if args.truth is not None and Path(args.output).resolve() == Path(args.truth).resolve():
        raise ParameterError(f"-o and --truth are the same file: {args.output}")


def robot_uri(args: argparse.Namespace) -> str:
    """The ``sim://`` robot URI these options describe."""
    options = [f"tilt_deg={args.tilt_deg[0]!r},{args.tilt_deg[1]!r}", f"seed={args.seed}"]
    if args.no_gripper:
        options.append("gripper=0")
    if args.load_kg is not None:
        options.append(f"load_kg={args.load_kg!r}&grasp=1")
    return "sim://?" + "&".join(options)


def run(args: argparse.Namespace) -> int:
    """``record`` on ``sim://``: open the cell by URI, record through the protocols, write the
    samples and the truth."""
    from ftcomp.hardware.registry import open_robot, open_sensor
    from ftcomp.io.poses_csv import read_pose_file
    from ftcomp.io.truth_json import TRUTH_HEADER
    from ftcomp.paper import paper_poses
    from ftcomp.sim.collect import record_with_truth

    _check_args(args)
    inputs = [] if args.poses == "paper" else [args.poses]
    samples_path = check_writable(args.output, overwrite=args.force, inputs=inputs)
    truth_path = None
    if args.truth is not None:
        truth_path = check_writable(args.truth, overwrite=args.force, inputs=inputs)
    poses = paper_poses() if args.poses == "paper" else read_pose_file(args.poses)
    uri = robot_uri(args)
    with open_robot(uri) as robot, open_sensor("sim://", robot):
        from ftcomp.sim.backend import as_sim_cell

        cell = as_sim_cell(robot, "sim collect (the ground truth)")
        samples, truth_model = record_with_truth(cell, poses, args.samples_per_pose)
        spec = cell.sensor.spec
        sensing_end_N = cell.config.tool.sensing_end_weight_N
    write_samples(
        samples_path,
        samples.wrench_sensor,
        Rotation.from_matrix(samples.R_base_sensor),
        encoding=args.encoding,
        pose=samples.pose,
        t=samples.t,
    )
    where = f"{len(samples)} readings at {len(poses)} poses to {samples_path}"
    if truth_path is None:
        print(f"wrote {where}")
        return 0
    truth: dict[str, Any] = {**TRUTH_HEADER, **model_to_dict(truth_model)}
    truth["simulation"] = {
        "robot": uri,
        "poses": poses.source,
        "pose_ids": list(poses.ids),
        "samples_per_pose": args.samples_per_pose,
        "seed": args.seed,
        "gripper": not args.no_gripper,
        "load_kg": args.load_kg,
        "sensing_end_weight_N": sensing_end_N,
        "sensor_noise_std": [spec.force_noise_std_N, spec.torque_noise_std_Nm],
        "sensor_resolution_fraction_of_range": spec.resolution_fraction_of_range,
    }
    atomic_write_text(truth_path, json.dumps(truth, indent=2, allow_nan=False) + "\n")
    print(f"wrote {where}; truth to {truth_path}")
    return 0
