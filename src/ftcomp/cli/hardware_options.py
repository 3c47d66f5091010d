"""``--robot``, ``--sensor`` and ``--mount``: the options every command on hardware shares.

A robot and a sensor are opened by URI (:mod:`ftcomp.hardware.registry`); the mount is the
sensor frame on the TCP, given at the edge in millimetres and degrees
(``--mount X,Y,Z,ROLL,PITCH,YAW``, URDF-style fixed-axis roll, pitch, yaw). Without
``--robot``, commands that allow it run the sensor alone on ``fixed://`` (the host's clock,
no pose).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from typing import TYPE_CHECKING

from ftcomp.errors import ParameterError
from ftcomp.hardware.devices import uri_help

if TYPE_CHECKING:
    from ftcomp.hardware.protocols import Mount, Robot, WrenchSensor

__all__ = ["add_hardware_arguments", "open_hardware", "parse_mount"]

#: The robot used when a command runs a sensor alone.
NO_ROBOT = "fixed://"


def parse_mount(text: str) -> tuple[float, ...]:
    """``"0,0,35,0,0,90"`` -> the numbers (six: x, y, z [mm], roll, pitch, yaw [deg]; the
    count and range are :meth:`~ftcomp.hardware.protocols.Mount.from_mm_deg`'s to check)."""
    try:
        return tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers X,Y,Z,ROLL,PITCH,YAW (mm, deg); got {text!r}"
        ) from None


def add_hardware_arguments(parser: argparse.ArgumentParser, *, robot_required: bool) -> None:
    """Add ``--robot``, ``--sensor`` and ``--mount``."""
    parser.add_argument(
        "--robot",
        required=robot_required,
        metavar="URI",
        help="the arm: "
        + uri_help("robot")
        + ("" if robot_required else " (default: none, the sensor alone)"),
    )
    parser.add_argument(
        "--sensor",
        required=True,
        metavar="URI",
        help="the F/T sensor: "
        + uri_help("sensor")
        + " (a sensor that tares itself, netft://HOST?bias=1, zeroes the tool's weight: refused "
        "with -c, use ftcomp rebias)",
    )
    parser.add_argument(
        "--mount",
        type=parse_mount,
        default=None,
        metavar="X,Y,Z,ROLL,PITCH,YAW",
        help="the sensor frame in the robot's TCP frame [mm, deg] (default: the TCP frame)",
    )


def mount_of(args: argparse.Namespace) -> Mount:
    """The :class:`~ftcomp.hardware.protocols.Mount` the options give."""
    from ftcomp.hardware.protocols import Mount

    return Mount() if args.mount is None else Mount.from_mm_deg(args.mount)


@contextmanager
def open_hardware(
    args: argparse.Namespace, check_robot: Callable[[Robot], None] | None = None
) -> Iterator[tuple[Robot, WrenchSensor, Mount]]:
    """Open and enter the robot (then ``check_robot(robot)``), then the sensor; leave both
    (motion stopped first) at the end."""
    from ftcomp.hardware.protocols import TaresInHardware
    from ftcomp.hardware.registry import open_robot, open_sensor

    calibration = getattr(args, "calibration", None)
    mount = mount_of(args)
    with ExitStack() as stack:
        robot = stack.enter_context(open_robot(args.robot or NO_ROBOT))
        if check_robot is not None:
            check_robot(robot)
        sensor = open_sensor(args.sensor, robot)
        if calibration is not None and (
            isinstance(sensor, TaresInHardware) and sensor.tares_in_hardware
        ):
            raise ParameterError(
                f"{args.sensor!r} zeroes the sensor with the tool's weight in it and "
                f"{calibration} would subtract that weight again; drop its bias=1 (the "
                "calibration's bias is used), or re-bias the calibration at a still pose: "
                "ftcomp rebias"
            )
        sensor = stack.enter_context(sensor)
        yield robot, sensor, mount
