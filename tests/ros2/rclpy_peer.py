"""ROS 2 nodes for the live tests, each in its own process, written with rclpy alone.

``python rclpy_peer.py publish SECONDS [FRAME] [--description] [--still] [--nan]
[--joints-s=S] [--load=KG --grasp-when=PATH]``: node ``sensor_driver`` publishing ``/ft_raw``
(WrenchStamped, reliable, 200 Hz; reading k is
``MODEL.predict(R_BASE_SENSOR) + contact(k)`` stamped ``EPOCH_NS + k * 5 ms`` in FRAME, default
``ft_sensor``) and ``/joint_states`` (JointState, 100 Hz, :data:`Q` on the two joints of
:data:`URDF`); with ``--description``, also ``/robot_description`` latched (transient local),
as robot_state_publisher does; with ``--still``, the tool at rest with the bias moved by
:data:`SHIFT` instead of a contact; with ``--nan``, every odd reading's fz is NaN; with
``--joints-s=S``, the joint states stop S seconds after a subscriber first matched them (the
wrenches go on; counted from the start, a node discovered late under load never saw one); with
``--load=KG``, the tool at rest (no contact) and, from the first reading after the file PATH
exists, a grasped load of KG at :data:`LOAD_COG_M` (:func:`load_wrench`).

``python rclpy_peer.py subscribe TOPIC COUNT SECONDS OUT.json``: node ``listener`` collecting
WrenchStamped on TOPIC until COUNT messages or SECONDS passed; writes
``[[stamp_ns, frame_id, fx, ..., tz], ...]``.

``python rclpy_peer.py robot SECONDS OUT.json``: node ``servo_robot``, a Cartesian arm
(:data:`CARTESIAN_URDF`) integrating TwistStamped into joint states (:func:`robot`).

``python rclpy_peer.py cell SECONDS OUT.json``: node ``servo_robot``, the simulated MuJoCo cell
(:data:`CELL_URI`: 0.5 kg held 2 mm above the sponge) in wall-clock time, its wrist sensor on
``/ft_sensor/wrench``, its joints on ``/joint_states``, its URDF latched on
``/robot_description``, and the TwistStamped it receives as the cell's motion (:func:`cell`).

``python rclpy_peer.py rebias OUT.json``: node ``client`` calling ``/ftcomp/rebias``
(std_srvs/Trigger), writing ``[success, message]``.

The environment (the test's) pins them to loopback and sets ROS_DOMAIN_ID.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time

import numpy as np
import rclpy
from geometry_msgs.msg import WrenchStamped
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from std_srvs.srv import Trigger

from ftcomp.model import GravityModel

EPOCH_NS = 1_700_000_000_000_000_000
PERIOD_NS = 5_000_000
MODEL = GravityModel(
    3.153,
    np.array([0.0001, -0.0003, 0.047]),
    np.array([-0.8613, 1.1015, 0.1976]),
    np.array([-0.0002, -0.0605, 0.0255]),
    tilt_U_rad=np.radians(-2.0),
    tilt_V_rad=np.radians(1.5),
)
#: A two-joint arm: base -> (yaw about z) -> link1 -> (pitch about y) -> link2 -> fixed
#: flip about x -> ft_sensor.
URDF = """<?xml version="1.0"?>
<robot name="two_joint">
  <link name="base"/><link name="link1"/><link name="link2"/><link name="ft_sensor"/>
  <joint name="yaw" type="revolute">
    <parent link="base"/><child link="link1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="9" velocity="3"/>
  </joint>
  <joint name="pitch" type="revolute">
    <parent link="link1"/><child link="link2"/>
    <origin xyz="0.4 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="9" velocity="3"/>
  </joint>
  <joint name="mount" type="fixed">
    <parent link="link2"/><child link="ft_sensor"/>
    <origin xyz="0 0 -0.1" rpy="3.141592653589793 0 0"/>
  </joint>
