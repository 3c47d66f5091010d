"""Live ROS 2 topics as ftcomp devices, through rclpy (:mod:`.rclpy_runtime`).

Tested against rclpy nodes in other processes (``tests/ros2/test_live.py``), on loopback.

- ``--sensor ros2:///TOPIC?domain=0&frame=S&qos=best_effort&timeout_s=5`` (:func:`open_sensor`):
  subscribes to a ``geometry_msgs/msg/WrenchStamped`` topic (``qos=best_effort`` matches reliable
  and best-effort publishers; ``reliable`` lets the middleware drop nothing). Each reading is
  stamped on arrival with the host's monotonic clock (the session clock of hardware backends);
  its ``header.stamp`` is kept for republishing (:meth:`Ros2WrenchSensor.source_stamp_ns`).
  ``frame`` (optional) must equal ``header.frame_id``: a reading in another frame is an error,
  never compensated with the wrong orientation.
- ``--robot ros2:///?urdf=FILE&joint_states=/joint_states&base_frame=B&tcp_frame=S`` (:func:`
  open_robot`): the pose of ``S`` in ``B`` from the latest ``sensor_msgs/msg/JointState`` and the
  robot description (``urdf`` a file; without it the ``/robot_description`` string that
  robot_state_publisher latches). ``tf2_msgs`` has no PyPI wheel, so ``/tf`` is not read. With
  ``twist_topic=/servo_node/delta_twist_cmds`` it is an arm: each cycle's twist goes out as
  ``geometry_msgs/msg/TwistStamped`` in ``B`` (MoveIt Servo's convention), a stop as a zero
  twist; without it, a pose source that cannot move.
- :class:`WrenchPublisher` publishes ``WrenchStamped`` (reliable, keep last 10, volatile: the
  rclcpp default QoS) and makes a ``run_loop`` sink of the compensated wrench.

``domain`` is the ROS_DOMAIN_ID (default: the environment's).
"""

from __future__ import annotations

import math
import tempfile
import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable, Mapping
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any, Self

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import HardwareError, InputFileError, ParameterError
from ftcomp.hardware.protocols import ClockName, PoseSample, Robot, WrenchSample, WrenchSensor
from ftcomp.hardware.registry import Uri
from ftcomp.ros2.node_config import QOS_CHOICES, check_topic_name
from ftcomp.ros2.rclpy_runtime import (
    DEFAULT_QOS,
    DESCRIPTION_QOS,
    JointState,
    Ros2Runtime,
    String,
    TwistStamped,
    WrenchStamped,
    check_domain,
    qos_profile,
    received_ns,
    stamp_ns,
    take_queued,
    twist_stamped,
    wrench_of,
    wrench_stamped,
)
from ftcomp.ros2.tf import clean_frame

if TYPE_CHECKING:
    from rclpy.node import Node

    from ftcomp.control.loop import Reading
    from ftcomp.ros2.urdf import UrdfChain

__all__ = [
    "JOINT_STATES_DEPTH",
    "JointStatePose",
    "Ros2PoseSource",
    "Ros2ServoRobot",
    "Ros2WrenchSensor",
    "WrenchPublisher",
    "check_topic_type",
    "open_robot",
    "open_sensor",
    "robot_description",
    "urdf_chain",
    "wait_for",
]

_STAMPS_KEPT = 4096
#: The joint states' subscription queue (keep last, best effort).
JOINT_STATES_DEPTH = 10


def _domain(options: Any, uri: Uri) -> int | None:
    domain = options.integer("domain", -1)
    return None if domain == -1 else check_domain(domain, repr(uri.text))


