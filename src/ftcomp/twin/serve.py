"""``serve_twin``: the simulated cell served as a UR e-Series with a wrist Net F/T, on loopback.

One process, one real-time loop at the e-Series' 500 Hz: each 2 ms cycle runs the controller
(:class:`~ftcomp.twin.controller.UrController`: the control script's register protocol and the
motion profiles), two 1 ms cycles of the MuJoCo cell, hands the wrist sensor's new samples
(1200 Hz) to the Net F/T's RDT stream and one data package to every RTDE client, and writes
the contact log's row. Sockets are bound before the loop starts, to the two addresses given and
nothing else: the robot's (RTDE 30004, dashboard 29999, script 30001-30003) and the sensor's
(RDT UDP 49152, HTTP 80).

What is faithful: the wire protocols (RTDE v2 with its real types, the dashboard's answers,
the script's register protocol as ``ur_rtde`` 1.6 uses it, Net F/T HTTP and RDT with
its bias and buffered mode); the 500 Hz stream; moveL/speedL/servoL/stops as profiles; the
contact physics of the cell (MuJoCo); the arm, a UR5e from UR's published DH table and link
masses (:func:`ftcomp.sim.arm.ur5e_arm`), the wrist sensor on its flange where the TCP offset
puts it. What is not: the joint servos (stiff PD loops, not UR's), joint-space moves, force
mode and the watchdog; ``actual_TCP_force`` and ``ft_raw_wrench`` are the wrist sensor's
readings (the same physics, not a second sensor).
"""

from __future__ import annotations

import collections
import contextlib
import csv
import dataclasses
import gc
import ipaddress
import math
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np

from ftcomp.control.timing import LoopTiming, TimingSummary
from ftcomp.errors import ParameterError
from ftcomp.frames import cross3, matrix_from_rotvec, rotvec_from_matrix
from ftcomp.hardware.pacing import realtime_loop
from ftcomp.hardware.registry import parse_uri
from ftcomp.io.atomic import atomic_output, atomic_write_text
from ftcomp.io.truth_json import truth_document
from ftcomp.session.log import LogObserver, ObserverThread
from ftcomp.sim.arm import ur5e_arm
from ftcomp.sim.backend import MAX_LOAD_KG, sensor_spec_from_uri
from ftcomp.sim.cell import COLLECTION_POSITION_BASE_M, SimCell
from ftcomp.sim.scene import SceneConfig
from ftcomp.sim.sensor import SensorSpec, SimWrenchSensor
from ftcomp.sim.surfaces import SURFACE_KINDS
from ftcomp.sim.tool import LoadSpec
from ftcomp.twin.controller import UrController
from ftcomp.twin.faults import FAULTS
from ftcomp.twin.netft import (
    COUNTS_PER_FORCE,
    COUNTS_PER_TORQUE,
    RT_PRIORITY,
    SERIOUS_STATUS,
    NetFtProcess,
    bind_socket,
)
from ftcomp.twin.ports import (
    DASHBOARD_PORT,
    SCRIPT_PORTS,
    accept_forever,
    serve_dashboard,
    serve_script,
)
from ftcomp.twin.rtde import RtdeSession

__all__ = [
    "CONTACT_LOG_COLUMNS",
    "MAX_SENSOR_RATE_HZ",
    "ROBOTS",
    "TwinConfig",
    "TwinResult",
    "flange_wrenches",
    "serve_twin",
]

#: Robots the twin answers as.
ROBOTS: Final = ("ur5e",)
_CYCLE_S: Final = 0.002
_VERSION: Final = (5, 11, 1, 108318)
_RTDE_PORT: Final = 30004
#: The contact log's columns (``--contact-log``): time, the surfaces' wrench on the load (base
#: frame, torque about the TCP), the TCP pose (metres, rotation vector), the safety state.
CONTACT_LOG_COLUMNS: Final = (
    "t_s", "fx", "fy", "fz", "tx", "ty", "tz", "x", "y", "z", "rx", "ry", "rz", "safety",
)  # fmt: skip


#: Net F/T counts per N (forces) and per N*m (torques), by axis.
_COUNTS_PER_UNIT: Final = np.repeat([COUNTS_PER_FORCE, COUNTS_PER_TORQUE], 3)
#: The fastest RDT output rate the twin's Net F/T offers [Hz] (ATI's Net F/T: up to 7000 Hz).
MAX_SENSOR_RATE_HZ: Final = 7000.0


