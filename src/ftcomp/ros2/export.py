"""A calibration as ros2_control parameters: the force/torque broadcaster, its gravity filter,
and the admittance controller.

What ros-controls computes (read from their code, versions in ``docs/ros2.md``):

- ``force_torque_sensor_broadcaster`` (ros2_controllers): ``wrench = (raw + offset) * multiplier``
  per axis (``apply_sensor_offset`` *adds* the offset), then the ``sensor_filter_chain``; the
  result is published on ``~/wrench_filtered``. So ``offset = -[F0, M0]`` and ``multiplier = 1``.
- ``control_filters/GravityCompensationWrench`` (control_toolbox): ``F_g = mass *
  gravity_field`` is given in ``world_frame``; in the sensor frame ``g_s = R_sensor_world @ F_g``,
  and it subtracts ``g_s`` from the force and ``CoG x g_s`` from the torque. With ``world_frame``
  the robot's base ``B`` and ``gravity_field = R_world_base.T @ [0, 0, -g]`` (the identified base
  tilt), ``mass * gravity_field`` is exactly ftcomp's ``gravity_base_N`` and the chain computes
  what :class:`~ftcomp.compensation.compensator.GravityCompensator` does.
- ``admittance_controller`` (ros2_controllers): subtracts ``CoG.force`` along ``-z`` of
  ``fixed_world_frame`` and ``(R CoG.pos) x weight`` from the torque; it has no bias parameter and
  no tilt: both are stated in a comment.

Which ROS 2 distribution (:data:`DISTROS`, ``distro``): Humble's broadcaster has no filter chain
and its control_toolbox no ``GravityCompensationWrench``, so on Humble the file has the
broadcaster's offsets and the admittance controller's gravity only; Jazzy and later have both,
and their broadcaster is chainable (it exports ``<broadcaster>/<sensor>/force.x`` ... with the
offset applied), so the admittance controller may read the bias-free wrench from it
(``chained``). The admittance section is a *fragment*: it sets the sensor and gravity
parameters, and the comment above it lists what admittance_controller needs besides
(:data:`ADMITTANCE_REQUIRED`: joints, interfaces, kinematics plugin, control frame, gains).

Numbers are written with ``repr`` (shortest round trip) and always as doubles (``1.0e-05``, never
``1e-05``, which a YAML 1.1 parser reads as a string), so the YAML holds the calibration exactly.
Names are checked (:func:`check_ros_name`: frames and the sensor name as tf2 checks a frame id,
any text but the empty one and one starting with ``/``; controller names by ROS's rule for a
node, letters, digits and ``_`` not starting with a digit) and written double-quoted, keys too,
so that no name reads back as anything but a string (``yes``, ``null``, ``on`` are valid names
and YAML 1.1 booleans or nulls).
"""

from __future__ import annotations

import json
import math
import re
import textwrap
from collections.abc import Iterable

import numpy as np

from ftcomp import __version__
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import ParameterError
from ftcomp.model import GravityModel

__all__ = [
    "ADMITTANCE_REQUIRED",
    "DISTROS",
    "check_ros_name",
    "ros2_control_parameters",
    "yaml_double",
    "yaml_string",
]

#: The ROS 2 distributions the export knows, oldest first.
DISTROS = ("humble", "jazzy", "kilted", "rolling")
#: Distributions whose force_torque_sensor_broadcaster has ``sensor_filter_chain`` and is
#: chainable, and whose control_toolbox has ``control_filters/GravityCompensationWrench``.
FILTER_CHAIN_DISTROS = ("jazzy", "kilted", "rolling")
#: admittance_controller parameters without a default that the export does not write (the
#: robot's, not the sensor's): the admittance section is a fragment to merge with them.
ADMITTANCE_REQUIRED = (
    "joints",
    "command_interfaces",
    "state_interfaces",
    "chainable_command_interfaces",
    "kinematics.plugin_name",
    "kinematics.plugin_package",
    "kinematics.base",
    "kinematics.tip",
    "control.frame.id",
    "admittance.selected_axes",
    "admittance.mass",
    "admittance.damping_ratio",
    "admittance.stiffness",
)

#: The parameter definitions this export follows (see docs/ros2.md).
SOURCES = (
    "ros2_controllers 6.9.0: force_torque_sensor_broadcaster/src/"
    "force_torque_sensor_broadcaster_parameters.yaml, admittance_controller/src/"
    "admittance_controller_parameters.yaml",
    "control_toolbox 6.3.0: control_toolbox/src/control_filters/"
    "gravity_compensation_filter_parameters.yaml",
)


def yaml_double(value: float) -> str:
    """``value`` as a YAML double that reads back exactly (``repr`` with a decimal point)."""
    if not math.isfinite(value):
        raise ParameterError(f"cannot export a non-finite number ({value})")
    text = repr(float(value))
    mantissa, e, exponent = text.partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    return mantissa + (e + exponent if e else "")


