"""ftcomp's one ROS 2 runtime: rclpy, ROS 2's own Python client library.

A sourced ROS 2 installation provides rclpy; on a machine without ROS the PyPI wheels do
(``pip install -e '.[ros2]'`` in the clone: ``ros-rclpy[fastrtps]`` and the message packages,
ROS 2 Kilted for CPython 3.11). Everything ``ros2://`` does goes through :class:`Ros2Runtime`:
one rclpy context and one node of its own, spun by one executor thread, so several of them (the
sensor, the robot, the compensation node) live side by side in one process and shut down
independently.

**One thread per node.** Every callback of a node runs on its executor's one thread, one at a
time (rclpy's ``SingleThreadedExecutor``). A callback that has to wait for later messages (the
node's ``~/rebias`` reads for seconds) is a coroutine that awaits a :class:`Future` the other
callbacks complete. rclpy's ``MultiThreadedExecutor`` would let it block instead, but its thread
pool and futures cost about 0.4 ms of CPU more per message (measured with the compensation node
fed at 1 kHz: 1.1 ms per reading against 0.7 ms), which a 1 kHz stream cannot afford.

**Loopback.** ROS 2 discovers peers on every interface by default. :func:`loopback_environment`
gives the environment that keeps a participant on 127.0.0.1: ``ROS_AUTOMATIC_DISCOVERY_RANGE=
LOCALHOST`` (Kilted ignores ``ROS_LOCALHOST_ONLY``) and a Fast DDS XML profile that whitelists
127.0.0.1 with the built-in transports off (no multicast, no shared memory). ftcomp's tests and
benchmark run every participant so; on a single machine users set the same (docs/ros2.md).
It must be in the environment before the first participant of the process starts.

**Time.** A message's ``header.stamp`` is integer nanoseconds of ROS time (the system clock
without ``use_sim_time``); readings are stamped on arrival with the host's monotonic clock, the
session clock of ftcomp's hardware backends.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Iterator, Mapping
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import HardwareError, ParameterError
from ftcomp.extras import install_hint
from ftcomp.ros2.node_config import QOS_CHOICES

try:  # the optional extra, or a sourced ROS 2
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from geometry_msgs.msg import InertiaStamped, TwistStamped, WrenchStamped
    from rclpy.callback_groups import ReentrantCallbackGroup
    from rclpy.context import Context
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.qos import (
        DurabilityPolicy,
        HistoryPolicy,
        QoSProfile,
        ReliabilityPolicy,
    )
    from rclpy.subscription import Subscription
    from rclpy.task import Future
    from sensor_msgs.msg import JointState
    from std_msgs.msg import String
    from std_srvs.srv import Trigger
except ImportError as exc:
    raise HardwareError(
        f"ros2:// needs rclpy: source a ROS 2 installation, or {install_hint('ros2')} ({exc})"
    ) from None

if TYPE_CHECKING:
    from builtin_interfaces.msg import Time

__all__ = [
    "DEFAULT_QOS",
    "DESCRIPTION_QOS",
    "LOOPBACK_PROFILE_XML",
    "STREAM_QOS",
    "DiagnosticArray",
    "DiagnosticStatus",
    "Future",
    "InertiaStamped",
    "JointState",
    "KeyValue",
    "ReentrantCallbackGroup",
    "Ros2Runtime",
    "String",
    "Trigger",
    "TwistStamped",
    "WrenchStamped",
    "check_domain",
    "loopback_environment",
    "qos_profile",
    "received_ns",
    "stamp_msg",
    "stamp_ns",
    "take_queued",
    "transmitted_packets",
    "twist_stamped",
    "wrench_of",
    "wrench_stamped",
]

_NS = 1_000_000_000

#: A Fast DDS profile (the default participant profile) that sends and listens on 127.0.0.1
#: only: a UDPv4 transport whitelisting it, the built-in transports (UDP on every interface,
#: shared memory) off.
LOOPBACK_PROFILE_XML = """<?xml version="1.0" encoding="UTF-8" ?>
<dds xmlns="http://www.eprosima.com">
<profiles>
  <transport_descriptors>
    <transport_descriptor>
      <transport_id>ftcomp_loopback_udp</transport_id>
      <type>UDPv4</type>
      <interfaceWhiteList><address>127.0.0.1</address></interfaceWhiteList>
    </transport_descriptor>
  </transport_descriptors>
  <participant profile_name="ftcomp_loopback" is_default_profile="true">
    <rtps>
      <userTransports><transport_id>ftcomp_loopback_udp</transport_id></userTransports>
      <useBuiltinTransports>false</useBuiltinTransports>
    </rtps>
  </participant>