class Ros2WrenchSensor:
    """A ``WrenchStamped`` topic as a :class:`~ftcomp.hardware.protocols.WrenchSensor`.

    Args:
        topic: the ROS 2 topic (``/ft_sensor/wrench``).
        domain_id: the ROS_DOMAIN_ID (None: the environment's).
        frame_id: if given, every message's ``header.frame_id`` must be this.
        qos: one of :data:`~ftcomp.ros2.rclpy_runtime.QOS_CHOICES`.
        timeout_s: how long entering waits for the first message [s].
    """

    def __init__(
        self,
        topic: str,
        *,
        domain_id: int | None = None,
        frame_id: str | None = None,
        qos: str = "best_effort",
        timeout_s: float = 5.0,
    ) -> None:
        self.topic = topic
        self.frame_id = clean_frame(frame_id) if frame_id else None
        self.timeout_s = timeout_s
        self._qos = qos_profile(qos, 100)
        self._runtime = Ros2Runtime("ftcomp_sensor", domain_id=domain_id)
        self._lock = threading.Lock()
        self._new: deque[WrenchSample] = deque(maxlen=_STAMPS_KEPT)
        self._last: WrenchSample | None = None
        self._stamps: OrderedDict[int, int] = OrderedDict()
        self._error: str | None = None
        self._arrived = threading.Event()

    def _on_wrench(self, msg: WrenchStamped) -> None:
        now = time.monotonic_ns()
        frame = clean_frame(msg.header.frame_id)
        sample = WrenchSample(now, wrench_of(msg))
        with self._lock:
            if self.frame_id is not None and frame != self.frame_id:
                self._error = (
                    f"ros2://{self.topic}: a reading in frame {frame!r}, expected "
                    f"{self.frame_id!r} (the calibration's sensor frame)"
                )
            self._new.append(sample)
            self._last = sample
            self._stamps[now] = stamp_ns(msg.header.stamp)
            while len(self._stamps) > _STAMPS_KEPT:
                self._stamps.popitem(last=False)
        self._arrived.set()

    def __enter__(self) -> Ros2WrenchSensor:
        runtime = self._runtime.__enter__()
        try:
            runtime.node.create_subscription(WrenchStamped, self.topic, self._on_wrench, self._qos)
            expected = "geometry_msgs/msg/WrenchStamped"
            if not wait_for(self._arrived, runtime, self.topic, expected, self.timeout_s):
                domain_id = self._runtime.domain_id
                domain = "of the environment" if domain_id is None else str(domain_id)
                raise HardwareError(
                    f"ros2://{self.topic}: no geometry_msgs/msg/WrenchStamped within "
                    f"{self.timeout_s:g} s (ROS_DOMAIN_ID {domain})"
                )
        except BaseException:
            self._runtime.__exit__(None, None, None)
            raise
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._runtime.__exit__(exc_type, exc, tb)

    def _check(self) -> None:
        if self._error is not None:
            raise HardwareError(self._error)

    def read(self) -> WrenchSample:
        """The newest reading."""
        with self._lock:
            last = self._last
        self._check()
        if last is None:
            raise HardwareError(f"ros2://{self.topic}: not started (use it in a with block)")
        return last

    def read_new(self) -> list[WrenchSample]:
        """Every reading since the previous call (or since entering), oldest first."""
        with self._lock:
            out = list(self._new)
            self._new.clear()
        self._check()
        return out

    def source_stamp_ns(self, t_ns: int) -> int | None:
        """The ``header.stamp`` [ns] of the reading that arrived at ``t_ns`` (if still kept)."""
        with self._lock:
            return self._stamps.get(t_ns)


def check_topic_type(runtime: Ros2Runtime, topic: str, expected: str) -> None:
    """Raise a ParameterError if a publisher on ``topic`` has a type other than ``expected``
    (it would never match: the subscription would just wait)."""
    for info in runtime.node.get_publishers_info_by_topic(topic):
        if info.topic_type != expected:
            raise ParameterError(f"{topic} carries {info.topic_type}, not {expected}")


def wait_for(
    arrived: threading.Event, runtime: Ros2Runtime, topic: str, expected: str, timeout_s: float
) -> bool:
    """Wait up to ``timeout_s`` for ``arrived``, checking the publishers' type meanwhile
    (:func:`check_topic_type`). True if it arrived."""
    deadline = time.monotonic() + timeout_s
    while not arrived.wait(min(0.05, max(0.0, deadline - time.monotonic()))):
        check_topic_type(runtime, topic, expected)
        if time.monotonic() >= deadline:
            return False
    return True