@dataclass(frozen=True)
class TwinConfig:
    """What the twin serves and how.

    Attributes:
        robot_host: loopback address of the robot's ports (127.0.0.0/8).
        sensor_host: loopback address of the Net F/T (127.0.0.0/8).
        seconds: serve this long [s] (or until SIGTERM / Ctrl-C).
        robot: the robot answered as (:data:`ROBOTS`).
        load_kg: a load held in the gripper [kg] (None: no load).
        surface: what lies on the table (``none``, ``sponge``, ``book``).
        clearance_mm: with a load and a surface, start holding it this far above [mm].
        tilt_deg: base mounting tilt ``(U, V)`` [deg].
        seed: the sensor noise's seed (the same options give the same readings).
        gain_error_percent: the sensor's gain error on every axis [%].
        realistic_drift: a real sensor's bias drift (wander and warm-up) times this, 0: none.
        drift_N_per_min: force-bias drift rate, x y z [N/min].
        truth_path: write the true tool, bias, tilt and mount here (JSON), or None.
        contact_log_path: write the contact log here (CSV), or None.
        fault: a fault of :data:`FAULTS` to inject, or None.
        fault_at_s: when, after the first RTDE client started streaming [s].
        realtime: ask for SCHED_FIFO for the loop and the Net F/T's sender (as ur_rtde does).
        tcp_offset_mm: the controller's TCP offset, the TCP origin in the flange frame [mm]
            (PolyScope's Installation > TCP). The TCP is the wrist sensor's frame: the cell
            mounts the sensor on the UR5e's flange (DH frame 6) at this offset, so
            ``actual_TCP_pose`` is the flange's pose (UR's DH forward kinematics) times it,
            ``actual_TCP_force`` is reported about the flange origin and ``ft_raw_wrench`` in
            the flange frame, as an e-Series does.
        tcp_rotvec_rad: the TCP offset's rotation (TCP axes in the flange frame), a rotation
            vector [rad].
        sensor_rate_hz: the Net F/T's RDT output rate [Hz], in (0, :data:`MAX_SENSOR_RATE_HZ`]
            (a real Net F/T streams at up to 7000 Hz); each record a fresh sample (noise and
            quantisation drawn per record) of the contact wrench held between physics steps.
    """

    robot_host: str
    sensor_host: str
    seconds: float
    robot: str = "ur5e"
    load_kg: float | None = None
    surface: str = "none"
    clearance_mm: float = 5.0
    tilt_deg: tuple[float, float] = (0.0, 0.0)
    seed: int = 0
    gain_error_percent: float = 0.0
    realistic_drift: float = 0.0
    drift_N_per_min: tuple[float, float, float] = (0.0, 0.0, 0.0)
    truth_path: Path | None = None
    contact_log_path: Path | None = None
    fault: str | None = None
    fault_at_s: float = 1.0
    realtime: bool = True
    tcp_offset_mm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    tcp_rotvec_rad: tuple[float, float, float] = (0.0, 0.0, 0.0)
    sensor_rate_hz: float = SensorSpec().output_rate_Hz

    def __post_init__(self) -> None:
        for name in ("robot_host", "sensor_host"):
            host = getattr(self, name)
            try:
                address = ipaddress.IPv4Address(host)
            except ValueError:
                raise ParameterError(f"{name}: {host!r} is not an IPv4 address") from None
            if not address.is_loopback:
                raise ParameterError(f"{name}: {host} is outside 127.0.0.0/8 (loopback only)")
        if self.robot_host == self.sensor_host:
            raise ParameterError("robot_host and sensor_host must differ")
        if not (math.isfinite(self.seconds) and 0.0 < self.seconds <= 86400.0):
            raise ParameterError(f"seconds must be in (0, 86400], got {self.seconds}")
        if self.robot not in ROBOTS:
            raise ParameterError(f"robot: unknown {self.robot!r}; known: {', '.join(ROBOTS)}")
        if self.surface not in SURFACE_KINDS:
            raise ParameterError(
                f"surface: unknown {self.surface!r}; known: {', '.join(SURFACE_KINDS)}"
            )
        if self.load_kg is not None and not (
            math.isfinite(self.load_kg) and 0.0 < self.load_kg <= MAX_LOAD_KG
        ):
            raise ParameterError(f"load_kg must be in (0, {MAX_LOAD_KG}] kg, got {self.load_kg}")
        if not (math.isfinite(self.clearance_mm) and 0.0 <= self.clearance_mm <= 100.0):
            raise ParameterError(f"clearance_mm must be in [0, 100], got {self.clearance_mm}")
        if any(not math.isfinite(t) or abs(t) >= 30.0 for t in self.tilt_deg):
            raise ParameterError(f"tilt_deg must be within +-30 deg, got {self.tilt_deg}")
        if self.fault is not None and self.fault not in FAULTS:
            raise ParameterError(f"fault: unknown {self.fault!r}; known: {', '.join(FAULTS)}")
        if not (math.isfinite(self.fault_at_s) and self.fault_at_s >= 0.0):
            raise ParameterError(f"fault_at_s must be >= 0, got {self.fault_at_s}")
        if self.seed < 0:
            raise ParameterError(f"seed must be >= 0, got {self.seed}")
        if not (math.isfinite(self.gain_error_percent) and abs(self.gain_error_percent) < 50.0):
            raise ParameterError("gain_error_percent must be within +-50 %")
        if not (math.isfinite(self.realistic_drift) and 0.0 <= self.realistic_drift <= 100.0):
            raise ParameterError(f"realistic_drift must be in 0 .. 100, got {self.realistic_drift}")
        if len(self.tcp_offset_mm) != 3 or any(
            not math.isfinite(v) or abs(v) > 500.0 for v in self.tcp_offset_mm
        ):
            raise ParameterError(
                f"tcp_offset_mm must be 3 values within +-500, got {self.tcp_offset_mm}"
            )
        if len(self.tcp_rotvec_rad) != 3 or not (
            all(math.isfinite(v) for v in self.tcp_rotvec_rad)
            and math.hypot(*self.tcp_rotvec_rad) <= math.pi
        ):
            raise ParameterError(
                f"tcp_rotvec_rad must be 3 values of norm <= pi, got {self.tcp_rotvec_rad}"
            )
        if not (
            math.isfinite(self.sensor_rate_hz) and 0.0 < self.sensor_rate_hz <= MAX_SENSOR_RATE_HZ
        ):
            raise ParameterError(
                f"sensor_rate_hz must be in (0, {MAX_SENSOR_RATE_HZ:g}] Hz (a Net F/T's RDT "
                f"rates), got {self.sensor_rate_hz:g}"
            )

    def sim_uri(self) -> str:
        """The ``sim://`` URI of the cell this twin serves, but for the arm (a ``sim://``
        cell carries the C4-like arm, the twin the UR5e: :meth:`open_cell`)."""
        parts = [f"tilt_deg={self.tilt_deg[0]:g},{self.tilt_deg[1]:g}", f"seed={self.seed}"]
        if self.load_kg is not None:
            parts += [f"load_kg={self.load_kg:g}", "grasp=1"]
            if self.surface != "none":
                parts.append(f"clearance_mm={self.clearance_mm:g}")
        parts.append(f"surface={self.surface}")
        if self.gain_error_percent:
            parts.append(f"gain_error_percent={self.gain_error_percent:g}")
        if self.realistic_drift:
            parts.append(f"realistic_drift={self.realistic_drift:g}")
        if any(self.drift_N_per_min):
            parts.append("drift_N_per_min=" + ",".join(f"{v:g}" for v in self.drift_N_per_min))
        return "sim://?" + "&".join(parts)

    def open_cell(self) -> SimCell:
        """The cell this twin serves: the UR5e with the wrist sensor at the TCP offset, the
        sensor's realism, and a load grasped (held ``clearance_mm`` above a surface)."""
        spec = sensor_spec_from_uri(parse_uri(self.sim_uri()))
        scene = SceneConfig(
            tilt_U_rad=math.radians(self.tilt_deg[0]),
            tilt_V_rad=math.radians(self.tilt_deg[1]),
            load=LoadSpec(self.load_kg) if self.load_kg is not None else None,
            surface=self.surface,  # type: ignore[arg-type]
            arm=ur5e_arm(),
            p_flange_sensor_m=tuple(v * 1e-3 for v in self.tcp_offset_mm),  # type: ignore[arg-type]
            rotvec_flange_sensor_rad=self.tcp_rotvec_rad,
        )
        cell = SimCell(scene, spec, seed=self.seed)
        if any(self.tcp_offset_mm) or any(self.tcp_rotvec_rad):
            # The sensor (the TCP) at the start pose whatever the offset: tool down in front.
            cell.move_pose(COLLECTION_POSITION_BASE_M, np.diag([1.0, -1.0, -1.0]), 0.5)
        if self.load_kg is not None:
            clearance_m = self.clearance_mm * 1e-3
            if self.surface != "none":  # grasp 20 mm up (empty on the way), then lower
                cell.hold_above_surface(max(clearance_m, 0.02), 0.5)
            cell.grasp()
            if self.surface != "none":
                cell.hold_above_surface(clearance_m, 0.3)
        return cell


