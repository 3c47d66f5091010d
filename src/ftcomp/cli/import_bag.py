"""``ftcomp import-bag BAG --wrench-topic T --base-frame B --sensor-frame S -o samples.csv``.

Reads a ROS 2 (MCAP, sqlite3) or ROS 1 bag without ROS, finds the still segments and writes
their readings as a sample CSV for ``ftcomp calibrate`` (see :mod:`ftcomp.ros2.importer`).
"""

from __future__ import annotations

import argparse

__all__ = ["register", "run"]


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``import-bag`` command's arguments to its parser."""
    from ftcomp.ros2.still import StillConfig

    d = StillConfig()
    parser.description = (
        "Read a ROS 2 bag (a rosbag2 directory, .mcap or .db3) or a ROS 1 .bag without a ROS "
        "installation: the wrench topic, the sensor's pose at each reading (from /tf and "
        "/tf_static, or from joint states and the URDF), the still segments; write their "
        "readings as a sample CSV (pose id per segment, t_ns) for 'ftcomp calibrate'."
    )
    parser.add_argument("bag", metavar="BAG", help="rosbag2 directory, .mcap, .db3 or .bag")
    parser.add_argument(
        "--wrench-topic", required=True, metavar="TOPIC", help="geometry_msgs/WrenchStamped"
    )
    parser.add_argument("--base-frame", required=True, metavar="B", help="the robot's base")
    parser.add_argument("--sensor-frame", required=True, metavar="S", help="the F/T frame")
    parser.add_argument(
        "--wrench-frame",
        metavar="F",
        help="the frame the readings are in, whatever their header.frame_id says (a warning "
        "when it disagrees): e.g. netft_rdt_driver stamps sensor-frame readings 'base_link'; "
        "give --wrench-frame S (default: the header's frame_id)",
    )
    parser.add_argument(
        "--urdf",
        metavar="ROBOT.urdf",
        help="take the sensor's pose from this robot description and --joint-states "
        "(default: from /tf and /tf_static)",
    )
    parser.add_argument(
        "--joint-states",
        metavar="TOPIC",
        help="sensor_msgs/JointState topic, with --urdf (default: none, poses from /tf)",
    )
    still = parser.add_argument_group("still segments")
    still.add_argument(
        "--still-angle-deg",
        type=float,
        metavar="DEG",
        default=d.angle_deg,
        help=f"orientation stays within this of the segment's first [deg] ({d.angle_deg:g})",
    )
    still.add_argument(
        "--still-min-s",
        type=float,
        metavar="S",
        default=d.min_duration_s,
        help=f"shortest segment [s] ({d.min_duration_s:g})",
    )
    still.add_argument(
        "--still-window-s",
        type=float,
        metavar="S",
        default=d.window_s,
        help=f"moving-mean window of the settled test [s] ({d.window_s:g})",
    )
    still.add_argument(
        "--still-force-N",
        type=float,
        metavar="N",
        default=d.force_N,
        help=f"settled: moving mean within this of the segment's [N] ({d.force_N:g})",
    )
    still.add_argument(
        "--still-torque-Nm",
        type=float,
        metavar="NM",
        default=d.torque_Nm,
        help=f"settled: ... [N*m] ({d.torque_Nm:g})",
    )
    parser.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="SAMPLES.csv",
        help="the sample CSV to write (pose ids per still segment, t_ns and t)",
    )
    parser.add_argument("--force", action="store_true", help="replace an existing output file")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Import, print the segments, write the sample CSV."""
    from rich.table import Table
    from scipy.spatial.transform import Rotation

    from ftcomp.cli.calibrate import console
    from ftcomp.cli.common import print_warnings
    from ftcomp.frames import encode_orientation
    from ftcomp.io.atomic import check_writable
    from ftcomp.ros2.importer import import_bag, write_bag_samples
    from ftcomp.ros2.still import StillConfig

    output = check_writable(args.output, overwrite=args.force)
    still = StillConfig(
        angle_deg=args.still_angle_deg,
        min_duration_s=args.still_min_s,
        window_s=args.still_window_s,
        force_N=args.still_force_N,
        torque_Nm=args.still_torque_Nm,
    )
    result = import_bag(
        args.bag,
        wrench_topic=args.wrench_topic,
        base_frame=args.base_frame,
        sensor_frame=args.sensor_frame,
        still=still,
        urdf=args.urdf,
        joint_states_topic=args.joint_states,
        wrench_frame=args.wrench_frame,
    )
    print_warnings(result.warnings)
    out = console()
    out.print(f"pose: {result.pose_source}")
    out.print(f"wrench: {result.wrench_note}")
    out.print(f"still: {still.describe()}")
    table = Table(title=f"Still segments in {result.source} ({args.wrench_topic})")
    for col in ("pose", "start [s]", "duration [s]", "readings", "alpha, beta, gamma [deg]"):
        table.add_column(col, justify="left" if col == "pose" else "right")
    table.add_column("force std [N]", justify="right")
    table.add_column("torque std [N·m]", justify="right")
    for k, seg in enumerate(result.segments, start=1):
        angles = encode_orientation(Rotation.from_matrix(seg.R_base_sensor), "paper_euler")
        table.add_row(
            str(k),
            f"{(seg.t_start_ns - result.t0_ns) / 1e9:.3f}",
            f"{seg.duration_s:.3f}",
            str(seg.readings),
            ", ".join(f"{a:+.2f}" for a in angles),
            " ".join(f"{v:.3f}" for v in seg.wrench_std[:3]),
            " ".join(f"{v:.4f}" for v in seg.wrench_std[3:]),
        )
    out.print(table)
    kept = len(result.t_ns)
    out.print(
        f"kept {kept} of {result.readings_total} readings in {len(result.segments)} still "
        f"segments; {result.readings_without_pose} had no pose, {result.unsettled} held "
        "orientation(s) never settled"
    )
    write_bag_samples(output, result)
    out.print(f"samples written to [bold]{output}[/bold]")
    if len(result.segments) < 3:
        print_warnings(
            [f"only {len(result.segments)} still segment(s): calibration needs at least 3 poses"]
        )
    return 0
