"""``ftcomp export ros2 CALIBRATION.json -o params.yaml --world-frame B --sensor-frame S``.

Writes the calibration as ros2_control parameters (see :mod:`ftcomp.ros2.export`).
"""

from __future__ import annotations

import argparse

__all__ = ["register", "run"]


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``export`` command's arguments to its parser."""
    from ftcomp.ros2.export import DISTROS

    parser.description = (
        "Write a calibration as ros2_control parameters: the force_torque_sensor_broadcaster "
        "section loads as it is (its offsets remove the bias; on Jazzy and later a "
        "control_filters/GravityCompensationWrench filter removes the tool's gravity in the "
        "base frame with the identified tilt). The admittance_controller section is a FRAGMENT "
        "to merge into your admittance configuration: it sets the F/T sensor and the tool's "
        "gravity (without tilt, and without bias unless --chained); add joints, "
        "command_interfaces, state_interfaces, chainable_command_interfaces, kinematics "
        "(plugin_name, plugin_package, base, tip), control.frame.id and the admittance gains "
        "(selected_axes, mass, damping_ratio, stiffness), as the file's comment lists."
    )
    parser.add_argument("target", choices=("ros2",), help="what to export to")
    parser.add_argument(
        "calibration", metavar="CALIBRATION.json", help="a calibration file from ftcomp calibrate"
    )
    parser.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="PARAMS.yaml",
        help="the ros2_control parameter file to write",
    )
    parser.add_argument(
        "--world-frame",
        required=True,
        metavar="B",
        help="the robot's base frame (the frame the calibration's tilt refers to)",
    )
    parser.add_argument(
        "--sensor-frame", required=True, metavar="S", help="the sensor's measuring frame"
    )
    parser.add_argument(
        "--sensor-name",
        metavar="NAME",
        help="the sensor's name in the ros2_control hardware description (default: S)",
    )
    parser.add_argument(
        "--broadcaster-name",
        default="force_torque_sensor_broadcaster",
        metavar="NAME",
        help="controller name of the broadcaster (force_torque_sensor_broadcaster)",
    )
    parser.add_argument(
        "--admittance-name",
        default="admittance_controller",
        metavar="NAME",
        help="controller name of the admittance controller (admittance_controller)",
    )
    parser.add_argument(
        "--distro",
        choices=DISTROS,
        default="jazzy",
        help="the ROS 2 distribution: humble has no broadcaster filter chain and no "
        "GravityCompensationWrench (the file then has the offsets and the admittance gravity "
        "only); jazzy and later have both (default: jazzy)",
    )
    parser.add_argument(
        "--chained",
        action="store_true",
        help="the admittance controller reads the broadcaster's exported interfaces, the bias "
        "removed by its offsets (jazzy and later; default: the sensor's raw interfaces)",
    )
    parser.add_argument("--force", action="store_true", help="replace an existing output file")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Load, convert, write."""
    from ftcomp.io.atomic import atomic_write_text, check_writable
    from ftcomp.io.calibration_json import load_calibration
    from ftcomp.ros2.export import ros2_control_parameters

    output = check_writable(args.output, overwrite=args.force)
    calibration = load_calibration(args.calibration)
    text = ros2_control_parameters(
        calibration.model,
        world_frame=args.world_frame,
        sensor_frame=args.sensor_frame,
        sensor_name=args.sensor_name,
        broadcaster=args.broadcaster_name,
        admittance=args.admittance_name,
        source=str(args.calibration),
        distro=args.distro,
        chained=args.chained,
    )
    atomic_write_text(output, text)
    print(f"ros2_control parameters written to {output}")
    return 0