def _list(values: Iterable[float]) -> str:
    return "[" + ", ".join(yaml_double(float(v)) for v in values) + "]"


_TOKEN = r"[A-Za-z_][A-Za-z0-9_]*"
_PATTERNS = {
    # tf2's own rule (BufferCore::validateFrameId): a frame id is any string but the empty one
    # and one starting with '/'; it need not be a ROS name (0x1F, sensor-1 are tf2 frames).
    "frame": (
        re.compile(r"[^/].*", re.DOTALL),
        "tf2 refuses an empty frame id and one starting with '/'",
    ),
    "node": (re.compile(_TOKEN), "letters, digits and _, not starting with a digit"),
}


def check_ros_name(kind: str, value: str, rule: str = "frame") -> str:
    """``value`` when it is a valid name of ``rule``: ``frame``, a tf2 frame id (any text but
    the empty one and one starting with ``/``, as tf2 checks); ``node``, a ROS node name.

    Raises:
        ParameterError: naming ``kind``, the value and the rule.
    """
    pattern, words = _PATTERNS[rule]
    if pattern.fullmatch(value) is None:
        what = "tf2 frame id" if rule == "frame" else "ROS name"
        raise ParameterError(f"{kind} {value!r}: not a valid {what} ({words})")
    return value


def yaml_string(value: str) -> str:
    """``value`` double-quoted, so every YAML parser (1.1 or 1.2) reads it as that string: a
    printable character as itself, any other escaped by its code point (``\\uXXXX``, or
    ``\\UXXXXXXXX`` beyond the BMP: YAML reads a JSON-style surrogate pair as two characters)."""
    quoted = json.dumps(value, ensure_ascii=False)
    return "".join(
        c if c.isprintable() else (f"\\u{ord(c):04x}" if ord(c) <= 0xFFFF else f"\\U{ord(c):08x}")
        for c in quoted
    )