def robot_description(runtime: Ros2Runtime, topic: str, timeout_s: float) -> str:
    """The URDF string latched on ``topic`` (``/robot_description``), waited for ``timeout_s``."""
    got: list[str] = []
    arrived = threading.Event()

    def on_description(msg: String) -> None:
        got.append(str(msg.data))
        arrived.set()

    sub = runtime.node.create_subscription(String, topic, on_description, DESCRIPTION_QOS)
    try:
        if not arrived.wait(timeout_s):
            raise HardwareError(
                f"no robot description on {topic} within {timeout_s:g} s: give urdf=FILE, or "
                "start robot_state_publisher"
            )
    finally:
        runtime.node.destroy_subscription(sub)
    return got[0]


def urdf_chain(urdf: str | None, description: str | None, base: str, tip: str) -> UrdfChain:
    """The chain ``base`` -> ``tip`` from a URDF file or a description string.

    Raises:
        InputFileError: the URDF does not hold the frames or they are not connected.
    """
    from ftcomp.ros2.urdf import UrdfChain

    if urdf is not None:
        return UrdfChain(urdf, base, tip)
    assert description is not None
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "robot_description.urdf"
        path.write_text(description, encoding="utf-8")
        try:
            return UrdfChain(path, base, tip)
        except InputFileError as exc:
            raise InputFileError(str(exc).replace(str(path), "/robot_description")) from None


class JointStatePose:
    """The sensor's pose from the latest ``JointState`` and a URDF chain (thread-safe).

    Args:
        chain: the base -> sensor chain.
        topic: the joint states' topic (for messages).

    A message only updates the chain's joint positions; the forward kinematics runs when a pose
    is asked for, once per configuration (joint states may come faster than the pose is used,
    at 1 kHz from franka_ros2).
    """

    def __init__(self, chain: UrdfChain, topic: str) -> None:
        self.chain = chain
        self.topic = topic
        self._lock = threading.Lock()
        self._q = np.full(len(chain.joint_names), np.nan)
        self._index = {name: k for k, name in enumerate(chain.joint_names)}
        #: Reception of the latest message naming every joint of the chain [ns, system clock].
        self.t_ns: int | None = None
        self.arrived = threading.Event()
        self._latest: tuple[int, NDArray[np.float64], NDArray[np.float64]] | None = None
        self._subscription: Any = None

    def subscribe(self, node: Node) -> None:
        """Subscribe ``node`` to :attr:`topic` (best effort, keep last
        :data:`JOINT_STATES_DEPTH`)."""
        qos = qos_profile("best_effort", JOINT_STATES_DEPTH)
        self._subscription = node.create_subscription(
            JointState, self.topic, self.on_joint_state, qos
        )

    def on_joint_state(self, msg: JointState, info: Mapping[str, Any]) -> None:
        """The subscription's callback: keep the chain's joints from ``msg``, then
        :meth:`catch_up`."""
        self._merge(msg, info)
        self.catch_up()

    def catch_up(self) -> None:
        """Keep the chain's joints from the messages queued on the subscription
        (:func:`take_queued`), and when the newest was received (the middleware's time: a
        backlog of callbacks does not age it). A callback that handles a batch of readings
        calls it before each, so each takes the newest joint states, as if the executor had
        served the joint states between them."""
        if self._subscription is not None:
            for queued in take_queued(self._subscription, JOINT_STATES_DEPTH):
                self._merge(*queued)

    def _merge(self, msg: JointState, info: Mapping[str, Any]) -> None:
        now = received_ns(info)
        with self._lock:
            for name, position in zip(msg.name, msg.position, strict=False):
                k = self._index.get(str(name))
                if k is not None:
                    self._q[k] = position
            if not np.isfinite(self._q).all():
                return
            self.t_ns, self._latest = now, None
        self.arrived.set()

    def missing(self) -> list[str]:
        """The chain's joints no message has given yet."""
        with self._lock:
            return [n for n, k in self._index.items() if not math.isfinite(self._q[k])]

    def pose(self) -> tuple[int, NDArray[np.float64], NDArray[np.float64]]:
        """``(reception [ns, system clock], p_base_sensor [m], R_base_sensor)`` of the latest
        joint states."""
        with self._lock:
            if self._latest is None:
                if self.t_ns is None:
                    raise HardwareError(f"no joint states on {self.topic} yet")
                T = self.chain.pose(self._q)
                self._latest = (self.t_ns, T[:3, 3].copy(), T[:3, :3].copy())
            return self._latest


