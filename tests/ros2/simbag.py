"""Bags recorded from the simulated cell, written with rosbags as a ROS driver stack would.

The cell moves its sensor through the paper's nine orientations (minimum-jerk joint moves) and
holds each for a while; every 2 ms (500 Hz) the wrist sensor's newest reading is logged, and
every 4 ms (250 Hz) the flange pose and the joint positions. What goes into a bag:

- ``/ft_sensor/wrench`` ``geometry_msgs/msg/WrenchStamped`` in frame ``ft_sensor`` (500 Hz);
- ``/tf``: ``base -> flange`` (the arm's last link, 250 Hz);
- ``/tf_static``: ``world -> base`` (the tilt), ``flange -> ft_sensor`` (the real mount: the
  sensor's z along the flange's x, offset along it) and an unrelated ``base -> camera``;
- ``/joint_states`` ``sensor_msgs/msg/JointState`` (250 Hz), for the URDF route;
  :func:`urdf_of_cell` writes the cell's kinematics as a URDF.

Stamps are the simulation time plus :data:`EPOCH_NS` (a plausible ROS time).
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from scipy.spatial.transform import Rotation

from ftcomp.model import GravityModel
from ftcomp.paper import paper_poses
from ftcomp.sim import SceneConfig, SimCell
from ftcomp.sim.arm import ARM_JOINT_NAMES
from ftcomp.sim.cell import COLLECTION_POSITION_BASE_M

EPOCH_NS = 1_700_000_000_000_000_000
WRENCH_TOPIC = "/ft_sensor/wrench"
BODIES = ("base", "link1", "link2", "link3", "link4", "link5", "link6")
LINK_NAMES = {"link6": "flange", "sensing_end": "ft_sensor"}


@dataclass
class Recording:
    """What the cell did, as arrays (times in ns on the bag's clock)."""

    wrench_t_ns: np.ndarray
    wrench: np.ndarray
    moving: np.ndarray  # per wrench reading: logged during a move (not a hold)
    pose_t_ns: np.ndarray
    p_base_flange: np.ndarray
    q_base_flange: np.ndarray  # x, y, z, w
    q_rad: np.ndarray
    p_flange_sensor: np.ndarray
    q_flange_sensor: np.ndarray
    q_world_base: np.ndarray
    truth: GravityModel
    urdf: str


def _pose_of(cell: SimCell, body: str) -> tuple[np.ndarray, np.ndarray]:
    b = cell.model.body(body).id
    Rwb = cell.R_world_base
    return Rwb.T @ cell.data.xpos[b], Rwb.T @ cell.data.xmat[b].reshape(3, 3)


def _nums(values: Any) -> str:
    return " ".join(repr(float(v)) for v in values)


def urdf_of_cell(cell: SimCell) -> str:
    """The arm from base to the sensing end as URDF (origins and axes from the MuJoCo model)."""
    m = cell.model
    chain = [*BODIES[1:], "sensor_housing", "sensing_end"]
    links = ["base", *(LINK_NAMES.get(b, b) for b in chain)]
    out = ['<?xml version="1.0"?>', '<robot name="ftcomp_cell">']
    out += [f'  <link name="{name}"/>' for name in links]
    joints = {name: m.joint(name) for name in ARM_JOINT_NAMES}
    for parent, body in zip(["base", *chain], chain, strict=False):
        b = m.body(body)
        w, x, y, z = b.quat
        with warnings.catch_warnings():  # the sensor mount is at gimbal lock: still exact
            warnings.simplefilter("ignore", UserWarning)
            rpy = Rotation.from_quat([x, y, z, w]).as_euler("xyz")
        joint = next((j for j in joints.values() if j.bodyid[0] == b.id), None)
        kind = "revolute" if joint is not None else "fixed"
        name = joint.name if joint is not None else f"{body}_fixed"
        out.append(f'  <joint name="{name}" type="{kind}">')
        out.append(f'    <parent link="{LINK_NAMES.get(parent, parent)}"/>')
        out.append(f'    <child link="{LINK_NAMES.get(body, body)}"/>')
        out.append(f'    <origin xyz="{_nums(b.pos)}" rpy="{_nums(rpy)}"/>')
        if joint is not None:
            lo, hi = m.jnt_range[joint.id]
            out.append(f'    <axis xyz="{_nums(joint.axis)}"/>')
            out.append(
                f'    <limit lower="{_nums([lo])}" upper="{_nums([hi])}" effort="9" velocity="3"/>'
            )
        out.append("  </joint>")
    out.append("</robot>")
    return "\n".join(out) + "\n"


@functools.cache
def recording() -> Recording:
    """The recording every bag test uses (made once per test process, about 1 s)."""
    return record_cell(seed=0)


def record_cell(seed: int = 0, hold_s: float = 0.8, move_s: float = 0.6) -> Recording:
    """Nine held poses and the moves between them (about 12.6 s of simulation)."""
    cell = SimCell(SceneConfig(), seed=seed)
    wrench_t, wrench, pose_t, p_bf, q_bf, q, moving = [], [], [], [], [], [], []
    count = [0]
    phase = [True]

    def log(c: SimCell) -> None:
        count[0] += 1
        if count[0] % 2:
            return
        sample = c.sensor.read()
        wrench_t.append(sample.t_ns)
        wrench.append(sample.wrench_sensor.copy())
        moving.append(phase[0])
        if count[0] % 4 == 0:
            p, R = _pose_of(c, "link6")
            pose_t.append(c.now_ns())
            p_bf.append(p)
            q_bf.append(Rotation.from_matrix(R).as_quat())
            q.append(c.q_rad)

    for R in paper_poses().rotations.as_matrix():
        phase[0] = True
        cell.move_pose(COLLECTION_POSITION_BASE_M, R, move_s, on_cycle=log)
        phase[0] = False
        for _ in range(round(hold_s / cell.control_period_s)):
            cell.wait_cycle()
            log(cell)
    p_f, R_f = _pose_of(cell, "link6")
    p_s, R_s = cell.sensor_pose()
    return Recording(
        wrench_t_ns=np.array(wrench_t, dtype=np.int64) + EPOCH_NS,
        wrench=np.array(wrench),
        moving=np.array(moving),
        pose_t_ns=np.array(pose_t, dtype=np.int64) + EPOCH_NS,
        p_base_flange=np.array(p_bf),
        q_base_flange=np.array(q_bf),
        q_rad=np.array(q),
        p_flange_sensor=R_f.T @ (p_s - p_f),
        q_flange_sensor=Rotation.from_matrix(R_f.T @ R_s).as_quat(),
        q_world_base=Rotation.from_matrix(cell.R_world_base).as_quat(),
        truth=cell.true_gravity_model(),
        urdf=urdf_of_cell(cell),
    )


class _Msgs:
    """Message builders on one typestore (ROS 2 Humble or ROS 1 Noetic)."""

    def __init__(self, ros1: bool) -> None:
        self.ros1 = ros1
        self.store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
        if ros1:  # the Noetic store lacks tf2_msgs: register it as a ROS 1 stack defines it
            self.store.register(
                get_types_from_msg(
                    "geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"
                )
            )
        self.T = self.store.types

    def header(self, t_ns: int, frame: str) -> Any:
        stamp = self.T["builtin_interfaces/msg/Time"](sec=t_ns // 10**9, nanosec=t_ns % 10**9)
        Header = self.T["std_msgs/msg/Header"]
        if self.ros1:
            return Header(seq=0, stamp=stamp, frame_id=frame)
        return Header(stamp=stamp, frame_id=frame)

    def wrench(self, t_ns: int, frame: str, w: np.ndarray) -> Any:
        V = self.T["geometry_msgs/msg/Vector3"]
        wrench = self.T["geometry_msgs/msg/Wrench"](
            force=V(*map(float, w[:3])), torque=V(*map(float, w[3:]))
        )
        return self.T["geometry_msgs/msg/WrenchStamped"](
            header=self.header(t_ns, frame), wrench=wrench
        )

    def tf(self, items: list[tuple[int, str, str, np.ndarray, np.ndarray]]) -> Any:
        T = self.T
        transforms = [
            T["geometry_msgs/msg/TransformStamped"](
                header=self.header(t, parent),
                child_frame_id=child,
                transform=T["geometry_msgs/msg/Transform"](
                    translation=T["geometry_msgs/msg/Vector3"](*map(float, p)),
                    rotation=T["geometry_msgs/msg/Quaternion"](*map(float, q)),
                ),
            )
            for t, parent, child, p, q in items
        ]
        return T["tf2_msgs/msg/TFMessage"](transforms=transforms)

    def joints(self, t_ns: int, q: np.ndarray) -> Any:
        return self.T["sensor_msgs/msg/JointState"](
            header=self.header(t_ns, ""),
            name=list(ARM_JOINT_NAMES),
            position=np.asarray(q, dtype=float),
            velocity=np.zeros(0),
            effort=np.zeros(0),
        )

    def serialize(self, msg: Any) -> bytes:
        if self.ros1:
            return bytes(self.store.serialize_ros1(msg, msg.__msgtype__))
        return bytes(self.store.serialize_cdr(msg, msg.__msgtype__))


def write_bag(
    rec: Recording,
    path: Path,
    *,
    storage: str = "mcap",
    wrench_frame: str = "ft_sensor",
    topics: tuple[str, ...] = (WRENCH_TOPIC, "/tf", "/tf_static", "/joint_states"),
    still: bool = True,
    until_s: float | None = None,
    foreign: bool = False,
    wrench_msgdef: str | None = None,
) -> Path:
    """Write the recording as a bag: ``storage`` is ``mcap``, ``sqlite3`` or ``ros1``.

    ``still=False`` keeps only the wrenches logged during moves; ``until_s`` keeps only the
    first seconds of the recording. ``foreign`` (rosbag2 only) adds what real bags hold besides:
    a service-event channel whose definition is a ``.srv`` text (as ``ros2 bag record`` with
    services can leave it; rosbags cannot parse it) and a custom type whose definition names a
    type nobody defines. ``wrench_msgdef`` replaces the wrench connection's definition.
    """
    msgs = _Msgs(ros1=storage == "ros1")
    t0 = rec.wrench_t_ns[0]
    zero = np.zeros(3)
    static = msgs.tf(
        [
            (t0, "world", "base", zero, rec.q_world_base),
            (t0, "flange", "ft_sensor", rec.p_flange_sensor, rec.q_flange_sensor),
            (t0, "base", "camera", np.array([1.0, 0.0, 1.0]), np.array([0.0, 0.0, 0.0, 1.0])),
        ]
    )
    out: list[tuple[str, int, Any]] = [("/tf_static", int(t0), static)]
    for t, w, m in zip(rec.wrench_t_ns, rec.wrench, rec.moving, strict=True):
        if still or m:
            out.append((WRENCH_TOPIC, int(t), msgs.wrench(int(t), wrench_frame, w)))
    for t, p, q, qj in zip(
        rec.pose_t_ns, rec.p_base_flange, rec.q_base_flange, rec.q_rad, strict=True
    ):
        out.append(("/tf", int(t), msgs.tf([(int(t), "base", "flange", p, q)])))
        out.append(("/joint_states", int(t), msgs.joints(int(t), qj)))
    end = t0 + (round(until_s * 1e9) if until_s is not None else 2**62)
    out = [item for item in out if item[0] in topics and item[1] <= end]
    out.sort(key=lambda item: item[1])
    types = {
        WRENCH_TOPIC: "geometry_msgs/msg/WrenchStamped",
        "/tf": "tf2_msgs/msg/TFMessage",
        "/tf_static": "tf2_msgs/msg/TFMessage",
        "/joint_states": "sensor_msgs/msg/JointState",
    }
    if storage == "ros1":
        with Writer1(path) as writer:
            conns = {t: writer.add_connection(t, types[t], typestore=msgs.store) for t in topics}
            for topic, t, msg in out:
                writer.write(conns[topic], t, msgs.serialize(msg))
        return path
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer2(path, version=9, storage_plugin=plugin) as writer:
        conns = {}
        for topic in topics:
            if topic == WRENCH_TOPIC and wrench_msgdef is not None:
                hash_ = msgs.store.hash_rihs01(types[topic])
                given = {"msgdef": wrench_msgdef, "rihs01": hash_}
                conns[topic] = writer.add_connection(topic, types[topic], **given)
            else:
                conns[topic] = writer.add_connection(topic, types[topic], typestore=msgs.store)
        if foreign:
            for topic, msgtype, msgdef in FOREIGN:
                conn = writer.add_connection(topic, msgtype, msgdef=msgdef, rihs01=FAKE_HASH)
                writer.write(conn, int(t0), bytes(24))
        for topic, t, msg in out:
            writer.write(conns[topic], t, msgs.serialize(msg))
    return path


FAKE_HASH = "RIHS01_" + "0" * 64
#: Connections a real bag holds besides what ftcomp reads: (topic, type, definition).
FOREIGN = (
    (
        "/add_two_ints/_service_event",
        "example_interfaces/srv/AddTwoInts_Event",
        "int64 a\nint64 b\n---\nint64 sum\n",
    ),
    ("/gripper/state", "acme_msgs/msg/GripperState", "acme_msgs/Finger[] fingers\n"),
)