</profiles>
</dds>
"""

#: rclcpp's default publisher QoS: reliable, keep last 10, volatile.
DEFAULT_QOS = QoSProfile(depth=10)
#: The node's outputs at a sensor's rate: reliable, volatile, keep last 100 (100 ms at 1 kHz
#: for a subscriber to acknowledge before the oldest is overwritten).
STREAM_QOS = QoSProfile(depth=100)
#: robot_state_publisher's ``/robot_description``: reliable, transient local, keep last 1.
DESCRIPTION_QOS = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)


def loopback_environment(directory: str | os.PathLike[str]) -> dict[str, str]:
    """The environment that pins rclpy (Fast DDS) to 127.0.0.1; writes the profile.

    Args:
        directory: where to write ``fastdds_loopback.xml``.

    Returns:
        ``RMW_IMPLEMENTATION``, ``ROS_AUTOMATIC_DISCOVERY_RANGE`` and
        ``FASTDDS_DEFAULT_PROFILES_FILE``, to merge into ``os.environ`` (before the process's
        first participant) or a child's environment.
    """
    path = Path(directory) / "fastdds_loopback.xml"
    path.write_text(LOOPBACK_PROFILE_XML, encoding="utf-8")
    return {
        "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "FASTDDS_DEFAULT_PROFILES_FILE": str(path),
    }


def transmitted_packets() -> dict[str, int]:
    """Packets each non-loopback interface has sent so far (``/proc/net/dev``, Linux): read
    before and after a run pinned by :func:`loopback_environment`, they prove it sent nothing
    off the host."""
    out = {}
    with open("/proc/net/dev", encoding="ascii") as handle:
        for line in handle.read().splitlines()[2:]:
            name, counters = line.split(":", 1)
            if name.strip() != "lo":
                out[name.strip()] = int(counters.split()[9])
    return out


def check_domain(domain_id: int, where: str) -> int:
    """``domain_id`` if it is a ROS_DOMAIN_ID (0..232), else a ParameterError naming ``where``."""
    if not 0 <= domain_id <= 232:
        raise ParameterError(f"{where}: domain must be a ROS_DOMAIN_ID in 0..232, not {domain_id}")
    return domain_id


def qos_profile(kind: str, depth: int) -> QoSProfile:
    """A subscription's QoS: ``kind`` one of :data:`QOS_CHOICES`, keep last ``depth``."""
    if kind not in QOS_CHOICES:
        raise ParameterError(f"qos must be one of {', '.join(QOS_CHOICES)}, not {kind!r}")
    reliability = (
        ReliabilityPolicy.RELIABLE if kind == "reliable" else ReliabilityPolicy.BEST_EFFORT
    )
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=depth,
        reliability=reliability,
        durability=DurabilityPolicy.VOLATILE,
    )


def received_ns(info: Mapping[str, Any]) -> int:
    """When the middleware received a message [ns, system clock], from the ``MessageInfo`` a
    two-argument subscription callback gets (now, where the middleware gives none)."""
    t = int(info.get("received_timestamp") or 0)
    return t if t > 0 else time.time_ns()


def take_queued(subscription: Subscription[Any], most: int) -> Iterator[tuple[Any, Any]]:
    """Up to ``most`` messages already queued on ``subscription``, each with its
    ``MessageInfo``, oldest first; for a callback that handles the rest of its queue after the
    message it was called with.

    rclpy's executor takes one message per wake-up and builds its wait set anew, in Python, for
    each (every subscription, service, timer and QoS event handler of the node: about as much
    CPU as a reading's whole compensation). Taking what is already queued from the callback, with
    the call the executor itself uses (the subscription handle's ``take_message``), shares one
    wait set among them. ``most`` bounds how long one callback keeps the executor, so that the
    node's other callbacks get their turn while messages keep arriving.
    """
    handle = subscription.handle
    with handle:  # not destroyed while taking, as the executor guards it
        for _ in range(most):
            taken = handle.take_message(subscription.msg_type, subscription.raw)
            if taken is None:
                return
            yield taken


def stamp_ns(stamp: Time) -> int:
    """A ``builtin_interfaces/Time`` as integer nanoseconds."""
    return int(stamp.sec) * _NS + int(stamp.nanosec)


