"""Live ROS 2 topics through Cyclone DDS from PyPI, without a ROS installation (EXPERIMENTAL).

Tested against Cyclone DDS peers speaking the ROS 2 wire format (type names, CDR bytes checked
against rosbags' serialiser), not yet against a ROS 2 node: see ``docs/ros2.md``.

- ``--sensor ros2:///TOPIC?domain=0&frame=S&timeout_s=5`` (:func:`open_sensor`): subscribes to a
  ``geometry_msgs/msg/WrenchStamped`` topic (best effort, which matches reliable and best-effort
  publishers). Each reading is stamped on arrival with the host's monotonic clock (the session
  clock of hardware backends); its ``header.stamp`` is kept for republishing
  (:meth:`Ros2WrenchSensor.source_stamp_ns`). ``frame`` (optional) must equal ``header.frame_id``.
- ``--robot ros2:///?base_frame=B&tcp_frame=S&domain=0&rate_hz=500`` (:func:`open_robot`): a
  pose source, not an arm: the latest ``/tf`` and ``/tf_static`` (transient local, as tf2's static
  broadcaster offers it) composed from ``B`` to ``S``. It cannot move: a non-zero twist or a move
  is an error; ``wait_cycle`` sleeps one period.
- :class:`WrenchPublisher` publishes ``WrenchStamped`` (reliable, keep last 10, volatile: the
  ``rclcpp`` default QoS) and makes a ``run_loop`` sink of the compensated wrench.

The DDS configuration is Cyclone's own (``CYCLONEDDS_URI``); ``domain`` is the ROS_DOMAIN_ID.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.protocols import ClockName, PoseSample, Robot, WrenchSample, WrenchSensor
from ftcomp.hardware.registry import Uri
from ftcomp.ros2.dds_types import TFMessage, WrenchStamped, dds_topic, wrench_message, wrench_of
from ftcomp.ros2.tf import TransformRecord, TransformTree, clean_frame

try:  # the optional extra (dds_types has said so already if it is missing)
    from cyclonedds.core import Listener, Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration
except ImportError as exc:  # pragma: no cover
    raise HardwareError(f"ros2:// needs Cyclone DDS: pip install 'ftcomp[ros2]' ({exc})") from None

if TYPE_CHECKING:
    from ftcomp.control.loop import Reading

__all__ = [
    "Ros2PoseSource",
    "Ros2WrenchSensor",
    "WrenchPublisher",
    "open_robot",
    "open_sensor",
]

#: ROS 2's default QoS for publishers (rclcpp ``SystemDefaultsQoS`` with Cyclone: reliable,
#: keep last 10, volatile).
DEFAULT_QOS = Qos(
    Policy.Reliability.Reliable(duration(milliseconds=100)),
    Policy.History.KeepLast(10),
    Policy.Durability.Volatile,
)
_SENSOR_QOS = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(100))
_TF_QOS = Qos(Policy.Reliability.Reliable(duration(milliseconds=100)), Policy.History.KeepLast(100))
_TF_STATIC_QOS = Qos(
    Policy.Reliability.Reliable(duration(milliseconds=100)),
    Policy.History.KeepLast(100),
    Policy.Durability.TransientLocal,
)
_STAMPS_KEPT = 4096


def _domain(options: Any, uri: Uri) -> int:
    domain = options.integer("domain", 0)
    if not 0 <= domain <= 232:
        raise ParameterError(f"{uri.text!r}: domain must be a ROS_DOMAIN_ID in 0..232")
    return int(domain)


class Ros2WrenchSensor:
    """A ``WrenchStamped`` topic as a :class:`~ftcomp.hardware.protocols.WrenchSensor`.

    Args:
        topic: the ROS 2 topic (``/ft_sensor/wrench``).
        domain_id: the ROS_DOMAIN_ID.
        frame_id: if given, every message's ``header.frame_id`` must be this.
        timeout_s: how long entering waits for the first message [s].
    """

    def __init__(
        self, topic: str, *, domain_id: int = 0, frame_id: str | None = None, timeout_s: float = 5.0
    ) -> None:
        self.topic = topic
        self._dds_topic = dds_topic(topic)
        self.domain_id = domain_id
        self.frame_id = clean_frame(frame_id) if frame_id else None
        self.timeout_s = timeout_s
        self._lock = threading.Lock()
        self._new: deque[WrenchSample] = deque(maxlen=_STAMPS_KEPT)
        self._last: WrenchSample | None = None
        self._stamps: OrderedDict[int, int] = OrderedDict()
        self._error: str | None = None
        self._arrived = threading.Event()
        self._entities: list[Any] = []

    def _on_data(self, reader: DataReader | None) -> None:
        if reader is None:  # Cyclone's callback for a reader deleted while it fired (on close)
            return
        for msg in reader.take(N=256):
            if not isinstance(msg, WrenchStamped):
                continue
            now = time.monotonic_ns()
            stamp, wrench = wrench_of(msg)
            frame = clean_frame(msg.header.frame_id)
            with self._lock:
                if self.frame_id is not None and frame != self.frame_id:
                    self._error = (
                        f"ros2://{self.topic}: a reading in frame {frame!r}, expected "
                        f"{self.frame_id!r}"
                    )
                sample = WrenchSample(now, wrench)
                self._new.append(sample)
                self._last = sample
                self._stamps[now] = stamp
                while len(self._stamps) > _STAMPS_KEPT:
                    self._stamps.popitem(last=False)
            self._arrived.set()

    def __enter__(self) -> Ros2WrenchSensor:
        participant = DomainParticipant(self.domain_id)
        topic = Topic(participant, self._dds_topic, WrenchStamped)
        reader = DataReader(
            participant, topic, qos=_SENSOR_QOS, listener=Listener(on_data_available=self._on_data)
        )
        self._entities = [participant, topic, reader]
        if not self._arrived.wait(self.timeout_s):
            self._entities.clear()
            raise HardwareError(
                f"ros2://{self.topic}: no geometry_msgs/msg/WrenchStamped within "
                f"{self.timeout_s:g} s (ROS_DOMAIN_ID {self.domain_id})"
            )
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._entities.clear()  # Cyclone deletes the reader and participant with them

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


class Ros2PoseSource:
    """The pose of ``tcp_frame`` in ``base_frame`` from live ``/tf``: a read-only Robot.

    Args:
        base_frame: the robot's base frame.
        tcp_frame: the frame whose pose is reported (the sensor frame: use an identity mount).
        domain_id: the ROS_DOMAIN_ID.
        period_s: the loop period ``wait_cycle`` sleeps [s].
        timeout_s: how long entering waits for the two frames to be connected [s].
    """

    clock_name: ClockName = "monotonic"
    pose_known = True

    def __init__(
        self,
        base_frame: str,
        tcp_frame: str,
        *,
        domain_id: int = 0,
        period_s: float = 0.002,
        timeout_s: float = 5.0,
    ) -> None:
        self.base_frame, self.tcp_frame = clean_frame(base_frame), clean_frame(tcp_frame)
        self.domain_id = domain_id
        self._period = period_s
        self.timeout_s = timeout_s
        self._lock = threading.Lock()
        self._latest: dict[tuple[str, str], TransformRecord] = {}
        self._entities: list[Any] = []

    @property
    def control_period_s(self) -> float:
        """The period ``wait_cycle`` sleeps [s]."""
        return self._period

    def _on_tf(self, reader: DataReader) -> None:
        for msg in reader.take(N=256):
            if not isinstance(msg, TFMessage):
                continue
            with self._lock:
                for tr in msg.transforms:
                    v, q = tr.transform.translation, tr.transform.rotation
                    key = (clean_frame(tr.header.frame_id), clean_frame(tr.child_frame_id))
                    self._latest[key] = TransformRecord(
                        0, key[0], key[1], (v.x, v.y, v.z), (q.x, q.y, q.z, q.w), True
                    )

    def _lookup(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The latest transform of every edge, composed (held as static: no interpolation)."""
        with self._lock:
            records = list(self._latest.values())
        tree = TransformTree(records, "live /tf")
        p, R, _ = tree.lookup(self.base_frame, self.tcp_frame, np.zeros(1, dtype=np.int64))
        return p[0], R[0].as_matrix()

    def __enter__(self) -> Ros2PoseSource:
        participant = DomainParticipant(self.domain_id)
        tf = Topic(participant, "rt/tf", TFMessage)
        tf_static = Topic(participant, "rt/tf_static", TFMessage)
        listener = Listener(on_data_available=self._on_tf)
        self._entities = [participant, tf, tf_static]
        self._entities.append(DataReader(participant, tf, qos=_TF_QOS, listener=listener))
        self._entities.append(
            DataReader(participant, tf_static, qos=_TF_STATIC_QOS, listener=listener)
        )
        deadline = time.monotonic() + self.timeout_s
        while True:
            try:
                self._lookup()
                return self
            except Exception as exc:
                if time.monotonic() > deadline:
                    self._entities.clear()
                    raise HardwareError(
                        f"ros2:// pose: {self.base_frame!r} -> {self.tcp_frame!r} not on /tf "
                        f"within {self.timeout_s:g} s ({exc})"
                    ) from None
                time.sleep(0.01)

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._entities.clear()

    def now_ns(self) -> int:
        """The host's monotonic clock [ns]."""
        return time.monotonic_ns()

    def pose(self) -> PoseSample:
        """The latest composed pose, stamped now."""
        p, R = self._lookup()
        return PoseSample(time.monotonic_ns(), p, R)

    def move_pose(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64], duration_s: float
    ) -> None:
        """Not possible: a pose source cannot move."""
        raise HardwareError("ros2:// is a pose source from /tf; it cannot move the robot")

    def settle(self, max_duration_s: float) -> float:
        """Not possible: a pose source cannot hold still on command."""
        raise HardwareError("ros2:// is a pose source from /tf; it cannot move the robot")

    def command_twist(self, twist_base: NDArray[np.float64]) -> None:
        """Only zero: a pose source cannot move."""
        if np.any(np.asarray(twist_base) != 0.0):
            raise HardwareError("ros2:// is a pose source from /tf; it cannot move the robot")

    def wait_cycle(self) -> None:
        """Sleep one period."""
        time.sleep(self._period)

    def stop(self) -> None:
        """Nothing moves."""