class Ros2PoseSource:
    """The pose of ``tcp_frame`` in ``base_frame`` from live joint states: a read-only Robot.

    Args:
        base_frame: the robot's base link.
        tcp_frame: the link whose pose is reported (the sensor frame: use an identity mount).
        joint_states: the ``sensor_msgs/msg/JointState`` topic.
        urdf: the URDF file; None: the ``/robot_description`` topic's.
        domain_id: the ROS_DOMAIN_ID (None: the environment's).
        period_s: the loop period ``wait_cycle`` sleeps [s].
        stale_s: joint states older than this are a fault [s].
        timeout_s: how long entering waits for the description and the joint states [s].
    """

    clock_name: ClockName = "monotonic"
    pose_known = True
    _node_name = "ftcomp_pose"

    def __init__(
        self,
        base_frame: str,
        tcp_frame: str,
        *,
        joint_states: str = "/joint_states",
        urdf: str | None = None,
        domain_id: int | None = None,
        period_s: float = 0.002,
        stale_s: float = 0.1,
        timeout_s: float = 5.0,
    ) -> None:
        self.base_frame, self.tcp_frame = clean_frame(base_frame), clean_frame(tcp_frame)
        self.joint_states_topic = joint_states
        self.urdf = urdf
        if urdf is not None:  # a bad file is an error before anything starts
            self._chain: UrdfChain | None = urdf_chain(urdf, None, self.base_frame, self.tcp_frame)
        else:
            self._chain = None
        self._period = period_s
        self.stale_s = stale_s
        self.timeout_s = timeout_s
        self._runtime = Ros2Runtime(self._node_name, domain_id=domain_id)
        self._pose: JointStatePose | None = None

    @property
    def control_period_s(self) -> float:
        """The period ``wait_cycle`` sleeps [s]."""
        return self._period

    def __enter__(self) -> Self:
        runtime = self._runtime.__enter__()
        try:
            self._start(runtime)
        except BaseException:
            self._runtime.__exit__(None, None, None)
            raise
        return self

    def _start(self, runtime: Ros2Runtime) -> None:
        chain = self._chain
        if chain is None:
            text = robot_description(runtime, "/robot_description", self.timeout_s)
            chain = urdf_chain(None, text, self.base_frame, self.tcp_frame)
        self._pose = JointStatePose(chain, self.joint_states_topic)
        self._pose.subscribe(runtime.node)
        topic = self.joint_states_topic
        expected = "sensor_msgs/msg/JointState"
        if not wait_for(self._pose.arrived, runtime, topic, expected, self.timeout_s):
            raise HardwareError(
                f"ros2:// pose: no joint states naming {', '.join(self._pose.missing())} on "
                f"{self.joint_states_topic} within {self.timeout_s:g} s"
            )

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._runtime.__exit__(exc_type, exc, tb)

    def now_ns(self) -> int:
        """The host's monotonic clock [ns]."""
        return time.monotonic_ns()

    def pose(self) -> PoseSample:
        """The latest pose, stamped now.

        Raises:
            HardwareError: joint states older than ``stale_s``.
        """
        if self._pose is None:
            raise HardwareError("ros2:// pose source not started (use a with block)")
        t, p, R = self._pose.pose()
        age = time.time_ns() - t
        if age > self.stale_s * 1e9:
            raise HardwareError(
                f"ros2:// pose: the joint states on {self.joint_states_topic} are "
                f"{age / 1e9:.3f} s old (stale after {self.stale_s:g} s)"
            )
        return PoseSample(time.monotonic_ns(), p, R)

    def move_pose(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64], duration_s: float
    ) -> None:
        """Not possible: a pose source cannot move."""
        raise HardwareError("ros2:// without twist_topic is a pose source; it cannot move")

    def settle(self, max_duration_s: float) -> float:
        """Nothing to wait for: the arm is not commanded (0 s)."""
        return 0.0

    def command_twist(self, twist_base: NDArray[np.float64]) -> None:
        """Only zero: a pose source cannot move."""
        if np.any(np.asarray(twist_base) != 0.0):
            raise HardwareError("ros2:// without twist_topic is a pose source; it cannot move")

    def wait_cycle(self) -> None:
        """Sleep one period."""
        time.sleep(self._period)

    def stop(self) -> None:
        """Nothing moves."""


