"""Reading ROS bags without ROS: rosbag2 (MCAP, sqlite3) and ROS 1 bags through ``rosbags``.

``rosbags``' :class:`~rosbags.highlevel.AnyReader` opens every kind of bag and builds its
typestore from the message definitions the bag carries (a bag without them is read with the ROS 2
Humble definitions of the standard messages). This module is the one place that speaks rosbags'
reader API; it returns plain arrays in the units and frames of the messages:

- ``geometry_msgs/msg/WrenchStamped`` -> :class:`WrenchSeries` (N, N*m in ``header.frame_id``);
- ``tf2_msgs/msg/TFMessage`` on ``/tf`` and ``/tf_static`` -> a
  :class:`~ftcomp.ros2.tf.TransformTree`;
- ``sensor_msgs/msg/JointState`` -> :class:`JointStates` (rad or m per joint).

Time stamps are the messages' ``header.stamp`` as integer nanoseconds; a topic whose stamps are
all zero (a driver that never sets them) falls back to the bag's receive times, with a warning.
Every problem (no such file, not a bag, a missing topic, a topic of another type) is an
:class:`~ftcomp.errors.InputFileError` naming the bag and the topic.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from rosbags.highlevel import AnyReader
from rosbags.interfaces import Connection
from rosbags.typesys import Stores, get_typestore

from ftcomp.errors import InputFileError
from ftcomp.ros2.tf import TransformRecord, TransformTree, clean_frame

__all__ = [
    "JOINT_STATE_TYPE",
    "TF_TYPES",
    "WRENCH_TYPE",
    "JointStates",
    "WrenchSeries",
    "open_bag",
    "read_joint_states",
    "read_transforms",
    "read_wrenches",
]

WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
JOINT_STATE_TYPE = "sensor_msgs/msg/JointState"
#: ROS 2 and ROS 1 (``tf2_msgs``, and the older ``tf``) transform messages.
TF_TYPES = ("tf2_msgs/msg/TFMessage", "tf/msg/tfMessage")
_NS = 1_000_000_000


@dataclass(frozen=True)
class WrenchSeries:
    """Every reading of one ``WrenchStamped`` topic.

    Attributes:
        topic: the topic.
        t_ns: stamps [ns], shape (N,), increasing.
        wrench: ``[fx, fy, fz, tx, ty, tz]`` [N, N*m] in ``frame_id``, shape (N, 6).
        frame_id: the readings' ``header.frame_id`` (without a leading ``/``).
        warnings: e.g. the stamps came from the bag's receive times.
    """

    topic: str
    t_ns: NDArray[np.int64] = field(repr=False)
    wrench: NDArray[np.float64] = field(repr=False)
    frame_id: str
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class JointStates:
    """Every message of a ``JointState`` topic, positions by joint name.

    Attributes:
        topic: the topic.
        t_ns: stamps [ns], shape (M,), increasing.
        names: the joint names, in the order of ``positions``' columns.
        positions: [rad or m], shape (M, J); NaN where a message did not name a joint.
    """

    topic: str
    t_ns: NDArray[np.int64] = field(repr=False)
    names: tuple[str, ...]
    positions: NDArray[np.float64] = field(repr=False)


@contextmanager
def open_bag(path: str | os.PathLike[str]) -> Iterator[AnyReader]:
    """The open bag: a rosbag2 directory, a ``.mcap`` or ``.db3`` file, or a ROS 1 ``.bag``.

    Raises:
        InputFileError: no such file, or not a bag rosbags can read.
    """
    bag = Path(path)
    if not bag.exists():
        raise InputFileError(f"{bag}: no such file or directory")
    humble = get_typestore(Stores.ROS2_HUMBLE)
    try:
        reader = AnyReader([bag], default_typestore=humble)
        reader.open()
    except Exception as exc:  # rosbags raises several kinds for unreadable input
        raise InputFileError(f"{bag}: not a readable ROS bag ({_reason(exc)})") from None
    try:
        yield reader
    finally:
        reader.close()


def _reason(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _connections(
    reader: AnyReader, topic: str, msgtypes: tuple[str, ...], source: str
) -> list[Connection]:
    conns = [c for c in reader.connections if c.topic == topic]
    if not conns:
        of_type = sorted({c.topic for c in reader.connections if c.msgtype in msgtypes})
        offer = ", ".join(of_type) if of_type else "none"
        raise InputFileError(
            f"{source}: no topic {topic!r} in the bag; topics of type {msgtypes[0]}: {offer}"
        )
    bad = [c.msgtype for c in conns if c.msgtype not in msgtypes]
    if bad:
        raise InputFileError(
            f"{source}: topic {topic!r} has type {bad[0]}, expected {' or '.join(msgtypes)}"
        )
    return conns


def _messages(reader: AnyReader, conns: list[Connection], source: str) -> Iterator[tuple[int, Any]]:
    """``(receive time [ns], message)`` of the connections, in time order."""
    try:
        for conn, log_ns, raw in reader.messages(connections=conns):
            yield log_ns, reader.deserialize(raw, conn.msgtype)
    except InputFileError:
        raise
    except Exception as exc:
        raise InputFileError(
            f"{source}: cannot read topic {conns[0].topic!r} ({_reason(exc)})"
        ) from None


def _stamp_ns(header: Any) -> int:
    return int(header.stamp.sec) * _NS + int(header.stamp.nanosec)


def _choose_stamps(
    header_ns: list[int], log_ns: list[int], topic: str, source: str
) -> tuple[NDArray[np.int64], list[str]]:
    if any(header_ns):
        return np.array(header_ns, dtype=np.int64), []
    warning = f"{source}: every header.stamp on {topic} is zero; using the bag's receive times"
    return np.array(log_ns, dtype=np.int64), [warning]


def read_wrenches(reader: AnyReader, topic: str, source: str) -> WrenchSeries:
    """Every ``WrenchStamped`` on ``topic``, sorted by stamp.

    Raises:
        InputFileError: the topic is missing, of another type, empty, or has readings in more
            than one frame.
    """
    conns = _connections(reader, topic, (WRENCH_TYPE,), source)
    header_ns: list[int] = []
    log_ns: list[int] = []
    values: list[tuple[float, ...]] = []
    frames: set[str] = set()
    for t_log, msg in _messages(reader, conns, source):
        log_ns.append(t_log)
        header_ns.append(_stamp_ns(msg.header))
        frames.add(clean_frame(msg.header.frame_id))
        f, m = msg.wrench.force, msg.wrench.torque
        values.append((f.x, f.y, f.z, m.x, m.y, m.z))
    if not values:
        raise InputFileError(f"{source}: topic {topic!r} holds no messages")
    if len(frames) > 1:
        raise InputFileError(
            f"{source}: topic {topic!r} has readings in frames {', '.join(sorted(frames))}; "
            "expected one"
        )
    t, warnings = _choose_stamps(header_ns, log_ns, topic, source)
    order = np.argsort(t, kind="stable")
    wrench = np.array(values, dtype=float)[order]
    if not np.isfinite(wrench).all():
        bad = int(np.flatnonzero(~np.isfinite(wrench).all(axis=1))[0])
        raise InputFileError(f"{source}: topic {topic!r}, message {bad + 1}: a non-finite value")
    return WrenchSeries(topic, t[order], wrench, frames.pop(), tuple(warnings))


def read_transforms(
    reader: AnyReader, source: str, topics: tuple[str, str] = ("/tf", "/tf_static")
) -> TransformTree:
    """The transform tree of the bag's ``/tf`` (dynamic) and ``/tf_static`` topics.

    Raises:
        InputFileError: neither topic is in the bag, or one has another type.
    """
    dynamic, static = topics
    present = {c.topic for c in reader.connections}
    if dynamic not in present and static not in present:
        raise InputFileError(
            f"{source}: no {dynamic} or {static} topic for the sensor's pose; record them, "
            "or give the robot description and joint states (--urdf, --joint-states)"
        )
    records: list[TransformRecord] = []
    for topic in topics:
        if topic not in present:
            continue
        conns = _connections(reader, topic, TF_TYPES, source)
        for _t_log, msg in _messages(reader, conns, source):
            for tr in msg.transforms:
                v, q = tr.transform.translation, tr.transform.rotation
                records.append(
                    TransformRecord(
                        _stamp_ns(tr.header),
                        tr.header.frame_id,
                        tr.child_frame_id,
                        (v.x, v.y, v.z),
                        (q.x, q.y, q.z, q.w),
                        topic == static,
                    )
                )
    return TransformTree(records, source)


def read_joint_states(reader: AnyReader, topic: str, source: str) -> JointStates:
    """Every ``JointState`` on ``topic``, sorted by stamp.

    Raises:
        InputFileError: the topic is missing, of another type, or empty; a message with fewer
            positions than names.
    """
    conns = _connections(reader, topic, (JOINT_STATE_TYPE,), source)
    header_ns: list[int] = []
    log_ns: list[int] = []
    rows: list[dict[str, float]] = []
    names: dict[str, None] = {}
    for t_log, msg in _messages(reader, conns, source):
        if len(msg.position) < len(msg.name):
            raise InputFileError(
                f"{source}: topic {topic!r}, message {len(rows) + 1}: {len(msg.name)} joint "
                f"names but {len(msg.position)} positions"
            )
        log_ns.append(t_log)
        header_ns.append(_stamp_ns(msg.header))
        row = {str(n): float(p) for n, p in zip(msg.name, msg.position, strict=False)}
        names.update(dict.fromkeys(row))
        rows.append(row)
    if not rows:
        raise InputFileError(f"{source}: topic {topic!r} holds no messages")
    t, _ = _choose_stamps(header_ns, log_ns, topic, source)
    order = np.argsort(t, kind="stable")
    joint_names = tuple(names)
    positions = np.array([[row.get(n, np.nan) for n in joint_names] for row in rows], dtype=float)
    return JointStates(topic, t[order], joint_names, positions[order])