class WrenchPublisher:
    """Publishes ``WrenchStamped`` on a ROS 2 topic (a context manager).

    Args:
        topic: the ROS 2 topic.
        frame_id: the messages' ``header.frame_id`` (the sensor frame).
        domain_id: the ROS_DOMAIN_ID.
    """

    def __init__(self, topic: str, frame_id: str, *, domain_id: int = 0) -> None:
        self.topic = topic
        self._dds_topic = dds_topic(topic)
        self.frame_id = clean_frame(frame_id)
        self.domain_id = domain_id
        self._writer: DataWriter | None = None
        self._entities: list[Any] = []
        #: Messages published.
        self.count = 0

    def __enter__(self) -> WrenchPublisher:
        participant = DomainParticipant(self.domain_id)
        topic = Topic(participant, self._dds_topic, WrenchStamped)
        self._writer = DataWriter(participant, topic, qos=DEFAULT_QOS)
        self._entities = [participant, topic, self._writer]
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._writer = None
        self._entities.clear()

    def publish(self, stamp_ns: int, wrench: NDArray[np.float64]) -> None:
        """Publish one wrench [N, N*m] stamped ``stamp_ns`` (ROS time [ns])."""
        if self._writer is None:
            raise HardwareError(f"ros2://{self.topic}: publisher not started (use a with block)")
        self._writer.write(wrench_message(stamp_ns, self.frame_id, wrench))
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


