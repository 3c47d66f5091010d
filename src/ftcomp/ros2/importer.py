"""Calibration samples from a ROS bag: wrenches, the sensor's pose at each, still segments.

:func:`import_bag` reads a ``WrenchStamped`` topic, puts the sensor's orientation in the base
frame at each reading's stamp (from ``/tf`` + ``/tf_static``, or from joint states and the URDF),
finds the still segments (:mod:`ftcomp.calibration.still`) and keeps their readings, one pose id per
segment. :func:`write_bag_samples` writes them as a sample CSV that ``ftcomp calibrate`` reads:
``pose, t_ns, t, qx, qy, qz, qw, fx, fy, fz, tx, ty, tz`` where ``t_ns`` is the reading's
``header.stamp`` in integer nanoseconds (exact) and ``t`` the seconds since the first reading of
the topic (the sample reader ignores ``t_ns`` as an extra column and reads ``t``).

A wrench in another frame than the sensor frame is moved into it when a *fixed* transform joins
the two (static tf, or only fixed joints in the URDF); otherwise it is an error. Drivers do not all
fill ``header.frame_id`` with the frame the readings are in: the ATI ``netft_rdt_driver``
publishes sensor-frame readings stamped ``base_link`` by default, some leave it empty.
``wrench_frame`` states the readings' frame; a header that disagrees is then a warning.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray
from rosbags.interfaces import Connection
from rosbags.typesys.store import Typestore
from scipy.spatial.transform import Rotation

from ftcomp.calibration.still import Segment, StillConfig, find_still_segments, segment_rows
from ftcomp.errors import InputFileError, ParameterError
from ftcomp.frames import ENCODING_COLUMNS, encode_orientation
from ftcomp.io.tables import write_table
from ftcomp.ros2.bag import Bag, open_bag, read_joint_states, read_transforms, read_wrenches
from ftcomp.ros2.tf import TransformTree
from ftcomp.ros2.urdf import UrdfChain
from ftcomp.samples import WRENCH_COLUMNS, Samples

__all__ = ["BagImport", "import_bag", "write_bag_samples"]

_NS = 1_000_000_000


@dataclass(frozen=True)
class BagImport:
    """What :func:`import_bag` found.

    Attributes:
        source: the bag.
        pose_source: how the poses were found (the tf chain, or the URDF and joint states).
        wrench_note: how the readings' frame was handled.
        t_ns: stamps of the kept readings [ns], shape (M,).
        wrench_sensor: kept readings [N, N*m], sensor frame, shape (M, 6).
        R_base_sensor: their orientations, shape (M, 3, 3).
        pose_ids: the segment id of each kept reading, shape (M,).
        segments: the still segments, in time order (pose id ``k + 1`` for ``segments[k]``).
        t0_ns: stamp of the topic's first reading [ns] (the CSV's ``t`` counts from it).
        readings_total: readings on the wrench topic.
        readings_without_pose: readings outside the recorded span of the pose source.
        unsettled: still orientations dropped because the wrench never settled.
        still: the thresholds used.
        warnings: things that look wrong but were accepted.
    """

    source: str
    pose_source: str
    wrench_note: str
    t_ns: NDArray[np.int64] = field(repr=False)
    wrench_sensor: NDArray[np.float64] = field(repr=False)
    R_base_sensor: NDArray[np.float64] = field(repr=False)
    pose_ids: NDArray[np.str_] = field(repr=False)
    segments: tuple[Segment, ...]
    t0_ns: int
    readings_total: int
    readings_without_pose: int
    unsettled: int
    still: StillConfig
    warnings: tuple[str, ...] = ()

    def samples(self) -> Samples:
        """The kept readings as :class:`~ftcomp.samples.Samples` (pose ids, ``t`` [s])."""
        return Samples(
            wrench_sensor=self.wrench_sensor,
            R_base_sensor=self.R_base_sensor,
            encoding="quaternion",
            pose=self.pose_ids,
            t=(self.t_ns - self.t0_ns) / _NS,
            source=self.source,
            warnings=self.warnings,
        )


def _transform_wrench(
    wrench: NDArray[np.float64], p_S_F: NDArray[np.float64], R_S_F: Rotation
) -> NDArray[np.float64]:
    """A wrench given in frame F (torques about F's origin) expressed in S, about S's origin."""
    force = R_S_F.apply(wrench[:, :3])
    torque = R_S_F.apply(wrench[:, 3:]) + np.cross(p_S_F, force)
    return np.hstack([force, torque])


def _fixed_pose(
    frame: str,
    sensor_frame: str,
    tree: TransformTree | None,
    urdf: Path | None,
    topic: str,
    source: str,
) -> tuple[NDArray[np.float64], Rotation]:
    """Pose of ``frame`` in the sensor frame, when a fixed transform joins them."""
    problem = f"{source}: readings on {topic} are in frame {frame!r}, not the sensor frame "
    problem += f"{sensor_frame!r}"
    hint = (
        " (if the driver stamps sensor-frame readings with another frame_id, as "
        "netft_rdt_driver's default 'base_link', give wrench_frame)"
    )
    if tree is not None:
        if frame not in tree.frames:
            raise InputFileError(
                f"{problem}, and {frame!r} is not in the tf tree{hint}", field="wrench_frame"
            )
        if not tree.is_static(sensor_frame, frame):
            raise InputFileError(
                f"{problem}, and the transform between them is not static{hint}",
                field="wrench_frame",
            )
        p, R, _ = tree.lookup(sensor_frame, frame, np.zeros(1, dtype=np.int64))
        return p[0], R[0]
    assert urdf is not None
    chain = UrdfChain(urdf, sensor_frame, frame)
    if chain.joint_names:
        raise InputFileError(
            f"{problem}, and joints {', '.join(chain.joint_names)} move between them{hint}",
            field="wrench_frame",
        )
    T = chain.forward({}, 1)[0]
    return T[:3, 3], Rotation.from_matrix(T[:3, :3])


#: Messages between two calls of :func:`import_bag`'s ``progress``.
_PROGRESS_EVERY = 2000


class _CountingBag:
    """A :class:`~ftcomp.ros2.bag.Bag` that tells ``progress`` how many of the messages it
    will read (``total``) it has read."""

    def __init__(self, bag: Bag, total: int, progress: Callable[[int, int], None]) -> None:
        self.bag, self.total, self.progress = bag, total, progress
        self.source, self.connections, self.warnings = bag.source, bag.connections, bag.warnings
        self.done = 0

    def typestore(self, conn: Connection) -> Typestore:
        return self.bag.typestore(conn)

    def messages(self, conns: list[Connection]) -> Iterator[tuple[int, Any]]:
        for item in self.bag.messages(conns):
            self.done += 1
            if self.done % _PROGRESS_EVERY == 0:
                self.progress(self.done, self.total)
            yield item
        self.progress(self.done, self.total)


def import_bag(
    path: str | os.PathLike[str],
    *,
    wrench_topic: str,
    base_frame: str,
    sensor_frame: str,
    still: StillConfig | None = None,
    urdf: str | os.PathLike[str] | None = None,
    joint_states_topic: str | None = None,
    wrench_frame: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> BagImport:
    """Read a bag and keep the readings of its still segments (see the module docstring).

    Args:
        path: the bag (rosbag2 directory, ``.mcap``, ``.db3``, or ROS 1 ``.bag``).
        wrench_topic: the ``geometry_msgs/msg/WrenchStamped`` topic.
        base_frame: the frame the orientations are given in (the robot's base).
        sensor_frame: the sensor's measuring frame.
        still: the still-segment thresholds (defaults: :class:`StillConfig`).
        urdf: with ``joint_states_topic``: take the pose from the joint states and this robot
            description instead of ``/tf``.
        joint_states_topic: the ``sensor_msgs/msg/JointState`` topic (with ``urdf``).
        wrench_frame: the frame the readings are in, whatever their ``header.frame_id`` says
            (default: the header's).
        progress: called every few thousand messages with ``(read, total)``: the messages
            read so far of the topics the import reads (wrench, tf, joint states) and their
            count in the bag (e.g. for a progress bar; default: none).

    Raises:
        InputFileError: an unreadable bag, a missing topic or frame, a wrench in an unexpected
            frame, or no still segment.
        ParameterError: ``urdf`` without ``joint_states_topic`` or the other way round.
    """
    if (urdf is None) != (joint_states_topic is None):
        raise ParameterError(
            "urdf and joint_states_topic go together: give both or neither",
            field=("urdf", "joint_states_topic"),
        )
    config = still if still is not None else StillConfig()
    source = str(path)
    urdf_path = Path(urdf) if urdf is not None else None
    tree: TransformTree | None = None
    with open_bag(path) as bag:
        reader = bag
        if progress is not None:
            poses = ("/tf", "/tf_static") if urdf_path is None else (joint_states_topic,)
            topics = {wrench_topic, *poses}
            total = sum(c.msgcount for c in bag.connections if c.topic in topics)
            # Read through the counting wrapper: it has every attribute of a Bag that the
            # readers use (source, connections, warnings, typestore, messages).
            reader = cast(Bag, _CountingBag(bag, total, progress))
        series = read_wrenches(reader, wrench_topic, source, wrench_frame)
        if urdf_path is None:
            tree = read_transforms(reader, source)
            frames = tree.chain(base_frame, sensor_frame)
            _, R, valid = tree.lookup(base_frame, sensor_frame, series.t_ns)
            pose_source = "tf " + " -> ".join(frames)
        else:
            assert joint_states_topic is not None
            chain = UrdfChain(urdf_path, base_frame, sensor_frame)
            states = read_joint_states(reader, joint_states_topic, source)
            _, R, valid = chain.sensor_poses(states, series.t_ns, source)
            pose_source = (
                f"{urdf_path.name} ({base_frame} -> {sensor_frame}, joints "
                f"{', '.join(chain.joint_names) or 'none'}) + {joint_states_topic}"
            )
    frame = series.frame_id
    wrench = series.wrench
    if not frame:
        raise InputFileError(
            f"{source}: readings on {wrench_topic} have an empty header.frame_id; "
            f"expected the sensor frame {sensor_frame!r} (state the readings' frame as "
            "wrench_frame)",
            field="wrench_frame",
        )
    if frame == sensor_frame:
        note = f"readings in the sensor frame {sensor_frame!r}"
    else:
        p_S_F, R_S_F = _fixed_pose(frame, sensor_frame, tree, urdf_path, wrench_topic, source)
        wrench = _transform_wrench(wrench, p_S_F, R_S_F)
        note = f"readings moved from frame {frame!r} into {sensor_frame!r} (fixed transform)"
    if not valid.any():
        raise InputFileError(
            f"{source}: no reading on {wrench_topic} falls within the recorded poses "
            f"({pose_source})"
        )
    t_kept = series.t_ns[valid]
    R_kept = R[np.flatnonzero(valid)]
    segments, unsettled = find_still_segments(t_kept, R_kept, wrench[valid], config)
    if not segments:
        raise InputFileError(
            f"{source}: no still period on {wrench_topic}{config.why_none(unsettled)}"
        )
    rows, ids = segment_rows(segments)
    return BagImport(
        source=source,
        pose_source=pose_source,
        wrench_note=note,
        t_ns=t_kept[rows],
        wrench_sensor=wrench[valid][rows],
        R_base_sensor=R_kept[rows].as_matrix(),
        pose_ids=ids,
        segments=tuple(segments),
        t0_ns=int(series.t_ns[0]),
        readings_total=len(series.t_ns),
        readings_without_pose=int(np.count_nonzero(~valid)),
        unsettled=unsettled,
        still=config,
        warnings=(*reader.warnings, *series.warnings),
    )


def write_bag_samples(path: str | os.PathLike[str], result: BagImport) -> None:
    """Write the kept readings as a sample CSV (columns in the module docstring), atomically."""
    quat = encode_orientation(Rotation.from_matrix(result.R_base_sensor), "quaternion")
    header = ("pose", "t_ns", "t", *ENCODING_COLUMNS["quaternion"], *WRENCH_COLUMNS)
    t_s = (result.t_ns - result.t0_ns) / _NS
    rows = [
        (
            pid,
            str(int(t)),
            f"{ts:.9f}",
            *(f"{v:.10g}" for v in q),
            *(f"{v:.10g}" for v in w),
        )
        for pid, t, ts, q, w in zip(
            result.pose_ids, result.t_ns, t_s, quat, result.wrench_sensor, strict=True
        )
    ]
    write_table(path, header, rows)
