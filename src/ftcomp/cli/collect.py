"""``ftcomp sim collect``: static calibration readings from the simulated cell, with the truth.

``ftcomp sim collect --poses paper|FILE.csv --samples-per-pose 500 [--load-kg X]
[--tilt-deg U V] [--no-gripper] [--seed N] -o samples.csv --truth truth.json``
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

from ftcomp.errors import ParameterError
from ftcomp.frames import ENCODING_COLUMNS
from ftcomp.io.atomic import atomic_write_text, check_writable
from ftcomp.io.calibration_file import model_to_dict
from ftcomp.io.samples import write_samples
from ftcomp.sim.cell import SimCell
from ftcomp.sim.collect import collect_static_samples, paper_poses, read_pose_file
from ftcomp.sim.scene import SceneConfig
from ftcomp.sim.sensor import SensorSpec
from ftcomp.sim.tool import LoadSpec

__all__ = ["PAPER_TILT_DEG", "register", "run"]

#: The paper's identified base tilt (U, V) [deg]: the default mounting of the simulated arm.
PAPER_TILT_DEG = (-0.204, -0.129)
#: Largest load the simulated arm takes [kg] (the C4-A901S is rated for 4 kg).
_MAX_LOAD_KG = 4.0


def register(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``collect`` command to the ``sim`` group."""
    parser = commands.add_parser(
        "collect",
        help="record static calibration readings in the simulated cell",
        description="Drive the simulated arm to each pose, wait until it is still, record the "
        "F/T sensor's readings (sample CSV) and write the true parameters (calibration-file "
        "keys).",
    )
    parser.add_argument(
        "--poses",
        default="paper",
        metavar="paper|FILE.csv",
        help="'paper' for the 9 poses of the paper's Table 1, or a CSV with one orientation "
        "encoding's columns (as in the sample CSV) and an optional pose column",
    )
    parser.add_argument("--samples-per-pose", type=int, default=500, metavar="N")
    parser.add_argument("--load-kg", type=float, metavar="X", help="grasp a load of X kg")
    parser.add_argument(
        "--tilt-deg",
        type=float,
        nargs=2,
        default=PAPER_TILT_DEG,
        metavar=("U", "V"),
        help="base mounting tilt [deg] (default: the paper's -0.204 -0.129)",
    )
    parser.add_argument(
        "--no-gripper", action="store_true", help="bare sensing end (measures its weight)"
    )
    parser.add_argument("--seed", type=int, default=0, help="sensor-noise seed (default 0)")
    parser.add_argument(
        "--encoding",
        choices=tuple(ENCODING_COLUMNS),
        default="paper_euler",
        help="orientation columns to write (default: the paper's angles)",
    )
    parser.add_argument("-o", "--output", required=True, metavar="SAMPLES.csv")
    parser.add_argument("--truth", required=True, metavar="TRUTH.json")
    parser.add_argument("--force", action="store_true", help="replace existing output files")
    parser.set_defaults(handler=run)


def _check_args(args: argparse.Namespace) -> None:
    if args.samples_per_pose < 1:
        raise ParameterError(f"--samples-per-pose must be >= 1, got {args.samples_per_pose}")
    if args.load_kg is not None:
        if not math.isfinite(args.load_kg) or not 0.0 < args.load_kg <= _MAX_LOAD_KG:
            raise ParameterError(f"--load-kg must be in (0, {_MAX_LOAD_KG}], got {args.load_kg}")
        if args.no_gripper:
            raise ParameterError("--load-kg needs the gripper: drop --no-gripper")
    for name, value in zip(("U", "V"), args.tilt_deg, strict=True):
        if not math.isfinite(value) or abs(value) >= 30.0:
            raise ParameterError(f"--tilt-deg {name}={value} must be within +-30 deg")
    if Path(args.output).resolve() == Path(args.truth).resolve():
        raise ParameterError(f"-o and --truth are the same file: {args.output}")


def run(args: argparse.Namespace) -> int:
    """Build the cell, collect, write the samples and the truth."""
    _check_args(args)
    samples_path = check_writable(args.output, overwrite=args.force)
    truth_path = check_writable(args.truth, overwrite=args.force)
    poses = paper_poses() if args.poses == "paper" else read_pose_file(args.poses)
    load = LoadSpec(args.load_kg) if args.load_kg is not None else None
    config = SceneConfig(
        tilt_U_rad=math.radians(args.tilt_deg[0]),
        tilt_V_rad=math.radians(args.tilt_deg[1]),
        gripper=not args.no_gripper,
        load=load,
    )
    spec = SensorSpec()
    cell = SimCell(config, spec, seed=args.seed)
    if load is not None:
        cell.grasp()
    data = collect_static_samples(cell, poses, args.samples_per_pose)
    write_samples(
        samples_path,
        data.wrench_sensor,
        data.rotations,
        encoding=args.encoding,
        pose=data.pose_ids,
        t=data.t,
    )
    truth: dict[str, Any] = model_to_dict(data.truth)
    truth["simulation"] = {
        "poses": poses.source,
        "pose_ids": list(poses.ids),
        "samples_per_pose": args.samples_per_pose,
        "seed": args.seed,
        "gripper": not args.no_gripper,
        "load_kg": args.load_kg,
        "sensing_end_weight_N": config.tool.sensing_end_weight_N,
        "sensor_noise_std": [spec.force_noise_std_N, spec.torque_noise_std_Nm],
        "sensor_resolution_fraction_of_range": spec.resolution_fraction_of_range,
    }
    atomic_write_text(truth_path, json.dumps(truth, indent=2, allow_nan=False) + "\n")
    print(
        f"wrote {len(data.t)} readings at {len(poses)} poses to {samples_path}; "
        f"truth to {truth_path}"
    )
    return 0