</robot>
"""
#: The joint positions the publisher holds [rad]: yaw, pitch.
Q = (0.5236, 0.3491)
#: The sensor's orientation at :data:`Q`, written out from the URDF by hand.
R_BASE_SENSOR = (
    Rotation.from_euler("z", Q[0])
    * Rotation.from_euler("y", Q[1])
    * (Rotation.from_euler("x", np.pi))
)


#: With ``--still``, every reading is the tool at rest with the bias moved by this [N, N*m].
SHIFT = np.array([0.3, -0.2, 0.5, 0.01, 0.02, -0.03])
#: With ``--load``: the grasped load's centre of gravity [m], sensor frame.
LOAD_COG_M = np.array([0.01, -0.02, 0.12])


def load_wrench(mass_kg: float) -> np.ndarray:
    """The wrench [N, N*m] a load of ``mass_kg`` at :data:`LOAD_COG_M` adds at
    :data:`R_BASE_SENSOR` (no bias: the load's gravity alone, the tool's tilted base)."""
    from ftcomp.constants import STANDARD_GRAVITY_MPS2

    load = GravityModel(
        mass_kg * STANDARD_GRAVITY_MPS2,
        LOAD_COG_M,
        np.zeros(3),
        np.zeros(3),
        tilt_U_rad=MODEL.tilt_U_rad,
        tilt_V_rad=MODEL.tilt_V_rad,
    )
    return np.asarray(load.predict(R_BASE_SENSOR.as_matrix()))


def contact(k: int) -> np.ndarray:
    """The contact wrench of reading k [N, N*m]: what compensation must give back."""
    return np.array([0.5, -1.0, 2.0, 0.01, -0.02, 0.03]) + 0.001 * k


def _stamp(msg_stamp: object, t_ns: int) -> None:
    msg_stamp.sec, msg_stamp.nanosec = divmod(t_ns, 10**9)  # type: ignore[attr-defined]


def publish(
    seconds: float,
    frame: str,
    description: bool,
    still: bool,
    nan: bool,
    joints_s: float,
    load_kg: float = 0.0,
    grasp_when: str = "",
) -> None:
    node = Node("sensor_driver")
    reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    wrenches = node.create_publisher(WrenchStamped, "/ft_raw", reliable)
    joints = node.create_publisher(JointState, "/joint_states", reliable)
    if description:
        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        node.create_publisher(String, "/robot_description", latched).publish(String(data=URDF))
    predicted = MODEL.predict(R_BASE_SENSOR.as_matrix())
    loaded = predicted + load_wrench(load_kg)
    held = False
    end = time.monotonic() + seconds
    k = 0
    joints_until: float | None = None  # set once a subscriber matched /joint_states
    while time.monotonic() < end:
        msg = WrenchStamped()
        _stamp(msg.header.stamp, EPOCH_NS + k * PERIOD_NS)
        msg.header.frame_id = frame
        if load_kg:
            held = held or os.path.exists(grasp_when)
            w = (loaded if held else predicted).tolist()
        else:
            w = (predicted + (SHIFT if still else contact(k))).tolist()
        if nan and k % 2:
            w[2] = float("nan")
        f, m = msg.wrench.force, msg.wrench.torque
        f.x, f.y, f.z, m.x, m.y, m.z = w
        wrenches.publish(msg)
        if joints_until is None and joints.get_subscription_count() > 0:
            joints_until = time.monotonic() + joints_s
        if k % 2 == 0 and (joints_until is None or time.monotonic() < joints_until):
            js = JointState(name=["yaw", "pitch"], position=list(Q))
            _stamp(js.header.stamp, time.time_ns())
            joints.publish(js)
        rclpy.spin_once(node, timeout_sec=0)
        k += 1
        time.sleep(PERIOD_NS / 1e9)
    node.destroy_node()


def subscribe(topic: str, count: int, seconds: float, out: str) -> None:
    node = Node("listener")
    got: list[list[object]] = []

    def on_msg(msg: WrenchStamped) -> None:
        f, m = msg.wrench.force, msg.wrench.torque
        stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        got.append([stamp, msg.header.frame_id, f.x, f.y, f.z, m.x, m.y, m.z])

    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    node.create_subscription(WrenchStamped, topic, on_msg, qos)
    end = time.monotonic() + seconds
    while time.monotonic() < end and len(got) < count:
        rclpy.spin_once(node, timeout_sec=0.05)
    with open(out, "w", encoding="utf-8") as handle:
        json.dump(got, handle)
    node.destroy_node()


def rebias(out: str) -> None:
    node = Node("client")
    client = node.create_client(Trigger, "/ftcomp/rebias")
    result: list[object] = [False, "service not available"]
    if client.wait_for_service(timeout_sec=120.0):
        future = client.call_async(Trigger.Request())
        rclpy.spin_until_future_complete(node, future, timeout_sec=60.0)
        if future.result() is not None:
            result = [future.result().success, future.result().message]
    with open(out, "w", encoding="utf-8") as handle:
        json.dump(result, handle)
    node.destroy_node()


#: A Cartesian arm: x, y, z slides along the base axes, then yaw, pitch, roll (R = Rz Ry Rx),
#: then the tool: a twist maps to joint rates without inverse kinematics.
CARTESIAN_URDF = """<?xml version="1.0"?>
<robot name="cartesian">
  <link name="base"/><link name="sx"/><link name="sy"/><link name="sz"/>
  <link name="ryaw"/><link name="rpitch"/><link name="tool"/>
  <joint name="x" type="prismatic"><parent link="base"/><child link="sx"/>
    <axis xyz="1 0 0"/><limit lower="-2" upper="2" effort="9" velocity="3"/></joint>
  <joint name="y" type="prismatic"><parent link="sx"/><child link="sy"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="9" velocity="3"/></joint>
  <joint name="z" type="prismatic"><parent link="sy"/><child link="sz"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="9" velocity="3"/></joint>
  <joint name="yaw" type="revolute"><parent link="sz"/><child link="ryaw"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="9" velocity="3"/></joint>
  <joint name="pitch" type="revolute"><parent link="ryaw"/><child link="rpitch"/>
    <axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="9" velocity="3"/></joint>
  <joint name="roll" type="revolute"><parent link="rpitch"/><child link="tool"/>
    <axis xyz="1 0 0"/><limit lower="-3" upper="3" effort="9" velocity="3"/></joint>
