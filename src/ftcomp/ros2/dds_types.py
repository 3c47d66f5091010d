"""ROS 2 messages as DDS types, for talking to a ROS 2 graph through Cyclone DDS (no ROS).

A ROS 2 node on a DDS middleware publishes topic ``/name`` as the DDS topic ``rt/name`` with the
type ``<package>::msg::dds_::<Type>_`` (rosidl's DDS mapping), XCDR1 little-endian with the
4-byte encapsulation header ``00 01 00 00``. These :class:`cyclonedds.idl.IdlStruct` classes have
exactly those names and the fields of the ``.msg`` definitions in order, so the bytes are what
rclcpp writes (``tests/ros2/test_live.py`` compares them with rosbags' CDR serialiser).
"""

# No ``from __future__ import annotations`` here: cyclonedds reads the field annotations of the
# IdlStruct classes as types, not as strings.
import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import HardwareError, ParameterError

try:
    from cyclonedds.idl import IdlStruct
    from cyclonedds.idl.types import float64, int32, sequence, uint32
except ImportError as exc:  # the optional extra is not installed
    raise HardwareError(f"ros2:// needs Cyclone DDS: pip install 'ftcomp[ros2]' ({exc})") from None

__all__ = [
    "Header",
    "Quaternion",
    "TFMessage",
    "Time",
    "Transform",
    "TransformStamped",
    "Vector3",
    "Wrench",
    "WrenchStamped",
    "dds_topic",
    "wrench_message",
    "wrench_of",
]

_NS = 1_000_000_000
_TOPIC = re.compile(r"^(/[A-Za-z_][A-Za-z0-9_]*)+$")


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    """``builtin_interfaces/msg/Time``."""

    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    """``std_msgs/msg/Header``."""

    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    """``geometry_msgs/msg/Vector3``."""

    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Wrench(IdlStruct, typename="geometry_msgs::msg::dds_::Wrench_"):
    """``geometry_msgs/msg/Wrench``."""

    force: Vector3 = field(default_factory=Vector3)
    torque: Vector3 = field(default_factory=Vector3)


@dataclass
class WrenchStamped(IdlStruct, typename="geometry_msgs::msg::dds_::WrenchStamped_"):
    """``geometry_msgs/msg/WrenchStamped``."""

    header: Header = field(default_factory=Header)
    wrench: Wrench = field(default_factory=Wrench)


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    """``geometry_msgs/msg/Quaternion`` (x, y, z, w)."""

    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    """``geometry_msgs/msg/Transform``."""

    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    """``geometry_msgs/msg/TransformStamped``."""

    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    """``tf2_msgs/msg/TFMessage``."""

    if TYPE_CHECKING:  # what a sequence is to a type checker
        transforms: list[TransformStamped] = field(default_factory=list)
    else:
        transforms: sequence[TransformStamped] = field(default_factory=list)


def dds_topic(topic: str) -> str:
    """The DDS topic of ROS 2 topic ``topic`` (``/ft/wrench`` -> ``rt/ft/wrench``).

    Raises:
        ParameterError: not an absolute ROS 2 topic name.
    """
    if not _TOPIC.match(topic):
        raise ParameterError(
            f"{topic!r} is not an absolute ROS 2 topic name (e.g. /ft_sensor/wrench)"
        )
    return "rt" + topic


def wrench_message(stamp_ns: int, frame_id: str, wrench: NDArray[np.float64]) -> WrenchStamped:
    """A ``WrenchStamped`` stamped ``stamp_ns`` [ns] in ``frame_id``."""
    w = [float(v) for v in wrench]
    return WrenchStamped(
        Header(Time(int(stamp_ns // _NS), int(stamp_ns % _NS)), frame_id),
        Wrench(Vector3(*w[:3]), Vector3(*w[3:])),
    )


def wrench_of(msg: WrenchStamped) -> tuple[int, NDArray[np.float64]]:
    """``(header stamp [ns], [fx, fy, fz, tx, ty, tz])`` of a message."""
    f, m = msg.wrench.force, msg.wrench.torque
    stamp = int(msg.header.stamp.sec) * _NS + int(msg.header.stamp.nanosec)
    return stamp, np.array([f.x, f.y, f.z, m.x, m.y, m.z], dtype=float)