def ros2_control_parameters(
    model: GravityModel,
    *,
    world_frame: str,
    sensor_frame: str,
    sensor_name: str | None = None,
    broadcaster: str = "force_torque_sensor_broadcaster",
    admittance: str = "admittance_controller",
    source: str = "",
    distro: str = "jazzy",
    chained: bool = False,
) -> str:
    """The parameter file (YAML text) for the broadcaster, its filter chain and the admittance.

    Args:
        model: the identified calibration.
        world_frame: the robot's base frame ``B`` the calibration's tilt refers to.
        sensor_frame: the sensor's measuring frame ``S`` (the broadcaster's ``frame_id``).
        sensor_name: the sensor's name in the ros2_control hardware description (its state
            interfaces ``<name>/force.x`` ...); default: ``sensor_frame``.
        broadcaster: the broadcaster's controller name (the YAML's top-level key).
        admittance: the admittance controller's name.
        source: where the calibration came from (a comment).
        distro: the ROS 2 distribution (:data:`DISTROS`): without a filter chain on Humble.
        chained: the admittance controller reads the broadcaster's exported interfaces (the
            bias removed by its offset) instead of the sensor's (Jazzy and later).

    Raises:
        ParameterError: a name that is not a valid ROS name (see :func:`check_ros_name`), an
            unknown distribution, or ``chained`` on one without a chainable broadcaster.
    """
    if distro not in DISTROS:
        raise ParameterError(f"distro {distro!r}: expected one of {', '.join(DISTROS)}")
    filters = distro in FILTER_CHAIN_DISTROS
    if chained and not filters:
        raise ParameterError(
            f"chained: {distro}'s force_torque_sensor_broadcaster exports no interfaces to chain "
            f"to (from {FILTER_CHAIN_DISTROS[0]} on)"
        )
    check_ros_name("world frame", world_frame)
    check_ros_name("sensor frame", sensor_frame)
    check_ros_name("sensor name", sensor_name if sensor_name is not None else sensor_frame)
    check_ros_name("broadcaster name", broadcaster, "node")
    check_ros_name("admittance controller name", admittance, "node")
    if admittance == broadcaster:
        raise ParameterError(
            f"admittance controller name {admittance!r} is the broadcaster's name too: one "
            "YAML key cannot hold both controllers"
        )
    q = yaml_string
    names = {
        "world frame": q(world_frame),
        "sensor frame": q(sensor_frame),
        "sensor name": q(sensor_name if sensor_name is not None else sensor_frame),
        "broadcaster name": q(broadcaster),
        "admittance controller name": q(admittance),
    }
    sensor_frame_raw = sensor_frame
    world_frame, sensor_frame = names["world frame"], names["sensor frame"]
    g = STANDARD_GRAVITY_MPS2
    mass = model.weight_N / g
    # A weightless tool: no direction to carry the tilt; the filter then subtracts nothing.
    field = model.gravity_base_N / mass if mass > 0.0 else np.array([0.0, 0.0, -g])
    F0, M0 = model.force_bias_N, model.torque_bias_Nm
    U, V = math.degrees(model.tilt_U_rad), math.degrees(model.tilt_V_rad)
    axes = "xyz"
    # The axis keys quoted too: a YAML 1.1 parser reads a plain y as a boolean.
    force_offset = ", ".join(
        f"{yaml_string(a)}: {yaml_double(-v)}" for a, v in zip(axes, F0, strict=True)
    )
    torque_offset = ", ".join(
        f"{yaml_string(a)}: {yaml_double(-v)}" for a, v in zip(axes, M0, strict=True)
    )
    header = [
        f"# ros2_control parameters from ftcomp {__version__}"
        + (f", calibration {source}" if source else "")
        + f", for ROS 2 {distro}",
        f"# tool weight {model.weight_N:.6g} N (mass {mass:.6g} kg at g = {g} m/s^2), base tilt "
        f"U {U:+.4f} deg, V {V:+.4f} deg",
        "# Parameter definitions followed:",
        *(f"#   {line}" for line in SOURCES),
    ]
    broadcaster_lines = [
        f"{names['broadcaster name']}:",
        "  ros__parameters:",
        f"    frame_id: {sensor_frame}",
        f"    sensor_name: {names['sensor name']}",
        "    # The broadcaster ADDS the offset to the raw reading: offset = -(identified bias).",
        "    offset:",
        f"      force: {{{force_offset}}}",
        f"      torque: {{{torque_offset}}}",
    ]
    if filters:
        broadcaster_lines += [
            "    # Gravity compensation, published on ~/wrench_filtered: the tool's weight as",
            f"    # mass * gravity_field in the robot's base frame {world_frame}; the field",
            "    # carries the identified base tilt.",
            "    sensor_filter_chain:",
            "      filter1:",
            '        type: "control_filters/GravityCompensationWrench"',
            '        name: "gravity_compensation"',
            "        params:",
            f"          world_frame: {world_frame}",
            f"          sensor_frame: {sensor_frame}",
            "          tool:",
            f"            CoG: {_list(model.center_of_gravity_m)}",
            f"            mass: {yaml_double(mass)}",
            f"            gravity_field: {_list(field)}",
        ]
    else:
        broadcaster_lines += [
            f"    # {distro}: the broadcaster has no sensor_filter_chain and control_toolbox no",
            "    # GravityCompensationWrench; the tool's weight is removed only by the",
            "    # admittance controller below (without the base tilt). Jazzy and later do both.",
            "    # (The offset needs a broadcaster with the offset parameters; without them the",
            "    # published wrench keeps the bias.)",
        ]
    required = ", ".join(ADMITTANCE_REQUIRED)
    fragment = [
        "    # A FRAGMENT to merge into your admittance_controller configuration: it sets the F/T",
        "    # sensor and the tool's gravity only. admittance_controller also needs (no defaults):",
        *(f"    #   {line}" for line in textwrap.wrap(required, 84)),
    ]
    if chained:
        source_lines = [
            "    # It reads the broadcaster's exported interfaces (the bias removed by its offset)",
            "    # and removes the tool's weight along -z of fixed_world_frame; it cannot express",
            f"    # the base tilt (U {U:+.4f} deg, V {V:+.4f} deg): set fixed_world_frame to a",
            "    # frame whose z is truly vertical.",
        ]
        ft_name = yaml_string(f"{broadcaster}/{sensor_name or sensor_frame_raw}")
    else:
        source_lines = [
            "    # admittance_controller reads the sensor's raw state interfaces and removes only "
            "the",
            "    # tool's weight along -z of fixed_world_frame: it can express neither the sensor "
            "bias",
            f"    # (F0 = {_list(F0)} N,",
            f"    #  M0 = {_list(M0)} N*m stay in the signal)",
            f"    # nor the base tilt (U {U:+.4f} deg, V {V:+.4f} deg): "
            + ("prefer the broadcaster's" if filters else "set fixed_world_frame to a"),
            "    # wrench_filtered, or set fixed_world_frame to a frame whose z is truly vertical."
            if filters
            else "    # frame whose z is truly vertical.",
        ]
        ft_name = names["sensor name"]
    admittance_lines = [
        f"{names['admittance controller name']}:",
        "  ros__parameters:",
        *fragment,
        *source_lines,
        "    ft_sensor:",
        f"      name: {ft_name}",
        "      frame:",
        f"        id: {sensor_frame}",
        "    fixed_world_frame:",
        "      frame:",
        f"        id: {world_frame}",
        "    gravity_compensation:",
        "      frame:",
        f"        id: {sensor_frame}",
        "      CoG:",
        f"        pos: {_list(model.center_of_gravity_m)}",
        f"        force: {yaml_double(model.weight_N)}",
    ]
    lines = [*header, *broadcaster_lines, *admittance_lines]
    return "\n".join(lines) + "\n"
