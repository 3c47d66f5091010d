"""``ftcomp import-bag BAG --wrench-topic T --base-frame B --sensor-frame S -o samples.csv``.

Reads a ROS 2 (MCAP, sqlite3) or ROS 1 bag without ROS, finds the still segments and writes
their readings as a sample CSV for ``ftcomp calibrate`` (see :mod:`ftcomp.ros2.importer`).
"""

from __future__ import annotations

import argparse

from ftcomp.cli.options import map_field, with_flags
from ftcomp.cli.still_options import add_still_arguments, print_segments, still_config

__all__ = ["register", "run"]


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``import-bag`` command's arguments to its parser."""
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
    add_still_arguments(parser)
    parser.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="SAMPLES.csv",
        help="the sample CSV to write (pose ids per still segment, t_ns and t)",
    )
    parser.add_argument("--force", action="store_true", help="replace an existing output file")
    map_field(parser, "joint_states_topic", "--joint-states")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Import, print the segments, write the sample CSV."""
    from ftcomp.cli.calibrate import console
    from ftcomp.cli.common import print_warnings
    from ftcomp.cli.live_status import CallbackProgress
    from ftcomp.io.atomic import check_writable
    from ftcomp.ros2.importer import import_bag, write_bag_samples

    output = check_writable(args.output, overwrite=args.force)
    still = still_config(args)
    bar = CallbackProgress("messages read")
    try:
        result = import_bag(
            args.bag,
            wrench_topic=args.wrench_topic,
            base_frame=args.base_frame,
            sensor_frame=args.sensor_frame,
            still=still,
            urdf=args.urdf,
            joint_states_topic=args.joint_states,
            wrench_frame=args.wrench_frame,
            progress=bar,
        )
    finally:
        bar.close()
    print_warnings(with_flags(w, args, ["wrench_frame"]) for w in result.warnings)
    out = console()
    out.print(f"pose: {result.pose_source}")
    out.print(f"wrench: {with_flags(result.wrench_note, args, ['wrench_frame'])}")
    title = f"Still segments in {result.source} ({args.wrench_topic})"
    print_segments(out, title, result.segments, result.t0_ns, still)
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