class Ros2ServoRobot(Ros2PoseSource):
    """An arm driven by Cartesian velocity on a ``TwistStamped`` topic (MoveIt Servo's
    ``delta_twist_cmds``), its pose from joint states: :class:`Ros2PoseSource`'s arguments and

    Args:
        twist_topic: the topic the twists go to.

    Each :meth:`command_twist` publishes one message in ``base_frame`` (linear [m/s] of the
    sensor origin, angular [rad/s]) stamped with ROS time; :meth:`stop` publishes a zero twist,
    also on leaving. The servo node turns them into joint motion; what it does with a stale
    command is its own (MoveIt Servo halts after ``incoming_command_timeout``).
    """

    _node_name = "ftcomp_servo"

    def __init__(self, base_frame: str, tcp_frame: str, *, twist_topic: str, **kwargs: Any):
        super().__init__(base_frame, tcp_frame, **kwargs)
        self.twist_topic = twist_topic
        self._publisher: Any = None

    def _start(self, runtime: Ros2Runtime) -> None:
        self._publisher = runtime.node.create_publisher(TwistStamped, self.twist_topic, DEFAULT_QOS)
        super()._start(runtime)

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        try:
            self.stop()
        finally:
            self._publisher = None
            super().__exit__(exc_type, exc, tb)

    def command_twist(self, twist_base: NDArray[np.float64]) -> None:
        """Publish ``[v; w]`` [m/s, rad/s] of the TCP, base frame."""
        if self._publisher is None:
            raise HardwareError(f"ros2://{self.twist_topic}: not started (use a with block)")
        self._publisher.publish(twist_stamped(time.time_ns(), self.base_frame, twist_base))

    def move_pose(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64], duration_s: float
    ) -> None:
        """Not offered: a servo topic takes velocities (move the arm with its own driver)."""
        raise HardwareError(
            "ros2:// drives the arm by twists only; move it into place with its own driver"
        )

    def stop(self) -> None:
        """Publish a zero twist (if started)."""
        if self._publisher is not None:
            self._publisher.publish(twist_stamped(time.time_ns(), self.base_frame, np.zeros(6)))


class WrenchPublisher:
    """Publishes ``WrenchStamped`` on a ROS 2 topic (a context manager).

    Args:
        topic: the ROS 2 topic.
        frame_id: the messages' ``header.frame_id`` (the sensor frame).
        domain_id: the ROS_DOMAIN_ID (None: the environment's).
    """

    def __init__(self, topic: str, frame_id: str, *, domain_id: int | None = None) -> None:
        self.topic = topic
        self.frame_id = clean_frame(frame_id)
        self._runtime = Ros2Runtime("ftcomp_publisher", domain_id=domain_id)
        self._publisher: Any = None
        #: Messages published.
        self.count = 0

    def __enter__(self) -> WrenchPublisher:
        runtime = self._runtime.__enter__()
        self._publisher = runtime.node.create_publisher(WrenchStamped, self.topic, DEFAULT_QOS)
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._publisher = None
        self._runtime.__exit__(exc_type, exc, tb)

    def subscribers(self) -> int:
        """How many subscriptions are matched now (discovery takes a moment: what is
        published before a subscriber matches never reaches it)."""
        if self._publisher is None:
            raise HardwareError(f"ros2://{self.topic}: publisher not started (use a with block)")
        return int(self._publisher.get_subscription_count())

    def publish(self, t_ns: int, wrench: NDArray[np.float64]) -> None:
        """Publish one wrench [N, N*m] stamped ``t_ns`` (ROS time [ns])."""
        if self._publisher is None:
            raise HardwareError(f"ros2://{self.topic}: publisher not started (use a with block)")
        self._publisher.publish(wrench_stamped(t_ns, self.frame_id, wrench))
        self.count += 1

    def sink(
        self, stamp: Callable[[int], int | None] | None = None
    ) -> Callable[[Reading, NDArray[np.float64]], None]:
        """A ``run_loop`` sink publishing each new reading's compensated wrench once (a cycle
        that sees the same sample again publishes nothing).

        Args:
            stamp: maps the reading's ``t_sample_ns`` to its ROS stamp (e.g.
                :meth:`Ros2WrenchSensor.source_stamp_ns`, so the compensated wrench carries the
                raw message's stamp); where it gives None, the host's wall clock
                (``time.time_ns``, ROS time without ``use_sim_time``) stamps it.
        """

        last = [-1]

        def publish(reading: Reading, _twist: NDArray[np.float64]) -> None:
            if reading.t_sample_ns == last[0]:
                return
            last[0] = reading.t_sample_ns
            t = stamp(reading.t_sample_ns) if stamp is not None else None
            self.publish(t if t is not None else time.time_ns(), reading.wrench_contact_sensor)

        return publish