</robot>
"""


class ServoCommands:
    """``/servo_node/delta_twist_cmds`` (TwistStamped, base frame, MoveIt Servo's convention)
    as a robot node takes it: the last twist, a twist older than 0.1 s counting as zero
    (Servo's command time-out), and how many came."""

    def __init__(self, node: Node, qos: QoSProfile) -> None:
        from geometry_msgs.msg import TwistStamped

        self.last = np.zeros(6)
        self.at = 0.0
        self.count = 0
        node.create_subscription(TwistStamped, "/servo_node/delta_twist_cmds", self._on, qos)

    def _on(self, msg: object) -> None:
        v, w = msg.twist.linear, msg.twist.angular  # type: ignore[attr-defined]
        self.last = np.array([v.x, v.y, v.z, w.x, w.y, w.z])
        self.at = time.monotonic()
        self.count += 1

    def twist(self, now: float) -> np.ndarray:
        """The twist to follow at ``now`` (monotonic [s])."""
        return self.last if now - self.at < 0.1 else np.zeros(6)


def robot(seconds: float, out: str) -> None:
    """Node ``servo_robot``: integrates ``/servo_node/delta_twist_cmds`` (TwistStamped, base
    frame, MoveIt Servo's convention) into the Cartesian arm's pose at 200 Hz, a twist older
    than 0.1 s counting as zero (Servo's command time-out), and publishes ``/joint_states``.
    Ends after SECONDS or when ``OUT.json.stop`` exists, writing ``{"p": [...], "R": [...],
    "last_twist": [...], "twists": N}``."""
    node = Node("servo_robot")
    reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    joints = node.create_publisher(JointState, "/joint_states", reliable)
    servo = ServoCommands(node, reliable)
    p = np.array([0.4, 0.0, 0.3])
    R = Rotation.from_euler("ZYX", [0.2, 0.1, np.pi - 0.05])
    end = time.monotonic() + seconds
    last = time.monotonic()
    stop = out + ".stop"
    while time.monotonic() < end and not os.path.exists(stop):
        rclpy.spin_once(node, timeout_sec=0.005)
        now = time.monotonic()
        dt, last = now - last, now
        twist = servo.twist(now)
        p = p + np.asarray(twist)[:3] * dt
        R = Rotation.from_rotvec(np.asarray(twist)[3:] * dt) * R
        yaw, pitch, roll = R.as_euler("ZYX")
        js = JointState(name=["x", "y", "z", "yaw", "pitch", "roll"])
        js.position = [*p.tolist(), float(yaw), float(pitch), float(roll)]
        _stamp(js.header.stamp, time.time_ns())
        joints.publish(js)
    with open(out, "w", encoding="utf-8") as handle:
        json.dump(
            {
                "p": p.tolist(),
                "R": R.as_matrix().tolist(),
                "last_twist": servo.last.tolist(),
                "twists": servo.count,
            },
            handle,
        )
    node.destroy_node()


#: The cell of ``tests/session/test_run.py``'s placement: 0.5 kg grasped, 2 mm above the sponge.
CELL_URI = "sim://?seed=4&surface=sponge&load_kg=0.5&grasp=1&clearance_mm=2"


def cell(seconds: float, out: str) -> None:
    """Node ``servo_robot``: the simulated cell (:data:`CELL_URI`) driven by
    ``/servo_node/delta_twist_cmds`` (TwistStamped, base frame, the sensor origin's twist; older
    than 0.1 s counts as zero, Servo's time-out), kept in step with the wall clock: each turn
    runs the cell's 1 ms cycles that are due (at most 50: a starved process slows the cell down
    rather than jump) and publishes its sensor's newest reading (``/ft_sensor/wrench``, frame
    ``ft_sensor``, stamped with ROS time) and its measured joints (``/joint_states``). Its URDF
    (``simbag.urdf_of_cell``) is latched on ``/robot_description``, as robot_state_publisher
    does. Ends after SECONDS, or once ``OUT.json.stop`` exists and the last twist received is
    zero (at most 10 s later), writing the sensor's start and end position in the base frame
    [m], the last twist, the count of twists and the cell's simulated and wall seconds."""
    from simbag import urdf_of_cell

    import ftcomp

    node = Node("servo_robot")
    reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    wrenches = node.create_publisher(WrenchStamped, "/ft_sensor/wrench", reliable)
    joints = node.create_publisher(JointState, "/joint_states", reliable)
    servo = ServoCommands(node, reliable)
    with ftcomp.open_robot(CELL_URI) as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        description = node.create_publisher(String, "/robot_description", latched)
        description.publish(String(data=urdf_of_cell(robot)))  # type: ignore[arg-type]
        names = list(robot.joint_names)  # type: ignore[attr-defined]
        start = robot.pose().p_base_tcp.tolist()
        period = robot.control_period_s  # type: ignore[attr-defined]
        t0 = time.monotonic()
        steps = 0
        stop, stop_by = out + ".stop", math.inf

        def stopped() -> bool:
            nonlocal stop_by
            if stop_by == math.inf and os.path.exists(stop):
                stop_by = time.monotonic() + 10.0
            return not np.any(servo.last) or time.monotonic() > stop_by

        while time.monotonic() - t0 < seconds and not (os.path.exists(stop) and stopped()):
            rclpy.spin_once(node, timeout_sec=0)
            due = min(int((time.monotonic() - t0) / period) - steps, 50)
            if due <= 0:
                time.sleep(period / 2)
                continue
            robot.command_twist(servo.twist(time.monotonic()))
            for _ in range(due):
                robot.wait_cycle()
            steps += due
            msg = WrenchStamped()
            _stamp(msg.header.stamp, time.time_ns())
            msg.header.frame_id = "ft_sensor"
            f, m = msg.wrench.force, msg.wrench.torque
            f.x, f.y, f.z, m.x, m.y, m.z = sensor.read().wrench_sensor.tolist()
            wrenches.publish(msg)
            js = JointState(name=names, position=robot.q_rad.tolist())  # type: ignore[attr-defined]
            _stamp(js.header.stamp, time.time_ns())
            joints.publish(js)
        state = {
            "start": start,
            "end": robot.pose().p_base_tcp.tolist(),
            "last_twist": servo.last.tolist(),
            "twists": servo.count,
            "sim_s": steps * period,
            "wall_s": time.monotonic() - t0,
        }
    with open(out, "w", encoding="utf-8") as handle:
        json.dump(state, handle)
    node.destroy_node()


if __name__ == "__main__":
    rclpy.init()
    try:
        mode = sys.argv[1]
        if mode == "publish":
            frame = next((a for a in sys.argv[3:] if not a.startswith("--")), "ft_sensor")
            flags = set(sys.argv[3:])
            publish(
                float(sys.argv[2]),
                frame,
                "--description" in flags,
                "--still" in flags,
                "--nan" in flags,
                float(next((f.split("=")[1] for f in flags if f.startswith("--joints-s=")), "inf")),
                float(next((f.split("=")[1] for f in flags if f.startswith("--load=")), "0")),
                next((f.split("=", 1)[1] for f in flags if f.startswith("--grasp-when=")), ""),
            )
        elif mode == "robot":
            robot(float(sys.argv[2]), sys.argv[3])
        elif mode == "cell":
            cell(float(sys.argv[2]), sys.argv[3])
        elif mode == "subscribe":
            subscribe(sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), sys.argv[5])
        else:
            rebias(sys.argv[2])
    finally:
        rclpy.try_shutdown()