@dataclass(frozen=True)
class TwinResult:
    """What a twin's run served.

    Attributes:
        cycles: controller cycles run.
        late_cycles: cycles that started more than one period late.
        rtde_packets: RTDE data packages sent, over all clients.
        rdt_records: RDT records sent.
        step_us_p50, step_us_p99: the cycle's compute time [us], percentiles.
        reason: why it ended (``time``, ``signal``).
        realtime: whether the loop got real-time priority (SCHED_FIFO).
        timing: the loop's timing (:class:`~ftcomp.control.timing.TimingSummary`, as every
            live loop of ftcomp reports it; ``late_cycles`` and the step percentiles are its).
    """

    cycles: int
    late_cycles: int
    rtde_packets: int
    rdt_records: int
    step_us_p50: float
    step_us_p99: float
    reason: str
    realtime: bool = False
    timing: TimingSummary | None = None


@contextlib.contextmanager
def _bound(config: TwinConfig) -> Iterator[dict[str, socket.socket]]:
    """Every socket, bound before anything runs (a busy port is one error, nothing left)."""
    ports: dict[str, socket.socket] = {}
    try:
        ports["rtde"] = bind_socket(config.robot_host, _RTDE_PORT)
        ports["dashboard"] = bind_socket(config.robot_host, DASHBOARD_PORT)
        for port in SCRIPT_PORTS:
            ports[f"script{port}"] = bind_socket(config.robot_host, port)
        for sock in ports.values():
            sock.listen(8)
        yield ports
    finally:
        for sock in ports.values():
            with contextlib.suppress(OSError):
                sock.close()


