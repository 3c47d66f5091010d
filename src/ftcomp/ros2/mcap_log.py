"""Live sessions' logs as MCAP files in the ROS 2 profile, for rosbags, Foxglove and Lichtblick.

:class:`SessionMcapLog` is a session's log observer
(:class:`~ftcomp.session.log.LogObserver`, ``--log run.mcap`` of ``ftcomp stream``, ``record``,
``run`` and ``sim place``), run on the observers' worker thread, off the loop's: it writes one
message per log row on each channel the row's columns fill, so every channel holds as many
messages as the session has rows, with the values its rows have:

==============================  ===================================  ===========================
topic                           type                                 columns
==============================  ===================================  ===========================
``/ftcomp/wrench_raw``          ``geometry_msgs/msg/WrenchStamped``  ``fx..tz`` (sensor frame)
``/ftcomp/wrench_compensated``  ``geometry_msgs/msg/WrenchStamped``  ``cfx..ctz`` (sensor frame)
``/tf``                         ``tf2_msgs/msg/TFMessage``           ``qx..qw``, ``px..pz``
``/ftcomp/wrench_error``        ``geometry_msgs/msg/WrenchStamped``  ``ex..etz`` (control frame)
``/ftcomp/twist_command``       ``geometry_msgs/msg/TwistStamped``   ``vx..wz`` (base frame)
``/ftcomp/load``                ``std_msgs/msg/Float64MultiArray``   the online load's columns
``/ftcomp/temperature``         ``sensor_msgs/msg/Temperature``      ``temperature_C``
``/ftcomp/imu``                 ``sensor_msgs/msg/Imu``              ``accel_x_m_s2..z``,
                                                                     ``gyro_x_rad_s..z``
``/ftcomp/events``              ``rcl_interfaces/msg/Log``           events (pose, grasp, end)
==============================  ===================================  ===========================

The temperature and IMU channels are a sensor's extra channels
(:class:`~ftcomp.hardware.protocols.ReportsExtraChannels`), in the sensor frame; an IMU message
has no orientation (``orientation_covariance[0] = -1``, as ``sensor_msgs/Imu`` says of an
unknown one) and unknown covariances (zeros). A row's stamp (its ``t_ns``) is every message's
log time and header stamp, except the wrenches, temperature and IMU of a ``run`` or ``sim
place`` log, stamped with the sample's own time (``t_sample_s``). Log times
are the session clock: simulation time for ``sim://``, so a simulated run starts near
1970-01-01 in a viewer.

Writer: rosbags' rosbag2 writer with its MCAP storage, the library that reads the bags too: one
dependency serialises (its typestore's CDR) and writes (profile ``ros2``, chunked, indexed, with
a summary), and what it writes it reads back. It writes a rosbag2 *directory*; the MCAP file in it
is self-contained (schemas, channels, messages), so :meth:`McapLog.close` moves that file to the
requested path and removes the rest. :class:`McapLog` is that writer (channels, CDR messages, the
file moved into place); :class:`SessionMcapLog` is the one that turns rows into messages.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import IMU_CHANNELS, TEMPERATURE_CHANNEL
from ftcomp.ros2.tf import clean_frame

__all__ = ["CHANNEL_COLUMNS", "SESSION_TOPICS", "TOPICS", "McapLog", "RowLayout", "SessionMcapLog"]

_NS = 1_000_000_000
#: A message's numbers: a row's slice or an array.
Values = Sequence[float] | NDArray[np.float64]
WRENCH = "geometry_msgs/msg/WrenchStamped"
#: The topics of a log's wrenches, pose and command, with their message types.
TOPICS: dict[str, str] = {
    "/ftcomp/wrench_raw": WRENCH,
    "/ftcomp/wrench_compensated": WRENCH,
    "/tf": "tf2_msgs/msg/TFMessage",
    "/ftcomp/twist_command": "geometry_msgs/msg/TwistStamped",
}
#: Every topic a session's log may hold (the columns of its rows decide which), with its type.
SESSION_TOPICS: dict[str, str] = {
    **TOPICS,
    "/ftcomp/wrench_error": WRENCH,
    "/ftcomp/load": "std_msgs/msg/Float64MultiArray",
    "/ftcomp/temperature": "sensor_msgs/msg/Temperature",
    "/ftcomp/imu": "sensor_msgs/msg/Imu",
    "/ftcomp/events": "rcl_interfaces/msg/Log",
}
_WRENCH = ("fx", "fy", "fz", "tx", "ty", "tz")
#: The log columns each channel of a session carries (a channel is there when all are).
CHANNEL_COLUMNS: dict[str, tuple[str, ...]] = {
    "/ftcomp/wrench_raw": _WRENCH,
    "/ftcomp/wrench_compensated": tuple(f"c{c}" for c in _WRENCH),
    "/tf": ("qx", "qy", "qz", "qw", "px", "py", "pz"),
    "/ftcomp/wrench_error": ("ex", "ey", "ez", "etx", "ety", "etz"),
    "/ftcomp/twist_command": ("vx", "vy", "vz", "wx", "wy", "wz"),
    "/ftcomp/temperature": (TEMPERATURE_CHANNEL,),
    "/ftcomp/imu": IMU_CHANNELS,
}
LOAD_TOPIC = "/ftcomp/load"


class RowLayout:
    """Where each channel's values are in a session's log rows (from its columns).

    Attributes:
        channels: topic -> the indices of its values in a row (:data:`CHANNEL_COLUMNS` order),
            for each channel whose columns are all there.
        load: indices of the online load's columns (``load_*``; empty without them).
        load_columns: their names.
    """

    def __init__(self, columns: Sequence[str]) -> None:
        index = {name: k for k, name in enumerate(columns)}
        self.channels: dict[str, list[int]] = {
            topic: [index[n] for n in names]
            for topic, names in CHANNEL_COLUMNS.items()
            if all(n in index for n in names)
        }
        self.load_columns = tuple(n for n in columns if n.startswith("load_"))
        self.load = [index[n] for n in self.load_columns]
        self._offset = (
            (index["t_s"], index["t_sample_s"])
            if "t_s" in index and "t_sample_s" in index
            else None
        )

    def sample_ns(self, t_ns: int, row: Sequence[float]) -> int:
        """The stamp of the row's wrench samples [ns]: the row's own, or in a run's log (which
        has ``t_sample_s`` beside ``t_s``) the sample's."""
        if self._offset is None:
            return t_ns
        k_now, k_sample = self._offset
        return t_ns + round((row[k_sample] - row[k_now]) * 1e9)