def open_sensor(uri: Uri, robot: Robot | None) -> WrenchSensor:
    """``ros2:///TOPIC?domain=N&frame=S&timeout_s=T`` (see the module docstring)."""
    options = uri.reader()
    domain = _domain(options, uri)
    frame = options.text("frame", "")
    timeout = options.number("timeout_s", 5.0)
    options.done()
    if uri.host:
        raise ParameterError(f"{uri.text!r}: no host in ros2:// URIs; write ros2:///TOPIC")
    if not uri.path or uri.path == "/":
        raise ParameterError(f"{uri.text!r}: name the WrenchStamped topic, e.g. ros2:///ft/wrench")
    assert timeout is not None
    return Ros2WrenchSensor(uri.path, domain_id=domain, frame_id=frame or None, timeout_s=timeout)


def open_robot(uri: Uri) -> Robot:
    """``ros2:///?base_frame=B&tcp_frame=S&domain=N&rate_hz=R`` (a read-only pose source)."""
    options = uri.reader()
    domain = _domain(options, uri)
    base = options.text("base_frame", "")
    tcp = options.text("tcp_frame", "")
    rate = options.number("rate_hz", 500.0)
    timeout = options.number("timeout_s", 5.0)
    options.done()
    if not base or not tcp:
        raise ParameterError(f"{uri.text!r}: give base_frame=B&tcp_frame=S (the /tf frames)")
    assert rate is not None and timeout is not None
    if not rate > 0.0:
        raise ParameterError(f"{uri.text!r}: rate_hz must be > 0")
    return Ros2PoseSource(base, tcp, domain_id=domain, period_s=1.0 / rate, timeout_s=timeout)