class _ContactRows:
    """The loop's contact-log rows (text, as written) to the CSV file and to the observers."""

    def __init__(self, writer: Any, observers: ObserverThread | None) -> None:
        self.writer = writer
        self.observers = observers

    def writerow(self, row: list[str]) -> None:
        if self.writer is not None:
            self.writer.writerow(row)
        if self.observers is not None:
            numbers = [float(v) for v in row[:-1]]
            numbers.append(0.0 if row[-1] == "normal" else 1.0)
            self.observers.row(round(numbers[0] * 1e9), numbers)


def _pose6(p: np.ndarray, R: np.ndarray) -> list[float]:
    return [*p.tolist(), *rotvec_from_matrix(R)]


def flange_wrenches(
    wrench_tcp: np.ndarray,
    R_base_tcp: np.ndarray,
    R_flange_tcp: np.ndarray,
    p_flange_tcp_m: np.ndarray,
) -> tuple[list[float], list[float]]:
    """What an e-Series reports of a wrench at its TCP: ``(actual_TCP_force, ft_raw_wrench)``.

    Args:
        wrench_tcp: ``[f, m]`` in the TCP frame, torque about the TCP origin [N, N*m].
        R_base_tcp: the TCP's orientation in the base frame.
        R_flange_tcp: the TCP offset's rotation (TCP axes in the flange frame).
        p_flange_tcp_m: the TCP offset (TCP origin in the flange frame) [m].

    Returns:
        ``actual_TCP_force``: base orientation, torque about the flange origin,
        ``[R f, R m + r x R f]`` with ``R = R_base_tcp`` and ``r = R_base_flange
        p_flange_tcp`` (the inverse of :func:`ftcomp.hardware.ur_sensor.tcp_wrench_from_flange`);
        ``ft_raw_wrench``: the flange frame, torque about the flange origin.
    """
    f_tcp, m_tcp = wrench_tcp[:3], wrench_tcp[3:]
    f_base, m_base = R_base_tcp @ f_tcp, R_base_tcp @ m_tcp
    lever_base = R_base_tcp @ (R_flange_tcp.T @ p_flange_tcp_m)
    f_flange = R_flange_tcp @ f_tcp
    m_flange = R_flange_tcp @ m_tcp + cross3(p_flange_tcp_m, f_flange)
    return (
        [*f_base.tolist(), *(m_base + cross3(lever_base, f_base)).tolist()],
        [*f_flange.tolist(), *m_flange.tolist()],
    )


