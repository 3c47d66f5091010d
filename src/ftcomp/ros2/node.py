"""``ftcomp ros2 node``: gravity compensation as a ROS 2 node (rclpy).

The node (``ftcomp`` by default) subscribes to a sensor's raw ``geometry_msgs/WrenchStamped``
(sensor frame) and the arm's ``sensor_msgs/JointState``, and with the URDF (a file, or the
``/robot_description`` string robot_state_publisher latches) knows the sensor's orientation.
For each raw reading it publishes, with the reading's own ``header.stamp``:

- ``~/wrench_compensated``: the contact wrench in the sensor frame (bias and tool gravity
  removed: :class:`~ftcomp.compensation.compensator.GravityCompensator`);
- ``~/wrench_contact_base``: the same wrench in the base frame's orientation (force and torque
  rotated by ``R_base_sensor``; the torque still about the sensor origin), ``frame_id`` the base.

With ``online_load`` a grasped load is weighed online
(:class:`~ftcomp.compensation.pipeline.WrenchPipeline`, the
:class:`~ftcomp.compensation.online.OnlineLoadCompensator` of ``stream --online-load``) and,
once its estimate has converged, compensated too; the node publishes ``~/load``
(``geometry_msgs/InertiaStamped``: the mass [kg] and centre of gravity [m] in the sensor frame,
the inertia tensor zero: not estimated; each state change and every :data:`LOAD_PERIOD_NS` of
readings) and ``~/load_state`` (``std_msgs/String``, latched: ``empty``, ``estimating``,
``holding``). The estimator's rate is measured from the stamps of the first 0.5 s of readings,
which are held back and published, in order and with their stamps, once it is known.

Services (``std_srvs/Trigger``): ``~/rebias`` re-estimates the bias from ``rebias_s`` of readings
with the arm still and nothing touching the tool (:func:`~ftcomp.calibration.rebias.rebias`);
``~/reload_calibration`` reads ``calibration_file`` again. Both answer ``success`` and a line.

Every callback runs on the runtime's one executor thread, one at a time (a multi-threaded
executor costs too much per message for a 1 kHz stream: docs/ros2.md, "Benchmark"). The raw
readings' callback also handles the readings queued behind its own, up to
:data:`WRENCH_BATCH` (:func:`~ftcomp.ros2.rclpy_runtime.take_queued`): rclpy's executor
builds its wait set anew for each message it takes, which costs about as much as the
compensation, so a node that fell behind catches up in a few wake-ups. A rebias
therefore does not block while it reads: its service callback is a coroutine that opens a
collection, which the readings' callback fills and closes when ``rebias_s`` has passed (or the
status timer, a second later, if the readings stopped), and then answers.

A reading that cannot be compensated honestly publishes nothing and says why on
``/diagnostics`` (``diagnostic_msgs/DiagnosticArray``, status ``ftcomp: compensation``, at once
on a change and every second): non-finite values, a ``frame_id`` other than ``sensor_frame``,
no joint states yet or joint states older than ``stale_s``. Its settings are ROS 2 parameters
(:class:`~ftcomp.ros2.node_config.NodeConfig`'s fields, ``--ros-args -p calibration_file:=...``).

Joint states are not interpolated: each reading takes the newest received before it is handled
(``stale_s`` bounds their age).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.rebias import rebias
from ftcomp.calibration_record import Calibration, TemperatureBiasDrift
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.compensation.online import LOAD_STATE_CODES
from ftcomp.compensation.pipeline import WrenchPipeline
from ftcomp.errors import FtcompError, HardwareError, ParameterError
from ftcomp.io.calibration_json import load_calibration
from ftcomp.ros2.live import JointStatePose, robot_description, urdf_chain, wait_for
from ftcomp.ros2.node_config import NodeConfig
from ftcomp.ros2.rclpy_runtime import (
    DEFAULT_QOS,
    DESCRIPTION_QOS,
    STREAM_QOS,
    DiagnosticArray,
    DiagnosticStatus,
    Future,
    InertiaStamped,
    KeyValue,
    ReentrantCallbackGroup,
    Ros2Runtime,
    String,
    Trigger,
    WrenchStamped,
    qos_profile,
    received_ns,
    stamp_msg,
    stamp_ns,
    take_queued,
    wrench_of,
)
from ftcomp.ros2.tf import clean_frame
from ftcomp.samples import Samples

__all__ = [
    "LOAD_PERIOD_NS",
    "MOVED_M",
    "TURNED_RAD",
    "WRENCH_BATCH",
    "WRENCH_DEPTH",
    "CompensationNode",
]

#: How far the sensor may move [m] and turn [rad] while ``~/rebias`` reads: further, the arm
#: was not still (the same bounds as ``--rebias-s``).
MOVED_M = 1e-3
TURNED_RAD = 0.005
#: ``~/load`` is published at each change of the estimate's state and, between them, once per
#: this span of the readings' stamps [ns] (10 Hz: a payload does not change faster, and the
#: wrench topics already carry the sensor's rate).
LOAD_PERIOD_NS = 100_000_000
#: The raw subscription's queue (keep last): 1 s at 1 kHz. The node handles readings faster
#: than a sensor sends them, so the queue is empty but across a stall of the host's scheduler,
#: whose readings it holds instead of overwriting them (docs/ros2.md, "Benchmark").
WRENCH_DEPTH = 1000
#: The most readings one wake-up of the executor handles (the joint states, the services and
#: the status timer then get their turn): 100 ms at 1 kHz.
WRENCH_BATCH = 100
#: ``~/load_state``'s words for the estimate's states (the log's ``load_state`` codes).
_STATE_WORDS = {code: state.value for state, code in LOAD_STATE_CODES.items()}


@dataclass
class _Status:
    """What the node last said on /diagnostics."""

    level: bytes
    message: str
    published: int = 0
    dropped: int = 0
    load: tuple[float, ...] = ()


@dataclass
class _Collection:
    """The readings a ``~/rebias`` collects until ``until_ns`` [ns, system clock], and the
    future that says they are all in."""

    until_ns: int
    done: Future = field(default_factory=Future)
    readings: list[tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]] = field(
        default_factory=list
    )

    def close_if_due(self, now_ns: int) -> None:
        """Complete :attr:`done` once ``now_ns`` [ns, system clock] reached :attr:`until_ns`."""
        if now_ns >= self.until_ns and not self.done.done():
            self.done.set_result(None)


class CompensationNode:
    """The compensation node, inside a :class:`~ftcomp.ros2.rclpy_runtime.Ros2Runtime`.

    Args:
        settings: :class:`~ftcomp.ros2.node_config.NodeConfig` field values a program or the
            command line gives (a ``-p name:=value`` in ``arguments`` overrides one, as ROS 2
            parameters do).
        node_name: the node's name.
        domain_id: the ROS_DOMAIN_ID (None: the environment's).
        arguments: ROS arguments (``["--ros-args", "-p", "rebias_s:=3.0"]``).

    Entering starts the node: reads the calibration and the URDF (a missing frame, an
    unreadable file: an error before anything is published), waits ``timeout_s`` for joint
    states naming the chain's joints. Leaving stops it.
    """

    def __init__(
        self,
        settings: Mapping[str, Any] | None = None,
        *,
        node_name: str = "ftcomp",
        domain_id: int | None = None,
        arguments: list[str] | None = None,
    ) -> None:
        self._given = dict(settings or {})
        unknown = sorted(set(self._given) - {f.name for f in fields(NodeConfig)})
        if unknown:
            raise ParameterError(f"unknown node settings: {', '.join(unknown)}", field=unknown[0])
        self.runtime = Ros2Runtime(node_name, domain_id=domain_id, arguments=arguments)
        self.config: NodeConfig | None = None
        self._compensator: GravityCompensator | None = None
        self._pipeline: WrenchPipeline | None = None  # with online_load
        self._load_state, self._load_sent_ns = -1, 0
        self._calibration: Calibration | None = None
        self._R_rec_sensor_T: NDArray[np.float64] | None = None
        self._pose: JointStatePose | None = None
        self._status = _Status(DiagnosticStatus.OK, "starting")
        self._rebias: _Collection | None = None  # a ~/rebias reading
        self._pub_sensor: Any = None
        self._pub_base: Any = None
        self._pub_diag: Any = None
        self._pub_load: Any = None
        self._pub_load_state: Any = None
        self._wrenches: Any = None

    # ----------------------------------------------------------------- start and stop
    def __enter__(self) -> CompensationNode:
        runtime = self.runtime.__enter__()
        try:
            self._start(runtime)
        except BaseException:
            self.runtime.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.runtime.__exit__(None, None, None)

    def serve(self, seconds: float | None = None) -> None:
        """Serve (its executor runs on its own thread) for ``seconds``, or until Ctrl-C."""
        threading.Event().wait(seconds)

    def _parameters(self, runtime: Ros2Runtime) -> NodeConfig:
        """The config from the node's parameters, declared with the given config's values."""
        node = runtime.node
        values: dict[str, Any] = {}
        for f in fields(NodeConfig):
            given = self._given.get(f.name)
            if given is None:
                given = f.default if isinstance(f.default, (str, float, bool)) else ""
            default: bool | float | str = (
                given
                if isinstance(given, bool)
                else float(given)
                if isinstance(given, float)
                else str(given)
            )
            try:
                values[f.name] = node.declare_parameter(f.name, default).value
            except Exception as exc:  # rclpy's: an override of another type
                kind = (
                    "true or false"
                    if isinstance(default, bool)
                    else "a number"
                    if isinstance(default, float)
                    else "a string"
                )
                raise ParameterError(
                    f"ROS parameter {f.name} must be {kind} ({type(exc).__name__})", field=f.name
                ) from None
        return NodeConfig(**values)

    def _start(self, runtime: Ros2Runtime) -> None:
        self.config = config = self._parameters(runtime)
        self._load(config.calibration_file)
        chain = urdf_chain(
            config.urdf or None,
            None
            if config.urdf
            else robot_description(runtime, "/robot_description", config.timeout_s),
            clean_frame(config.base_frame),
            clean_frame(config.sensor_frame),
        )
        node = runtime.node
        self._pose = JointStatePose(chain, config.joint_states)
        self._pose.subscribe(node)  # before the readings: each wake-up serves it first
        if not wait_for(
            self._pose.arrived,
            runtime,
            config.joint_states,
            "sensor_msgs/msg/JointState",
            config.timeout_s,
        ):
            raise HardwareError(
                f"no joint states naming {', '.join(self._pose.missing())} on "
                f"{config.joint_states} within {config.timeout_s:g} s"
            )
        self._out_sensor, self._out_base = WrenchStamped(), WrenchStamped()
        self._out_base.header.frame_id = config.base_frame
        self._pub_sensor = node.create_publisher(WrenchStamped, "~/wrench_compensated", STREAM_QOS)
        self._pub_base = node.create_publisher(WrenchStamped, "~/wrench_contact_base", STREAM_QOS)
        self._pub_diag = node.create_publisher(DiagnosticArray, "/diagnostics", DEFAULT_QOS)
        if config.online_load:
            self._out_load = InertiaStamped()
            self._out_load.header.frame_id = config.sensor_frame
            self._pub_load = node.create_publisher(InertiaStamped, "~/load", DEFAULT_QOS)
            self._pub_load_state = node.create_publisher(String, "~/load_state", DESCRIPTION_QOS)
        # Not in the readings' (default, mutually exclusive) callback group, which a rebias
        # awaiting its readings would otherwise hold.
        services = ReentrantCallbackGroup()
        node.create_service(Trigger, "~/rebias", self._on_rebias, callback_group=services)
        node.create_service(
            Trigger, "~/reload_calibration", self._on_reload, callback_group=services
        )
        self._wrenches = node.create_subscription(
            WrenchStamped,
            config.wrench_topic,
            self._on_wrenches,
            qos_profile(config.wrench_qos, WRENCH_DEPTH),
        )
        node.create_timer(1.0, self._publish_status)
        self._say(DiagnosticStatus.OK, "compensating")

    def _load(self, path: str) -> Calibration:
        calibration = load_calibration(path)
        self._use(calibration)
        return calibration

    def _use(self, calibration: Calibration) -> None:
        """Compensate with ``calibration`` from the next reading on (with ``online_load``, a
        new estimate: a load held is weighed again once the gripper next grasps one).

        Raises:
            ParameterError: with ``online_load``, a calibration without the tool's weight; a
                bias that follows the sensor's temperature (a wrench topic carries none).
        """
        if isinstance(calibration.bias_drift, TemperatureBiasDrift):
            raise ParameterError(
                "calibration_file: its bias follows the sensor's temperature, which a "
                "WrenchStamped topic does not carry: the node needs a calibration with another "
                "bias model"
            )
        compensator = GravityCompensator(calibration)
        pipeline = None
        if self.config is not None and self.config.online_load:
            known = self._pipeline.rate_Hz if self._pipeline is not None else math.nan
            pipeline = WrenchPipeline.weighing(calibration, known if known > 0.0 else None)
        mount = calibration.mount
        self._calibration, self._compensator = calibration, compensator
        self._pipeline = pipeline
        self._R_rec_sensor_T = None if mount is None else mount.R_rec_sensor.T.copy()

    # ----------------------------------------------------------------- the readings
    def _on_wrenches(self, msg: WrenchStamped, info: Mapping[str, Any]) -> None:
        """The raw subscription's callback: this reading, then up to :data:`WRENCH_BATCH` - 1
        queued behind it, in order, in one of the executor's wake-ups (:func:`take_queued`),
        each with the joint states that arrived before it was handled."""
        pose, subscription = self._pose, self._wrenches
        assert pose is not None
        self._on_wrench(msg, info)
        if subscription is None:  # the executor's thread ran it before _start kept it
            return
        for queued in take_queued(subscription, WRENCH_BATCH - 1):
            pose.catch_up()
            self._on_wrench(*queued)

    def _on_wrench(self, msg: WrenchStamped, info: Mapping[str, Any]) -> None:
        config, pose = self.config, self._pose
        assert config is not None and pose is not None
        wrench = wrench_of(msg)
        frame = clean_frame(msg.header.frame_id)
        if frame != config.sensor_frame:
            self._drop(f"a wrench in frame {frame!r}, the calibration's is {config.sensor_frame!r}")
            return
        if not np.isfinite(wrench).all():
            self._drop(f"a non-finite wrench on {config.wrench_topic}")
            return
        received = received_ns(info)
        try:
            t_pose, p, R = pose.pose()
        except HardwareError as exc:
            self._drop(str(exc))
            return
        if received - t_pose > config.stale_s * 1e9:  # both as the middleware received them
            self._drop(
                f"joint states on {config.joint_states} {(received - t_pose) / 1e9:.3f} s older "
                f"than the reading (stale after {config.stale_s:g} s)"
            )
            return
        collection = self._rebias
        if collection is not None:
            collection.readings.append((wrench, R, p))
            collection.close_if_due(received)
        compensator, pipeline, R_T = self._compensator, self._pipeline, self._R_rec_sensor_T
        assert compensator is not None
        R_feed = R if R_T is None else R @ R_T  # a mount-identified calibration's frame
        # Two messages made once and refilled (one callback at a time; publish serialises at
        # once): building a WrenchStamped costs about 80 us (measured).
        self._out_sensor.header.frame_id = msg.header.frame_id
        if pipeline is None:
            self._publish(stamp_ns(msg.header.stamp), compensator.compensate(wrench, R_feed), R)
        else:  # each reading once, in order; the first held back while the rate is measured
            pipeline.push(stamp_ns(msg.header.stamp), wrench, R_feed, p)
            for c in pipeline.ready:
                R_c = c.R_base_sensor if R_T is None else c.R_base_sensor @ R_T.T
                self._publish(c.t_ns, c.wrench_contact_sensor, R_c)
                self._publish_load(c.t_ns, c.load)
            pipeline.ready.clear()
        if self._status.level != DiagnosticStatus.OK:
            self._say(DiagnosticStatus.OK, "compensating")

    def _publish(self, t_ns: int, contact: NDArray[np.float64], R: NDArray[np.float64]) -> None:
        """One reading's contact wrench [N, N*m] on both topics, stamped ``t_ns`` [ns]."""
        out, base = self._out_sensor, self._out_base
        stamp_msg(out.header.stamp, t_ns)
        stamp_msg(base.header.stamp, t_ns)
        _fill(out, contact)
        self._pub_sensor.publish(out)
        _fill(base, (R @ contact.reshape(2, 3).T).T.ravel())
        self._pub_base.publish(base)
        self._status.published += 1

    def _publish_load(self, t_ns: int, load: tuple[float, ...]) -> None:
        """The online estimate after a reading stamped ``t_ns`` [ns] (``load``: the
        :data:`~ftcomp.compensation.online.LOAD_COLUMNS`): ``~/load_state`` when the state
        changed, ``~/load`` then and every :data:`LOAD_PERIOD_NS`."""
        state, mass_kg, mass_std_kg, cx, cy, cz = int(load[0]), *load[1:6]
        changed = state != self._load_state
        if not changed and t_ns - self._load_sent_ns < LOAD_PERIOD_NS:
            return
        self._load_state, self._load_sent_ns = state, t_ns
        msg = self._out_load
        stamp_msg(msg.header.stamp, t_ns)
        msg.inertia.m = mass_kg
        com = msg.inertia.com
        com.x, com.y, com.z = (v if math.isfinite(v) else 0.0 for v in (cx, cy, cz))
        self._pub_load.publish(msg)
        if changed:
            self._pub_load_state.publish(String(data=_STATE_WORDS[state]))
        self._status.load = (state, mass_kg, mass_std_kg)

    def _drop(self, why: str) -> None:
        message = why + ": nothing published"
        self._status.dropped += 1
        if self._status.message != message:
            self._say(DiagnosticStatus.ERROR, message)

    # ----------------------------------------------------------------- diagnostics
    def _say(self, level: bytes, message: str) -> None:
        self._status.level, self._status.message = level, message
        if level != DiagnosticStatus.OK:
            self.runtime.node.get_logger().warning(message)
        self._publish_status()

    def _publish_status(self) -> None:
        if self._rebias is not None:  # the readings stopped: a rebias ends a second late
            self._rebias.close_if_due(time.time_ns() - 1_000_000_000)
        if self._pub_diag is None:
            return
        s = self._status
        status = DiagnosticStatus(
            level=s.level,
            name="ftcomp: compensation",
            hardware_id=self.config.sensor_frame if self.config else "",
            message=s.message,
            values=[
                KeyValue(key="published", value=str(s.published)),
                KeyValue(key="dropped", value=str(s.dropped)),
            ],
        )
        if s.load:
            state, mass_kg, mass_std_kg = s.load
            status.values += [
                KeyValue(key="load_state", value=_STATE_WORDS[int(state)]),
                KeyValue(key="load_kg", value=f"{mass_kg:.4f}"),
                KeyValue(key="load_kg_std", value=f"{mass_std_kg:.4f}"),
            ]
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.runtime.node.get_clock().now().to_msg()
        self._pub_diag.publish(array)

    # ----------------------------------------------------------------- services
    async def _on_rebias(self, _request: Any, response: Any) -> Any:
        """Collect ``rebias_s`` of readings, then re-estimate the bias (a coroutine: the
        executor goes on compensating while it awaits the readings)."""
        config = self.config
        assert config is not None
        response.success, response.message = False, ""
        if self._rebias is not None:
            response.message = "a rebias is already reading: bias kept"
            return response
        collection = _Collection(time.time_ns() + round(config.rebias_s * 1e9))
        self._rebias = collection
        try:
            await collection.done
        finally:
            self._rebias = None
        got = collection.readings
        calibration, R_T = self._calibration, self._R_rec_sensor_T
        assert calibration is not None
        if len(got) < 2:
            response.message = (
                f"{len(got)} readings in {config.rebias_s:g} s: nothing to rebias from"
            )
            return response
        wrench = np.array([w for w, _, _ in got])
        R = np.array([r for _, r, _ in got])
        p = np.array([q for _, _, q in got])
        moved = float(np.linalg.norm(p - p[0], axis=1).max())
        cos = (np.einsum("nij,ij->n", R, R[0]) - 1.0) / 2.0
        turned = float(np.arccos(np.clip(cos, -1.0, 1.0)).max())
        if moved > MOVED_M or turned > TURNED_RAD:
            response.message = (
                f"the arm moved while the bias was read ({moved * 1e3:.1f} mm, "
                f"{math.degrees(turned):.2f} deg): bias kept"
            )
            return response
        R_rec = R if R_T is None else R @ R_T
        samples = Samples(wrench, R_rec, "quaternion", source="the still readings")
        try:
            new = rebias(calibration, samples)
        except FtcompError as exc:
            response.message = str(exc)
            return response
        shift = np.concatenate([new.model.force_bias_N, new.model.torque_bias_Nm]) - np.concatenate(
            [calibration.model.force_bias_N, calibration.model.torque_bias_Nm]
        )
        self._use(new)
        response.success = True
        response.message = (
            f"re-biased from {len(got)} still readings: the bias moved by "
            f"[{shift[0]:+.3f} {shift[1]:+.3f} {shift[2]:+.3f}] N "
            f"[{shift[3]:+.4f} {shift[4]:+.4f} {shift[5]:+.4f}] N*m"
        )
        return response

    def _on_reload(self, _request: Any, response: Any) -> Any:
        config = self.config
        assert config is not None
        try:
            self._load(config.calibration_file)
        except FtcompError as exc:
            response.success, response.message = False, f"{exc} (the previous one kept)"
            return response
        response.success, response.message = True, f"reloaded {config.calibration_file}"
        return response

    # ----------------------------------------------------------------- for programs
    @property
    def calibration(self) -> Calibration | None:
        """The calibration in use (after a rebias, the re-biased one)."""
        return self._calibration


def _fill(msg: WrenchStamped, wrench: NDArray[np.float64]) -> None:
    fx, fy, fz, tx, ty, tz = wrench.tolist()
    f, m = msg.wrench.force, msg.wrench.torque
    f.x, f.y, f.z, m.x, m.y, m.z = fx, fy, fz, tx, ty, tz
