"""``ftcomp ros2 node``: run gravity compensation as a ROS 2 node (docs/ros2.md).

``ftcomp ros2 node --calibration calibration.json --base-frame base_link --sensor-frame ft_sensor
--wrench-topic /ft_sensor/wrench [--urdf robot.urdf] [--online-load] [--ros-args -p name:=value
...]``

Publishes ``~/wrench_compensated`` (sensor frame) and ``~/wrench_contact_base`` (base frame)
with each raw reading's stamp; with ``--online-load`` it weighs a grasped load, compensates it
once the estimate converged and publishes ``~/load`` (geometry_msgs/InertiaStamped: mass [kg],
centre of gravity [m], sensor frame) and ``~/load_state`` (std_msgs/String: empty, estimating,
holding); services ``~/rebias`` and ``~/reload_calibration``
(std_srvs/Trigger); says on ``/diagnostics`` why a reading was not compensated. Every setting is
also a ROS 2 parameter of the node (``-p calibration_file:=...``; a ``-p`` wins over the option).
Runs until Ctrl-C (or ``--seconds``).
"""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["register"]

#: The options and the node settings they give (``NodeConfig``'s fields).
_TEXT = ("calibration_file", "base_frame", "sensor_frame", "wrench_topic", "joint_states", "urdf")
_NUMBERS = ("stale_s", "rebias_s", "timeout_s")


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``ros2`` command and its ``node`` subcommand."""
    commands = parser.add_subparsers(
        dest="ros2_command", metavar="ROS2_COMMAND", required=True, help="node: the node"
    )
    node = commands.add_parser(
        "node", help="gravity compensation as a ROS 2 node", description=__doc__
    )
    node.formatter_class = argparse.RawDescriptionHelpFormatter
    from ftcomp.cli.options import add_field_option
    from ftcomp.ros2.node_config import RUN_FOR, NodeConfig

    required = ("calibration_file", "base_frame", "sensor_frame")
    for name in _TEXT:
        flag = "--calibration" if name == "calibration_file" else None
        extra: dict[str, Any] = {
            "metavar": "FILE" if name in ("calibration_file", "urdf") else "NAME"
        }
        if name in required:
            extra.update(default=None, none_means="required, here or as -p " + name + ":=...")
        elif name == "urdf":
            extra.update(default=None, none_means="the /robot_description topic's", help="the URDF")
        add_field_option(node, NodeConfig, name, flag, type=str, dest=name, **extra)
    add_field_option(node, NodeConfig, "wrench_qos")
    for name in _NUMBERS:
        add_field_option(node, NodeConfig, name, metavar="S")
    node.add_argument(
        "--online-load",
        action="store_true",
        default=None,
        help="weigh a grasped load online, compensate it and publish ~/load and ~/load_state "
        "(the readings' rate measured from their first 0.5 s of stamps; default: off)",
    )
    node.add_argument("--name", default="ftcomp", help="the node's name (default ftcomp)")
    add_field_option(node, RUN_FOR, "seconds", "--seconds", none_means="until Ctrl-C")
    node.add_argument(
        "--ros-args",
        dest="ros_args",
        nargs=argparse.REMAINDER,
        default=None,
        help="ROS 2 arguments to the end of the line (-p name:=value, -r from:=to), as ros2 run",
    )
    node.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Start the node, say so, run until Ctrl-C or ``--seconds``."""
    from ftcomp.ros2.node import CompensationNode

    settings: dict[str, Any] = {
        name: getattr(args, name)
        for name in (*_TEXT, "wrench_qos", *_NUMBERS, "online_load")
        if getattr(args, name) is not None
    }
    arguments = ["--ros-args", *args.ros_args] if args.ros_args is not None else []
    with CompensationNode(settings, node_name=args.name, arguments=arguments) as node:
        config = node.config
        assert config is not None
        load = ", ~/load, ~/load_state" if config.online_load else ""
        print(
            f"node {args.name}: {config.wrench_topic} compensated with {config.calibration_file} "
            f"-> ~/wrench_compensated, ~/wrench_contact_base{load} (Ctrl-C stops)",
            flush=True,
        )
        node.serve(args.seconds)
    return 0