class _Twin:
    """The running twin: the cell, the controller, the clients."""

    def __init__(
        self,
        config: TwinConfig,
        cell: SimCell,
        ports: dict[str, socket.socket],
        netft: NetFtProcess,
    ):
        self.config = config
        self.cell = cell
        self.controller = UrController(cell, _CYCLE_S)
        self.tcp_offset = (
            matrix_from_rotvec(config.tcp_rotvec_rad),
            np.array(config.tcp_offset_mm, dtype=float) * 1e-3,
        )
        self.sessions: list[RtdeSession] = []
        self.sessions_lock = threading.Lock()
        self.packets_closed = 0
        self.netft = netft
        self.sensor_streaming = False
        self.started_at: float | None = None
        self.fault_fired = False
        self.rtde_silent = False
        self.latency = False
        #: The latency fault's packages held back: (due time, state, registers), in order; the
        #: cell's loop sends each in its first cycle past its due time (no thread of its own: one
        #: holding the interpreter's lock while preempted held up the cell, and with it the Net
        #: F/T's stream, which the fault must leave alone).
        self.delayed: collections.deque[tuple[float, dict[str, object], dict[str, Any]]] = (
            collections.deque()
        )
        threading.Thread(
            target=accept_forever, args=(ports["rtde"], self._rtde_session), daemon=True
        ).start()
        threading.Thread(
            target=serve_dashboard, args=(ports["dashboard"], self.controller), daemon=True
        ).start()
        for port in SCRIPT_PORTS:
            threading.Thread(
                target=serve_script, args=(ports[f"script{port}"], self.controller), daemon=True
            ).start()

    def _rtde_session(self, conn: socket.socket) -> None:
        session = RtdeSession(conn, _VERSION, self.controller.write_input)
        with self.sessions_lock:
            self.packets_closed += sum(s.packets for s in self.sessions if s.closed)
            self.sessions = [s for s in self.sessions if not s.closed] + [session]
        session.serve()

    def _fire_fault(self, now: float) -> None:
        fault = self.config.fault
        if fault is None or self.fault_fired:
            return
        streaming = any(s.started for s in self.sessions)
        if self.started_at is None and streaming:
            self.started_at = now
        if self.started_at is None or now - self.started_at < self.config.fault_at_s:
            return
        self.fault_fired = True
        if fault in ("sensor-frozen", "rdt-loss", "network-loss"):
            self.netft.inject(fault)
        if fault in ("rtde-stop", "network-loss"):
            self.rtde_silent = True
        if fault == "protective-stop":
            self.controller.protective_stop("protective stop on demand (--fault)")
        elif fault == "script-stop":
            self.controller.stop_program()
        elif fault == "latency":
            self.latency = True

    def state(self) -> dict[str, object]:
        cell, ctl = self.cell, self.controller
        p, R = cell.sensor_pose()
        w = (
            cell.sensor.read().wrench_sensor.tolist()
            if self._last_wrench is None
            else self._last_wrench
        )
        tcp_force, raw_wrench = flange_wrenches(np.array(w), R, *self.tcp_offset)
        runtime, robot_bits, robot_mode = ctl.status()
        q = cell.q_rad.tolist()
        qd = cell.data.qvel[:6].tolist()
        return {
            "timestamp": cell.time(),
            "actual_TCP_pose": _pose6(p, R),
            "target_TCP_pose": _pose6(ctl.p_ref, ctl.R_ref),
            "actual_TCP_speed": ctl.v_ref.tolist(),
            "target_TCP_speed": ctl.v_ref.tolist(),
            "actual_q": q,
            "target_q": cell.q_command_rad.tolist(),
            "actual_qd": qd,
            "target_qd": qd,
            "actual_TCP_force": tcp_force,
            "ft_raw_wrench": raw_wrench,
            "robot_mode": robot_mode,
            "safety_mode": ctl.safety.safety_mode,
            "safety_status": ctl.safety.safety_mode,
            "safety_status_bits": ctl.safety.safety_status_bits,
            "robot_status_bits": robot_bits,
            "runtime_state": runtime,
            "speed_scaling": 1.0,
            "target_speed_fraction": 1.0,
            "joint_mode": [255] * 6,
            "payload": ctl.payload_kg,
            "actual_main_voltage": 48.0,
            "actual_robot_voltage": 48.0,
        }

    _last_wrench: list[float] | None = None

    def _publish(self, state: dict[str, object], registers: dict[str, Any]) -> None:
        with self.sessions_lock:
            sessions = list(self.sessions)
        for session in sessions:
            session.publish(state, registers)

    def finish(self, result: TwinResult) -> TwinResult:
        """Stop the program and the Net F/T; the result with the records it sent."""
        self.controller.stop_program()
        self.netft.close()
        return dataclasses.replace(result, rdt_records=self.netft.sent)

    def run(self, seconds: float, stop: threading.Event, log: Any) -> TwinResult:
        timing = LoopTiming(_CYCLE_S, name="ftcomp twin")
        # The cell's set-up (MuJoCo, numpy, scipy) is frozen out of the collector: a full
        # collection over it took 30-40 ms, a stall that starved the Net F/T stream.
        gc.collect()
        gc.freeze()
        # As every live loop of ftcomp (hardware.pacing): SCHED_FIFO for the loop, and for the
        # process's other threads (the RTDE sessions, the script and dashboard ports) a low
        # real-time priority, so that none is preempted by an ordinary process while it holds
        # the interpreter's lock (which stalled the cell's loop behind it).
        with realtime_loop(RT_PRIORITY, realtime=self.config.realtime) as timing.realtime:
            reason = self._cycles(seconds, stop, log, timing)
        summary = timing.summary()
        return TwinResult(
            cycles=summary.cycles,
            late_cycles=summary.late_cycles,
            rtde_packets=self.packets_closed + sum(s.packets for s in self.sessions),
            rdt_records=0,
            step_us_p50=summary.compute_p50_s * 1e6 if summary.cycles else 0.0,
            step_us_p99=summary.compute_p99_s * 1e6 if summary.cycles else 0.0,
            reason=reason,
            realtime=timing.realtime,
            timing=summary,
        )

    def _cycles(self, seconds: float, stop: threading.Event, log: Any, timing: LoopTiming) -> str:
        """The cell's loop until ``seconds`` pass or ``stop`` is set; why it ended."""
        cell, ctl = self.cell, self.controller
        start = time.monotonic()
        due = start
        rng = np.random.default_rng(self.config.seed + 7)
        reason = "time"
        # The Net F/T's samples at its own rate (the cell's sensor when the rates agree): each
        # physics step's wrench held for the ticks until the next, every tick a fresh draw.
        rate_hz = self.config.sensor_rate_hz
        wrist = (
            cell.sensor
            if rate_hz == cell.sensor.spec.output_rate_Hz
            else SimWrenchSensor(
                dataclasses.replace(cell.sensor.spec, output_rate_Hz=rate_hz),
                cell.ideal_wrench_sensor,
                cell.time,
                seed=self.config.seed,
            )
        )
        while True:
            now = time.monotonic()
            if stop.is_set():
                reason = "signal"
                break
            if now - start >= seconds:
                break
            timing.start()
            self._fire_fault(now)
            w_contact = cell.true_contact_wrench_base(cell.sensor_pose()[0])
            twist = ctl.cycle(float(np.linalg.norm(w_contact[:3])))
            cell.command_twist(twist)
            cell.wait_cycle()
            # Read after each 1 ms physics step: the ticks since the last one see its state.
            samples = wrist.read_new()
            cell.wait_cycle()
            samples += wrist.read_new()
            # In counts, all samples in one numpy call (rint halves to even, as round() did).
            counts = (
                np.rint(np.reshape([s.wrench_sensor for s in samples], (-1, 6)) * _COUNTS_PER_UNIT)
                .astype(np.int64)
                .tolist()
            )
            if counts:
                self._last_wrench = samples[-1].wrench_sensor.tolist()
            status = (
                SERIOUS_STATUS if self.fault_fired and self.config.fault == "sensor-fault" else 0
            )
            self.netft.push(counts, status)
            if not self.rtde_silent:
                state = self.state()
                registers = {**ctl.inputs, **ctl.registers}
                if self.latency:  # the network holds the package back; the cell goes on
                    now = time.monotonic()
                    self.delayed.append(
                        (now + 0.008 + 0.004 * float(rng.random()), state, registers)
                    )
                    while self.delayed and self.delayed[0][0] <= now:
                        _, late_state, late_registers = self.delayed.popleft()
                        self._publish(late_state, late_registers)
                else:
                    self._publish(state, registers)
            if log is not None:
                p, R = cell.sensor_pose()
                log.writerow(
                    [
                        f"{cell.time():.4f}",
                        *(f"{v:.5f}" for v in w_contact),
                        *(f"{v:.6f}" for v in _pose6(p, R)),
                        "protective_stop" if ctl.safety.protective_stop else "normal",
                    ]
                )
            timing.sent()
            due += _CYCLE_S
            wait = due - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            elif wait < -0.05:  # far behind (a stall): start the schedule again
                due = time.monotonic()
        return reason