#: rcl_interfaces/msg/Log levels of the event kinds (INFO 20, WARN 30, ERROR 40).
_EVENT_LEVELS = {"fault": 40, "contact": 30}


class McapLog:
    """An MCAP file of ROS 2 messages on channels (see the module docstring).

    A context manager; leaving it (also by an exception) finishes the file with what was logged.

    Args:
        path: the ``.mcap`` file to write.
        base_frame: the robot's base frame id.
        sensor_frame: the sensor's frame id.
        overwrite: replace an existing file (else an existing file is an error).
        topics: the channels opened at once (more with :meth:`add_topic`).

    Raises:
        ParameterError: the file exists (and not ``overwrite``), or is a directory.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        base_frame: str = "base",
        sensor_frame: str = "ft_sensor",
        overwrite: bool = False,
        topics: Mapping[str, str] = TOPICS,
    ) -> None:
        self.path = Path(path)
        if self.path.is_dir():
            raise ParameterError(f"{self.path}: is a directory, expected an .mcap file path")
        if self.path.exists() and not overwrite:
            raise ParameterError(f"{self.path}: exists; remove it or choose another log file")
        self.base_frame = clean_frame(base_frame)
        self.sensor_frame = clean_frame(sensor_frame)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._tmp = Path(tempfile.mkdtemp(prefix=f".{self.path.name}.", dir=self.path.parent))
        self._store = get_typestore(Stores.ROS2_HUMBLE)
        self._T = self._store.types
        self._writer: Writer | None = Writer(
            self._tmp / "log", version=9, storage_plugin=StoragePlugin.MCAP
        )
        self._writer.open()
        self._conns: dict[str, Any] = {}
        self._types: dict[str, str] = {}
        #: Messages written per topic.
        self.counts: dict[str, int] = {}
        for topic, msgtype in topics.items():
            self.add_topic(topic, msgtype)

    def add_topic(self, topic: str, msgtype: str) -> None:
        """Open a channel for ``topic`` with ROS 2 message type ``msgtype``."""
        if self._writer is None:
            raise ParameterError(f"{self.path}: the log is closed")
        self._conns[topic] = self._writer.add_connection(topic, msgtype, typestore=self._store)
        self._types[topic] = msgtype
        self.counts[topic] = 0

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    # ----------------------------------------------------------------- messages
    def _header(self, t_ns: int, frame: str) -> Any:
        stamp = self._T["builtin_interfaces/msg/Time"](sec=t_ns // _NS, nanosec=t_ns % _NS)
        return self._T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def _vector(self, v: Values) -> Any:
        return self._T["geometry_msgs/msg/Vector3"](x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def _wrench(self, t_ns: int, w: Values, frame: str | None = None) -> Any:
        wrench = self._T["geometry_msgs/msg/Wrench"](
            force=self._vector(w[:3]), torque=self._vector(w[3:])
        )
        header = self._header(t_ns, self.sensor_frame if frame is None else frame)
        return self._T[WRENCH](header=header, wrench=wrench)

    def _tf_quat(self, t_ns: int, p: Values, q_xyzw: Values) -> Any:
        x, y, z, w = (float(v) for v in q_xyzw)
        T = self._T
        transform = T["geometry_msgs/msg/Transform"](
            translation=self._vector(p),
            rotation=T["geometry_msgs/msg/Quaternion"](x=x, y=y, z=z, w=w),
        )
        stamped = T["geometry_msgs/msg/TransformStamped"](
            header=self._header(t_ns, self.base_frame),
            child_frame_id=self.sensor_frame,
            transform=transform,
        )
        return T["tf2_msgs/msg/TFMessage"](transforms=[stamped])

    def _twist(self, t_ns: int, twist: Values) -> Any:
        T = self._T
        body = T["geometry_msgs/msg/Twist"](
            linear=self._vector(twist[:3]), angular=self._vector(twist[3:])
        )
        return T["geometry_msgs/msg/TwistStamped"](
            header=self._header(t_ns, self.base_frame), twist=body
        )

    def _temperature(self, t_ns: int, temperature_C: float) -> Any:
        return self._T["sensor_msgs/msg/Temperature"](
            header=self._header(t_ns, self.sensor_frame),
            temperature=float(temperature_C),
            variance=0.0,
        )

    def _imu(self, t_ns: int, accel_gyro: Values) -> Any:
        T = self._T
        unknown = np.zeros(9)
        no_orientation = np.zeros(9)
        no_orientation[0] = -1.0  # sensor_msgs/Imu: the orientation is not estimated
        return T["sensor_msgs/msg/Imu"](
            header=self._header(t_ns, self.sensor_frame),
            orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
            orientation_covariance=no_orientation,
            angular_velocity=self._vector(accel_gyro[3:]),
            angular_velocity_covariance=unknown,
            linear_acceleration=self._vector(accel_gyro[:3]),
            linear_acceleration_covariance=unknown,
        )

    def write(self, topic: str, log_ns: int, message: Any) -> None:
        """Serialise ``message`` (CDR) and write it on ``topic`` at log time ``log_ns``."""
        if self._writer is None:
            raise ParameterError(f"{self.path}: the log is closed")
        data = self._store.serialize_cdr(message, self._types[topic])
        self._writer.write(self._conns[topic], max(0, int(log_ns)), data)
        self.counts[topic] += 1

    def close(self) -> None:
        """Finish the MCAP file and move it into place (idempotent)."""
        self._finish(keep=True)

    def _finish(self, *, keep: bool) -> None:
        if self._writer is None:
            return
        writer, self._writer = self._writer, None
        try:
            writer.close()
            if keep:
                os.replace(self._tmp / "log" / "log.mcap", self.path)
        finally:
            shutil.rmtree(self._tmp, ignore_errors=True)


class SessionMcapLog(McapLog):
    """A live session's log rows and events as MCAP (a :class:`~ftcomp.session.log.LogObserver`).

    The channels are those of :data:`SESSION_TOPICS` whose columns the session's rows have
    (see the module docstring); the events channel is always there.

    Args:
        path: the ``.mcap`` file to write.
        base_frame: the robot's base frame id.
        sensor_frame: the sensor's frame id.
        control_frame: the frame id of the wrench error (the controller's frame).
        overwrite: replace an existing file.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        base_frame: str = "base",
        sensor_frame: str = "ft_sensor",
        control_frame: str = "base",
        overwrite: bool = False,
    ) -> None:
        super().__init__(
            path,
            base_frame=base_frame,
            sensor_frame=sensor_frame,
            overwrite=overwrite,
            topics={"/ftcomp/events": SESSION_TOPICS["/ftcomp/events"]},
        )
        self.control_frame = clean_frame(control_frame)
        self.layout = RowLayout(())
        self.opened = False

    def open(self, columns: Sequence[str]) -> None:
        """Open the channels the columns fill."""
        self.opened = True
        self.layout = RowLayout(columns)
        for topic in self.layout.channels:
            self.add_topic(topic, SESSION_TOPICS[topic])
        if self.layout.load:
            self.add_topic(LOAD_TOPIC, SESSION_TOPICS[LOAD_TOPIC])

    def row(self, t_ns: int, row: Sequence[float]) -> None:
        """Write one row's messages, at log time ``t_ns`` [ns]."""
        now = max(0, int(t_ns))
        layout = self.layout
        t_sample = max(0, layout.sample_ns(now, row))
        for topic, columns in layout.channels.items():
            values = [row[k] for k in columns]
            if topic == "/tf":
                message = self._tf_quat(now, values[4:], values[:4])
            elif topic == "/ftcomp/twist_command":
                message = self._twist(now, values)
            elif topic == "/ftcomp/wrench_error":
                message = self._wrench(now, values, self.control_frame)
            elif topic == "/ftcomp/temperature":
                message = self._temperature(t_sample, values[0])
            elif topic == "/ftcomp/imu":
                message = self._imu(t_sample, values)
            else:
                message = self._wrench(t_sample, values)
            self.write(topic, now, message)
        if layout.load:
            self.write(LOAD_TOPIC, now, self._array([float(row[k]) for k in layout.load]))

    def _array(self, values: list[float]) -> Any:
        T = self._T
        dim = T["std_msgs/msg/MultiArrayDimension"](
            label=",".join(self.layout.load_columns), size=len(values), stride=len(values)
        )
        layout = T["std_msgs/msg/MultiArrayLayout"](dim=[dim], data_offset=0)
        return T["std_msgs/msg/Float64MultiArray"](
            layout=layout, data=np.asarray(values, dtype=np.float64)
        )

    def close(self) -> None:
        """Finish the file and move it into place; a log no session opened (the command failed
        before its session began) leaves no file (idempotent)."""
        self._finish(keep=self.opened)

    def event(self, t_ns: int, kind: str, text: str) -> None:
        """Write an event on ``/ftcomp/events``."""
        now = max(0, int(t_ns))
        stamp = self._T["builtin_interfaces/msg/Time"](sec=now // _NS, nanosec=now % _NS)
        message = self._T["rcl_interfaces/msg/Log"](
            stamp=stamp,
            level=_EVENT_LEVELS.get(kind, 20),
            name=f"ftcomp.{kind}",
            msg=text,
            file="",
            function="",
            line=0,
        )
        self.write("/ftcomp/events", now, message)
