"""The settings of ``ftcomp ros2 node`` (:mod:`.node`), readable without rclpy.

The command line builds its options from :class:`NodeConfig`'s fields, and ``--help`` must not
need ROS 2; the node declares each field as a ROS 2 parameter of the same name.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ftcomp.config_fields import FieldSpec, check_fields, param
from ftcomp.errors import ParameterError

__all__ = ["QOS_CHOICES", "RUN_FOR", "NodeConfig", "check_topic_name"]

#: The QoS a subscription to a sensor topic may ask for: ``best_effort`` (matches reliable
#: and best-effort publishers, ROS 2's ``SensorDataQoS``), ``reliable`` (reliable publishers
#: only; nothing is dropped by the middleware).
QOS_CHOICES = ("best_effort", "reliable")
#: How long ``ftcomp ros2 node`` runs [s] (None: until Ctrl-C).
RUN_FOR = FieldSpec(help="stop after this long", unit="s", gt=0.0, optional=True)
_TOPIC = re.compile(r"^(/[A-Za-z_][A-Za-z0-9_]*)+$")


def check_topic_name(topic: str, where: str) -> str:
    """``topic`` if it is an absolute ROS 2 topic name, else a ParameterError naming ``where``."""
    if not _TOPIC.match(topic):
        raise ParameterError(
            f"{where}: {topic!r} is not an absolute ROS 2 topic name (e.g. /ft_sensor/wrench)"
        )
    return topic


@dataclass(frozen=True)
class NodeConfig:
    """The node's settings; each is a ROS 2 parameter of the same name.

    Attributes:
        calibration_file: the calibration (``ftcomp calibrate``'s JSON).
        base_frame: the URDF link the arm's base is (``base_link``).
        sensor_frame: the URDF link of the sensor; raw wrenches must carry it as ``frame_id``.
        wrench_topic: the raw ``WrenchStamped`` topic.
        joint_states: the ``JointState`` topic.
        urdf: the URDF file; empty: the ``/robot_description`` topic's string.
        wrench_qos: the raw topic's subscription QoS (one of ``best_effort``, ``reliable``).
        stale_s: joint states older than this [s] stop publishing.
        rebias_s: how long ``~/rebias`` reads [s].
        timeout_s: how long starting waits for the description and the joint states [s].
        online_load: weigh a grasped load online, compensate it once its estimate converged
            and publish the estimate (``~/load``, ``~/load_state``); the readings' rate is
            measured from the stamps of their first 0.5 s.
    """

    calibration_file: str = param(help="the calibration (JSON)")
    base_frame: str = param(help="the arm's base link in the URDF")
    sensor_frame: str = param(help="the sensor's link in the URDF (the raw wrenches' frame_id)")
    wrench_topic: str = param("/ft_sensor/wrench", help="the raw WrenchStamped topic")
    joint_states: str = param("/joint_states", help="the JointState topic")
    urdf: str = param("", help="the URDF file (empty: the /robot_description topic's)")
    wrench_qos: str = param("best_effort", choices=QOS_CHOICES, help="the raw topic's QoS")
    stale_s: float = param(0.1, gt=0.0, unit="s", help="joint states older than this stop output")
    rebias_s: float = param(
        2.0, gt=0.0, le=60.0, unit="s", help="how long ~/rebias reads still readings"
    )
    timeout_s: float = param(
        10.0, gt=0.0, unit="s", help="how long to wait for the description and joint states"
    )
    online_load: bool = False

    def __post_init__(self) -> None:
        check_fields(self)
        for name in ("calibration_file", "base_frame", "sensor_frame"):
            if not getattr(self, name):
                raise ParameterError(f"{name} is required", field=name)
        for name in ("wrench_topic", "joint_states"):
            try:
                check_topic_name(getattr(self, name), name)
            except ParameterError as exc:
                raise ParameterError(str(exc), field=name) from None
