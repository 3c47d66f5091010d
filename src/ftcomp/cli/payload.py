"""``ftcomp payload set``: write a calibration's tool mass and centre of gravity to the robot.

``ftcomp payload set ur://HOST|franka://HOST -c calibration.json [--mount X,Y,Z,ROLL,PITCH,YAW]``
``[--inertia dynamic.json]``

A UR controller's force mode, its protective stops and ``actual_TCP_force`` use the payload set
on it (the pendant's payload wizard, or by hand). This writes the calibration's: the mass
(weight / standard gravity) and the centre of gravity, taken from the sensor frame into the
controller's TCP frame through the mount (``--mount``, as ``record`` had it), then from the tool
flange through the TCP offset the controller reports, with ur_rtde's ``setPayload``. Prints what
was set before and what is set now (as RTDE reports them). The tool's weight in the calibration
includes the sensor's sensing end: the payload is everything beyond the sensor's fixed half.

A Franka arm's payload (libfranka's load model, which its collision detection, its external
wrench estimate and its gravity compensation use) is written with franky's ``set_load``: the
mass, the centre of gravity taken into the flange frame through the end effector the arm
reports (``F_T_EE``), and the inertia about the centre of gravity from ``--inertia``
(``ftcomp calibrate-dynamic``'s file, sensor axes), zero without it.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from ftcomp.errors import ParameterError

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from ftcomp.hardware.registry import Uri

__all__ = ["register", "run"]


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``payload`` command's subcommand ``set`` and its arguments."""
    from ftcomp.cli.hardware_options import parse_mount

    parser.description = __doc__.split("\n\n", 1)[1].replace("``", "") if __doc__ else None
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    actions = parser.add_subparsers(
        dest="action", metavar="ACTION", required=True, help="set: write the payload"
    )
    set_parser = actions.add_parser(
        "set",
        help="write the calibration's mass and centre of gravity to the controller",
        description="write the calibration's mass and centre of gravity to the controller",
    )
    set_parser.add_argument(
        "robot", metavar="ROBOT", help="the arm: ur://HOST (a UR controller) or franka://HOST"
    )
    set_parser.add_argument(
        "-c", "--calibration", required=True, help="the calibration file (ftcomp calibrate -o)"
    )
    set_parser.add_argument(
        "--mount",
        type=parse_mount,
        default=None,
        metavar="X,Y,Z,ROLL,PITCH,YAW",
        help="the sensor frame in the robot's TCP frame [mm, deg] (default: the TCP frame)",
    )
    set_parser.add_argument(
        "--inertia",
        default=None,
        metavar="FILE",
        help="franka:// only: the tool's inertia (ftcomp calibrate-dynamic's file)",
    )
    parser.set_defaults(handler=run)


def _text(mass_kg: float, cog_m: tuple[float, float, float]) -> str:
    cog = ", ".join(f"{v * 1e3:.2f}" for v in cog_m)
    return f"{mass_kg:.4f} kg at [{cog}] mm from the flange"


def run(args: argparse.Namespace) -> int:
    """Write the payload; print before and after."""
    from ftcomp.cli.hardware_options import mount_of
    from ftcomp.hardware.registry import parse_uri
    from ftcomp.io.calibration_json import load_calibration

    uri = parse_uri(args.robot)
    if uri.scheme not in ("ur", "franka") or not uri.host:
        raise ParameterError(
            f"{args.robot!r}: payload set writes to a UR controller or a Franka arm: ur://HOST "
            "or franka://HOST"
        )
    if args.inertia is not None and uri.scheme != "franka":
        raise ParameterError(
            "--inertia: a UR controller's payload has no inertia (ur_rtde's setPayload)",
            field="inertia",
        )
    model = load_calibration(args.calibration).model
    mount = mount_of(args)
    cog_tcp = mount.p_tcp_sensor_m + mount.R_tcp_sensor @ model.center_of_gravity_m
    if uri.scheme == "franka":
        return _franka(args, uri, model.mass_kg, cog_tcp, mount.R_tcp_sensor)
    from ftcomp.hardware.ur import set_payload

    before, after = set_payload(uri.host, model.mass_kg, cog_tcp, label=args.robot)
    print(f"{args.robot}: payload was {_text(before.mass_kg, before.cog_flange_m)}")
    print(f"{args.robot}: payload now {_text(after.mass_kg, after.cog_flange_m)}")
    return 0


def _franka(
    args: argparse.Namespace,
    uri: Uri,
    mass_kg: float,
    cog_tcp_m: NDArray[np.float64],
    R_tcp_sensor: NDArray[np.float64],
) -> int:
    """franky's set_load, the inertia (sensor axes) turned into the end effector's."""
    from ftcomp.hardware.franka import Load, set_load

    inertia_tcp = None
    if args.inertia is not None:
        from ftcomp.io.dynamic_json import load_dynamic

        inertia_tcp = R_tcp_sensor @ load_dynamic(args.inertia) @ R_tcp_sensor.T
    before, after = set_load(uri, mass_kg, cog_tcp_m, inertia_tcp)

    def text(load: Load) -> str:
        diagonal = ", ".join(f"{load.inertia_kgm2[i][i]:.2e}" for i in range(3))
        return f"{_text(load.mass_kg, load.cog_flange_m)}, inertia diagonal [{diagonal}] kg m^2"

    print(f"{args.robot}: load was {text(before)}")
    print(f"{args.robot}: load now {text(after)}")
    return 0