def stamp_msg(msg_stamp: Time, t_ns: int) -> None:
    """Write ``t_ns`` [ns] into a ``builtin_interfaces/Time`` in place."""
    msg_stamp.sec, msg_stamp.nanosec = divmod(int(t_ns), _NS)


def wrench_of(msg: WrenchStamped) -> NDArray[np.float64]:
    """``[fx, fy, fz, tx, ty, tz]`` [N, N*m] of a ``WrenchStamped``."""
    f, m = msg.wrench.force, msg.wrench.torque
    return np.array([f.x, f.y, f.z, m.x, m.y, m.z], dtype=float)


def wrench_stamped(t_ns: int, frame_id: str, wrench: NDArray[np.float64]) -> WrenchStamped:
    """A ``WrenchStamped`` of ``wrench`` [N, N*m] in ``frame_id`` stamped ``t_ns`` [ns]."""
    msg = WrenchStamped()
    stamp_msg(msg.header.stamp, t_ns)
    msg.header.frame_id = frame_id
    fx, fy, fz, tx, ty, tz = (float(v) for v in wrench)
    f, m = msg.wrench.force, msg.wrench.torque
    f.x, f.y, f.z, m.x, m.y, m.z = fx, fy, fz, tx, ty, tz
    return msg


def twist_stamped(t_ns: int, frame_id: str, twist: NDArray[np.float64]) -> TwistStamped:
    """A ``TwistStamped`` of ``[vx, vy, vz, wx, wy, wz]`` [m/s, rad/s] in ``frame_id``."""
    msg = TwistStamped()
    stamp_msg(msg.header.stamp, t_ns)
    msg.header.frame_id = frame_id
    vx, vy, vz, wx, wy, wz = (float(v) for v in twist)
    v, w = msg.twist.linear, msg.twist.angular
    v.x, v.y, v.z, w.x, w.y, w.z = vx, vy, vz, wx, wy, wz
    return msg


class Ros2Runtime:
    """One rclpy context and node, spun on a thread of its own (a context manager).

    Args:
        node_name: the node's name (``get_node_names()`` lists it).
        domain_id: the ROS_DOMAIN_ID; None: the environment's (``ROS_DOMAIN_ID``, else 0).
        arguments: ROS command-line arguments (``["--ros-args", "-p", "name:=value"]``): the
            node's parameter overrides and remappings, as ``ros2 run`` passes them.

    Entering starts the participant and the executor; callbacks run on the executor's one
    thread, one at a time.
    Leaving stops the executor, destroys the node and shuts the context down.
    """

    def __init__(
        self,
        node_name: str,
        *,
        domain_id: int | None = None,
        arguments: list[str] | None = None,
    ) -> None:
        if domain_id is not None:
            check_domain(domain_id, f"node {node_name!r}")
        self.node_name = node_name
        self.domain_id = domain_id
        self.arguments = list(arguments or [])
        self._context: Context | None = None
        self._node: Node | None = None
        self._executor: SingleThreadedExecutor | None = None
        self._thread: threading.Thread | None = None

    @property
    def node(self) -> Node:
        """The node (only inside the ``with`` block)."""
        if self._node is None:
            raise HardwareError(f"ROS 2 node {self.node_name!r} is not started (use a with block)")
        return self._node

    def __enter__(self) -> Ros2Runtime:
        context = Context()
        kwargs: dict[str, Any] = {"context": context, "args": ["ftcomp", *self.arguments]}
        if self.domain_id is not None:
            kwargs["domain_id"] = self.domain_id
        try:
            rclpy.init(**kwargs)
        except Exception as exc:  # rclpy's own errors (a bad --ros-args) are RCLError
            raise ParameterError(f"ROS 2 arguments {' '.join(self.arguments)!r}: {exc}") from None
        self._context = context
        try:
            self._node = Node(self.node_name, context=context)
            self._executor = SingleThreadedExecutor(context=context)
            self._executor.add_node(self._node)
        except BaseException:
            self._close()
            raise
        self._thread = threading.Thread(
            target=self._spin, name=f"rclpy {self.node_name}", daemon=True
        )
        self._thread.start()
        return self

    def _spin(self) -> None:
        executor = self._executor
        assert executor is not None
        with contextlib.suppress(ExternalShutdownException):  # the context shut down: leaving
            executor.spin()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._close()

    def _close(self) -> None:
        if self._executor is not None:
            self._executor.shutdown()
        if self._thread is not None:
            self._thread.join()
        if self._node is not None:
            self._node.destroy_node()
        if self._context is not None:
            self._context.try_shutdown()
        self._executor = self._thread = self._node = self._context = None