def _topic(value: str, uri: Uri, what: str) -> str:
    return check_topic_name(value, f"{uri.text!r}: {what}")


def open_sensor(uri: Uri, robot: Robot | None) -> WrenchSensor:
    """``ros2:///TOPIC?domain=N&frame=S&qos=Q&timeout_s=T`` (see the module docstring)."""
    options = uri.reader()
    domain = _domain(options, uri)
    frame = options.text("frame", "")
    qos = options.text("qos", "best_effort", QOS_CHOICES)
    timeout = options.number("timeout_s", 5.0)
    options.done()
    if uri.host:
        raise ParameterError(f"{uri.text!r}: no host in ros2:// URIs; write ros2:///TOPIC")
    if not uri.path or uri.path == "/":
        raise ParameterError(f"{uri.text!r}: name the WrenchStamped topic, e.g. ros2:///ft/wrench")
    topic = _topic(uri.path, uri, "the topic")
    assert timeout is not None
    return Ros2WrenchSensor(
        topic, domain_id=domain, frame_id=frame or None, qos=qos, timeout_s=timeout
    )


def open_robot(uri: Uri) -> Robot:
    """``ros2:///?base_frame=B&tcp_frame=S&urdf=FILE&joint_states=/joint_states&
    twist_topic=T&domain=N&rate_hz=R&stale_s=S&timeout_s=T`` (see the module docstring)."""
    options = uri.reader()
    domain = _domain(options, uri)
    base = options.text("base_frame", "")
    tcp = options.text("tcp_frame", "")
    urdf = options.text("urdf", "")
    joint_states = options.text("joint_states", "/joint_states")
    twist_topic = options.text("twist_topic", "")
    rate = options.number("rate_hz", 500.0)
    stale = options.number("stale_s", 0.1)
    timeout = options.number("timeout_s", 5.0)
    options.done()
    if not base or not tcp:
        raise ParameterError(f"{uri.text!r}: give base_frame=B&tcp_frame=S (the URDF's links)")
    assert rate is not None and timeout is not None and stale is not None
    if not rate > 0.0:
        raise ParameterError(f"{uri.text!r}: rate_hz must be > 0")
    if not stale > 0.0:
        raise ParameterError(f"{uri.text!r}: stale_s must be > 0")
    kwargs: dict[str, Any] = {
        "joint_states": _topic(joint_states, uri, "joint_states"),
        "urdf": urdf or None,
        "domain_id": domain,
        "period_s": 1.0 / rate,
        "stale_s": stale,
        "timeout_s": timeout,
    }
    if twist_topic:
        topic = _topic(twist_topic, uri, "twist_topic")
        return Ros2ServoRobot(base, tcp, twist_topic=topic, **kwargs)
    return Ros2PoseSource(base, tcp, **kwargs)
