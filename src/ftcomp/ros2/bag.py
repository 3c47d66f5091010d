"""Reading ROS bags without ROS: rosbag2 (MCAP, sqlite3) and ROS 1 bags through ``rosbags``.

:func:`open_bag` opens a bag with ``rosbags``' storage readers and builds a typestore only for the
types ftcomp reads (:data:`READ_TYPES`), from the definitions the bag carries (a bag without them
is read with the ROS 2 Humble definitions of the standard messages). Every other connection is
left alone: a service-event channel (``ros2 bag record`` with services), a camera, a custom type
whose definition rosbags cannot parse or the typestore does not know does not stop the import;
such a connection is named, with its type, in a warning (:attr:`Bag.warnings`). This module is
the one place that speaks rosbags' reader API; it returns plain arrays in the units and frames of
the messages:

- ``geometry_msgs/msg/WrenchStamped`` -> :class:`WrenchSeries` (N, N*m in ``header.frame_id``,
  or in the frame the caller states);
- ``tf2_msgs/msg/TFMessage`` on ``/tf`` and ``/tf_static`` -> a
  :class:`~ftcomp.ros2.tf.TransformTree`;
- ``sensor_msgs/msg/JointState`` -> :class:`JointStates` (rad or m per joint).

Time stamps are the messages' ``header.stamp`` as integer nanoseconds; a topic whose stamps are
all zero (a driver that never sets them) falls back to the bag's receive times, with a warning.
Every problem (no such file, not a bag, a missing topic, a topic of another type, a definition of
a needed type that cannot be parsed, with rosbags' whole reason) is an
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
from rosbags.interfaces import Connection, MessageDefinitionFormat
from rosbags.rosbag1 import Reader as Reader1
from rosbags.rosbag2 import Reader as Reader2
from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from ftcomp.errors import InputFileError
from ftcomp.ros2.tf import TransformRecord, TransformTree, clean_frame

__all__ = [
    "JOINT_STATE_TYPE",
    "READ_TYPES",
    "TF_TYPES",
    "WRENCH_TYPE",
    "Bag",
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
#: The message types ftcomp reads; no other connection's definition is parsed.
READ_TYPES = (WRENCH_TYPE, JOINT_STATE_TYPE, *TF_TYPES)
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


class Bag:
    """An open bag: its connections, and the messages of the types ftcomp reads.

    Attributes:
        source: the bag, as given (for messages).
        connections: every connection in the bag.
        warnings: connections left unread because their type's definition cannot be parsed
            or is unknown (named with their type).
    """

    def __init__(self, reader: Reader1 | Reader2, source: str) -> None:
        self._reader = reader
        self._ros1 = isinstance(reader, Reader1)
        self._stores: dict[str, Typestore] = {}
        self.source = source
        self.connections: tuple[Connection, ...] = tuple(reader.connections)
        self.warnings: tuple[str, ...] = tuple(
            f"{source}: skipped topic {c.topic!r} of type {c.msgtype} ({why})"
            for c in self.connections
            if c.msgtype not in READ_TYPES and (why := _unreadable(c)) is not None
        )

    def typestore(self, conn: Connection) -> Typestore:
        """The typestore of ``conn``'s type, built from the bag's definition of it.

        Raises:
            InputFileError: the definition cannot be parsed (with rosbags' whole reason).
        """
        if conn.msgtype not in self._stores:
            try:
                types = _definitions(conn)
                store = get_typestore(Stores.EMPTY)
                store.register(types)
                store.generate_msgdef(conn.msgtype)  # resolves every nested type
            except Exception as exc:
                raise InputFileError(
                    f"{self.source}: cannot parse the definition of {conn.msgtype} on topic "
                    f"{conn.topic!r} ({_reason(exc)})"
                ) from None
            self._stores[conn.msgtype] = store
        return self._stores[conn.msgtype]

    def messages(self, conns: list[Connection]) -> Iterator[tuple[int, Any]]:
        """``(receive time [ns], message)`` of the connections, in time order.

        Raises:
            InputFileError: a definition or a message cannot be read.
        """
        stores = {c.id: self.typestore(c) for c in conns}
        try:
            for conn, log_ns, raw in self._reader.messages(connections=conns):
                store = stores[conn.id]
                if self._ros1:
                    yield log_ns, store.deserialize_ros1(raw, conn.msgtype)
                else:
                    yield log_ns, store.deserialize_cdr(raw, conn.msgtype)
        except InputFileError:
            raise
        except Exception as exc:
            raise InputFileError(
                f"{self.source}: cannot read topic {conns[0].topic!r} ({_reason(exc)})"
            ) from None


def _definitions(conn: Connection) -> dict[str, Any]:
    """The type definitions ``conn`` carries (the Humble ones when it carries none)."""
    fmt, text = conn.msgdef.format, conn.msgdef.data
    if fmt == MessageDefinitionFormat.NONE or not text.strip():
        humble = get_typestore(Stores.ROS2_HUMBLE)
        if conn.msgtype not in humble.fielddefs:
            raise InputFileError(f"the bag has no definition of {conn.msgtype}")
        return dict(humble.fielddefs)
    if fmt == MessageDefinitionFormat.MSG:
        return dict(get_types_from_msg(text, conn.msgtype))
    sep = "=" * 80 + "\n"
    types: dict[str, Any] = {}
    if text.startswith(f"{sep}IDL: "):
        for part in text.split(sep)[1:]:
            types.update(get_types_from_idl(part.split("\n", 1)[1]))
    else:
        types.update(get_types_from_idl(text))
    return types


def _unreadable(conn: Connection) -> str | None:
    """Why ``conn``'s type could not be read, or None when it could."""
    try:
        store = get_typestore(Stores.EMPTY)
        store.register(_definitions(conn))
        store.generate_msgdef(conn.msgtype)  # resolves every nested type
    except InputFileError:
        return "no definition in the bag"
    except Exception as exc:
        return f"its definition cannot be read: {_reason(exc)}"
    return None


@contextmanager
def open_bag(path: str | os.PathLike[str]) -> Iterator[Bag]:
    """The open bag: a rosbag2 directory, a ``.mcap`` or ``.db3`` file, or a ROS 1 ``.bag``.

    Raises:
        InputFileError: no such file, or not a bag rosbags can read.
    """
    bag = Path(path)
    if not bag.exists():
        raise InputFileError(f"{bag}: no such file or directory")
    try:
        reader: Reader1 | Reader2 = Reader1(bag) if bag.suffix == ".bag" else Reader2(bag)
        reader.open()
    except Exception as exc:  # rosbags raises several kinds for unreadable input
        raise InputFileError(f"{bag}: not a readable ROS bag ({_reason(exc)})") from None
    try:
        yield Bag(reader, str(bag))
    finally:
        reader.close()


def _reason(exc: BaseException) -> str:
    """The whole text of ``exc`` on one line (rosbags' first line may be empty)."""
    text = " ".join(line.strip() for line in str(exc).splitlines() if line.strip())
    return text if text else type(exc).__name__


def _connections(
    reader: Bag, topic: str, msgtypes: tuple[str, ...], source: str
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


def _stamp_ns(header: Any) -> int:
    return int(header.stamp.sec) * _NS + int(header.stamp.nanosec)


def _choose_stamps(
    header_ns: list[int], log_ns: list[int], topic: str, source: str
) -> tuple[NDArray[np.int64], list[str]]:
    if any(header_ns):
        return np.array(header_ns, dtype=np.int64), []
    warning = f"{source}: every header.stamp on {topic} is zero; using the bag's receive times"
    return np.array(log_ns, dtype=np.int64), [warning]


def read_wrenches(
    reader: Bag, topic: str, source: str, frame_id: str | None = None
) -> WrenchSeries:
    """Every ``WrenchStamped`` on ``topic``, sorted by stamp.

    Args:
        reader: the open bag.
        topic: the ``WrenchStamped`` topic.
        source: the bag's name for messages.
        frame_id: the frame the readings are in, when the caller knows it better than the
            headers (a driver that stamps sensor-frame readings with ``base_link`` or nothing);
            a header that says otherwise is then only a warning.

    Raises:
        InputFileError: the topic is missing, of another type, empty, or (without
            ``frame_id``) has readings in more than one frame.
    """
    conns = _connections(reader, topic, (WRENCH_TYPE,), source)
    header_ns: list[int] = []
    log_ns: list[int] = []
    values: list[tuple[float, ...]] = []
    frames: set[str] = set()
    for t_log, msg in reader.messages(conns):
        log_ns.append(t_log)
        header_ns.append(_stamp_ns(msg.header))
        frames.add(clean_frame(msg.header.frame_id))
        f, m = msg.wrench.force, msg.wrench.torque
        values.append((f.x, f.y, f.z, m.x, m.y, m.z))
    if not values:
        raise InputFileError(f"{source}: topic {topic!r} holds no messages")
    notes: list[str] = []
    if frame_id is not None:
        stated = clean_frame(frame_id)
        if frames != {stated}:
            said = ", ".join(repr(f) for f in sorted(frames))
            notes.append(
                f"{source}: readings on {topic} say header.frame_id {said}; taken as in "
                f"{stated!r} as stated (wrench_frame)"
            )
        frames = {stated}
    elif len(frames) > 1:
        raise InputFileError(
            f"{source}: topic {topic!r} has readings in frames {', '.join(sorted(frames))}; "
            "expected one (give the readings' frame as wrench_frame)",
            field="wrench_frame",
        )
    t, warnings = _choose_stamps(header_ns, log_ns, topic, source)
    order = np.argsort(t, kind="stable")
    wrench = np.array(values, dtype=float)[order]
    if not np.isfinite(wrench).all():
        bad = int(np.flatnonzero(~np.isfinite(wrench).all(axis=1))[0])
        raise InputFileError(f"{source}: topic {topic!r}, message {bad + 1}: a non-finite value")
    return WrenchSeries(topic, t[order], wrench, frames.pop(), (*notes, *warnings))


def read_transforms(
    reader: Bag, source: str, topics: tuple[str, str] = ("/tf", "/tf_static")
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
            "or give the robot description and joint states (urdf, joint_states_topic)",
            field=("urdf", "joint_states_topic"),
        )
    records: list[TransformRecord] = []
    for topic in topics:
        if topic not in present:
            continue
        conns = _connections(reader, topic, TF_TYPES, source)
        for _t_log, msg in reader.messages(conns):
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


def read_joint_states(reader: Bag, topic: str, source: str) -> JointStates:
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
    for t_log, msg in reader.messages(conns):
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
