"""Control-loop logs as MCAP files in the ROS 2 profile, for rosbags, Foxglove and Lichtblick.

:class:`McapLog` is a sink of :func:`ftcomp.control.loop.run_loop` (``sink(reading, twist)``):
every cycle it writes, CDR-encoded with the standard ROS 2 message definitions embedded
(``ros2msg`` schemas):

==============================  ==================================  ==========================
topic                           type                                content
==============================  ==================================  ==========================
``/ftcomp/wrench_raw``          ``geometry_msgs/msg/WrenchStamped``  the reading, sensor frame
``/ftcomp/wrench_compensated``  ``geometry_msgs/msg/WrenchStamped``  the contact wrench
``/tf``                         ``tf2_msgs/msg/TFMessage``          base -> sensor pose
``/ftcomp/twist_command``       ``geometry_msgs/msg/TwistStamped``  the commanded sensor twist
==============================  ==================================  ==========================

Wrenches are stamped with the sample's ``t_sample_ns``; pose and twist with the cycle's
``now_ns``; the log time of every message is ``now_ns`` (the session clock: simulation time for
``sim://``, so a simulated run starts near 1970-01-01 in a viewer).

Writer: rosbags' rosbag2 writer with its MCAP storage, the library that reads the bags too: one
dependency serialises (its typestore's CDR) and writes (profile ``ros2``, chunked, indexed, with
a summary), and what it writes it reads back. It writes a rosbag2 *directory*; the MCAP file in it
is self-contained (schemas, channels, messages), so :meth:`McapLog.close` moves that file to the
requested path and removes the rest.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from ftcomp.errors import ParameterError
from ftcomp.ros2.tf import clean_frame

if TYPE_CHECKING:
    from ftcomp.control.loop import Reading

__all__ = ["TOPICS", "McapLog"]

_NS = 1_000_000_000
WRENCH = "geometry_msgs/msg/WrenchStamped"
#: Every topic a log holds, with its message type.
TOPICS: dict[str, str] = {
    "/ftcomp/wrench_raw": WRENCH,
    "/ftcomp/wrench_compensated": WRENCH,
    "/tf": "tf2_msgs/msg/TFMessage",
    "/ftcomp/twist_command": "geometry_msgs/msg/TwistStamped",
}


class McapLog:
    """Writes each control cycle to an MCAP file (see the module docstring).

    A context manager; leaving it (also by an exception) finishes the file with what was logged.

    Args:
        path: the ``.mcap`` file to write.
        base_frame: the robot's base frame id.
        sensor_frame: the sensor's frame id.
        overwrite: replace an existing file (else an existing file is an error).

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
        self._conns = {
            topic: self._writer.add_connection(topic, msgtype, typestore=self._store)
            for topic, msgtype in TOPICS.items()
        }
        #: Messages written per topic.
        self.counts: dict[str, int] = dict.fromkeys(TOPICS, 0)

    def __enter__(self) -> McapLog:
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

    def _vector(self, v: NDArray[np.float64]) -> Any:
        return self._T["geometry_msgs/msg/Vector3"](x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def _wrench(self, t_ns: int, w: NDArray[np.float64]) -> Any:
        wrench = self._T["geometry_msgs/msg/Wrench"](
            force=self._vector(w[:3]), torque=self._vector(w[3:])
        )
        return self._T[WRENCH](header=self._header(t_ns, self.sensor_frame), wrench=wrench)

    def _tf(self, t_ns: int, p: NDArray[np.float64], R: NDArray[np.float64]) -> Any:
        from scipy.spatial.transform import Rotation

        x, y, z, w = Rotation.from_matrix(R).as_quat()
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

    def _twist(self, t_ns: int, twist: NDArray[np.float64]) -> Any:
        T = self._T
        body = T["geometry_msgs/msg/Twist"](
            linear=self._vector(twist[:3]), angular=self._vector(twist[3:])
        )
        return T["geometry_msgs/msg/TwistStamped"](
            header=self._header(t_ns, self.base_frame), twist=body
        )

    def write(self, topic: str, log_ns: int, message: Any) -> None:
        """Serialise ``message`` (CDR) and write it on ``topic`` at log time ``log_ns``."""
        if self._writer is None:
            raise ParameterError(f"{self.path}: the log is closed")
        data = self._store.serialize_cdr(message, TOPICS[topic])
        self._writer.write(self._conns[topic], max(0, int(log_ns)), data)
        self.counts[topic] += 1

    def __call__(self, reading: Reading, twist: NDArray[np.float64]) -> None:
        """Log one cycle (the :func:`~ftcomp.control.loop.run_loop` sink signature)."""
        now = max(0, int(reading.now_ns))
        t_sample = max(0, int(reading.t_sample_ns))
        self.write("/ftcomp/wrench_raw", now, self._wrench(t_sample, reading.wrench_raw_sensor))
        self.write(
            "/ftcomp/wrench_compensated",
            now,
            self._wrench(t_sample, reading.wrench_contact_sensor),
        )
        self.write("/tf", now, self._tf(now, reading.p_base_sensor, reading.R_base_sensor))
        self.write("/ftcomp/twist_command", now, self._twist(now, np.asarray(twist, dtype=float)))

    def close(self) -> None:
        """Finish the MCAP file and move it into place (idempotent)."""
        if self._writer is None:
            return
        writer, self._writer = self._writer, None
        try:
            writer.close()
            os.replace(self._tmp / "log" / "log.mcap", self.path)
        finally:
            shutil.rmtree(self._tmp, ignore_errors=True)