def serve_twin(
    config: TwinConfig,
    on_ready: Callable[[str], None],
    stop: threading.Event | None = None,
    observers: Sequence[LogObserver] = (),
) -> TwinResult:
    """Build the cell, bind every socket, call ``on_ready`` with the ready line, and serve
    until ``config.seconds`` pass, ``stop`` is set, or SIGTERM / SIGINT arrives.

    ``observers`` (e.g. :class:`ftcomp.views.foxglove_view.TwinView`, ``--view``) see every
    cycle's contact-log row (:data:`CONTACT_LOG_COLUMNS`, as numbers; ``safety`` 1.0 in a
    protective stop) on a worker thread: the loop only queues it.

    Raises:
        ParameterError: a socket cannot be bound (busy port, address not local), or an option
            is out of range. Nothing is left bound or half-written.
    """
    stop = stop if stop is not None else threading.Event()
    # The loop, the RDT sender and the RTDE sessions share the interpreter: hand it over
    # every 0.2 ms (Python's default, 5 ms, would hold a sender back by whole periods).
    sys.setswitchinterval(2e-4)
    cell = config.open_cell()
    with _bound(config) as ports:
        netft = NetFtProcess(config.sensor_host, config.sensor_rate_hz, config.realtime)
        twin = _Twin(config, cell, ports, netft)
        if config.truth_path is not None:
            import json

            document = truth_document(cell.true_gravity_model())
            document["mount"] = {"R_tcp_sensor": np.eye(3).tolist(), "p_tcp_sensor_m": [0, 0, 0]}
            document["twin"] = {
                "robot": config.robot,
                "sim_uri": config.sim_uri(),
                "tcp_offset_mm": list(config.tcp_offset_mm),
                "tcp_rotvec_rad": list(config.tcp_rotvec_rad),
            }
            atomic_write_text(config.truth_path, json.dumps(document, indent=2) + "\n")
        previous: dict[signal.Signals, Any] = {}
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGTERM, signal.SIGINT):
                previous[sig] = signal.signal(sig, lambda *_: stop.set())
        try:
            on_ready(
                f"twin ready: robot ur://{config.robot_host} sensor netft://{config.sensor_host}"
            )
            with contextlib.ExitStack() as stack:
                writer = None
                if config.contact_log_path is not None:
                    tmp = stack.enter_context(atomic_output(config.contact_log_path))
                    writer = csv.writer(stack.enter_context(open(tmp, "w", newline="")))
                    writer.writerow(CONTACT_LOG_COLUMNS)
                thread = None
                if observers:
                    thread = ObserverThread(observers)
                    stack.callback(thread.close)
                    thread.open(CONTACT_LOG_COLUMNS)
                sink = _ContactRows(writer, thread) if writer or thread else None
                return twin.finish(twin.run(config.seconds, stop, sink))
        finally:
            twin.controller.stop_program()
            if twin.netft.proc.is_alive():
                twin.netft.close()
            for sig, handler in previous.items():
                signal.signal(sig, handler)
