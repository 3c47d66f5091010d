"""``serve_twin``: the simulated cell served as a robot and a wrist sensor, on loopback.

One process, one real-time loop at the robot face's period (a UR e-Series: 2 ms): each period
runs the robot face's controller (:mod:`ftcomp.twin.faces`), the MuJoCo cell's 1 ms physics
steps through the period, hands the wrist sensor's new samples (at the sensor face's rate) to
the sensor face and the period's state to the robot face's clients, and writes the contact
log's row. Each face binds its own address before the loop starts, and nothing else is bound.
Which faces exist, with their faults, is the device registry's
(:mod:`ftcomp.hardware.devices`): ``ftcomp twin --robot ur5e --sensor netft`` (the defaults)
pairs any robot face with any sensor face.
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import ipaddress
import math
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numpy as np

from ftcomp.errors import ParameterError
from ftcomp.frames import rotvec_from_matrix
from ftcomp.hardware.devices import Device, Fault, load_target, twin_faces
from ftcomp.hardware.pacing import LoopClock, TimingSummary
from ftcomp.io.atomic import atomic_output, atomic_write_text
from ftcomp.io.truth_json import truth_document
from ftcomp.session.log import LogObserver, ObserverThread
from ftcomp.sim.arm import ArmModel
from ftcomp.sim.cell import SimCell
from ftcomp.sim.cell_config import CellConfig
from ftcomp.sim.sensor import SensorSpec, SimWrenchSensor
from ftcomp.sim.tool import LoadSpec
from ftcomp.twin.faces import RobotFace, SensorFace
from ftcomp.twin.netft import RT_PRIORITY

__all__ = [
    "CONTACT_LOG_COLUMNS",
    "TwinConfig",
    "TwinResult",
    "face_arm",
    "pair_faults",
    "serve_twin",
]

#: The contact log's columns (``--contact-log``): time, the surfaces' wrench on the load (base
#: frame, torque about the TCP), the TCP pose (metres, rotation vector), the safety state.
CONTACT_LOG_COLUMNS: Final = (
    "t_s", "fx", "fy", "fz", "tx", "ty", "tz", "x", "y", "z", "rx", "ry", "rz", "safety",
)  # fmt: skip

#: The loop starts its schedule again once it is this far behind (a stall) [s]: a period's
#: lateness is caught up, a stall's is not.
_RESTART_AFTER_S: Final = 0.05


def face_arm(robot: str) -> ArmModel | None:
    """The simulated arm of a robot face (None: the cell's default arm); build a
    :class:`~ftcomp.sim.cell_config.CellConfig` for the twin with it, since where a sensor may
    sit on the flange depends on the arm."""
    arm = twin_faces("robot")[robot].twin.arm  # type: ignore[union-attr]
    return None if arm is None else load_target(arm)()


def pair_faults(robot: str, sensor: str) -> dict[str, Fault]:
    """The faults a pair of faces injects on demand: name -> fault (a fault both declare, as
    ``network-loss``, once: injected on both)."""
    faults: dict[str, Fault] = {}
    for device in (twin_faces("robot")[robot], twin_faces("sensor")[sensor]):
        assert device.twin is not None
        for fault in device.twin.faults:
            faults.setdefault(fault.name, fault)
    return faults


@dataclass(frozen=True)
class TwinConfig:
    """What the twin serves and how.

    Attributes:
        robot_host: loopback address of the robot's ports (127.0.0.0/8).
        sensor_host: loopback address of the sensor (127.0.0.0/8).
        seconds: serve this long [s] (or until SIGTERM / Ctrl-C).
        robot: the robot face (a twin face of :mod:`ftcomp.hardware.devices`: ``ur5e``).
        sensor: the sensor face (``netft``).
        cell: the simulated cell: tool, load and surface, base tilt, the sensor's realism and
            where it sits on the flange (:class:`~ftcomp.sim.cell_config.CellConfig`; a UR's
            TCP offset is the sensor's offset on the flange). Its arm is the robot face's.
        truth_path: write the true tool, bias, tilt and mount here (JSON), or None.
        contact_log_path: write the contact log here (CSV), or None.
        fault: a fault one of the two faces declares, or None.
        fault_at_s: when, after a client first commanded the arm to move [s] (``run``: its
            loop's first cycle).
        realtime: ask for SCHED_FIFO for the loop and the faces' senders (as ur_rtde does).
        sensor_rate_hz: the sensor face's output rate [Hz] (None: the face's default, or the
            simulated sensor's), within the face's fastest; each sample a fresh draw (noise
            and quantisation) of the contact wrench held between physics steps.
    """

    robot_host: str
    sensor_host: str
    seconds: float
    robot: str = "ur5e"
    sensor: str = "netft"
    cell: CellConfig = field(default_factory=CellConfig)
    truth_path: Path | None = None
    contact_log_path: Path | None = None
    fault: str | None = None
    fault_at_s: float = 1.0
    realtime: bool = True
    sensor_rate_hz: float | None = None

    def __post_init__(self) -> None:
        for name in ("robot_host", "sensor_host"):
            host = getattr(self, name)
            try:
                address = ipaddress.IPv4Address(host)
            except ValueError:
                raise ParameterError(
                    f"{name}: {host!r} is not an IPv4 address", field=name
                ) from None
            if not address.is_loopback:
                raise ParameterError(
                    f"{name}: {host} is outside 127.0.0.0/8 (loopback only)", field=name
                )
        if self.robot_host == self.sensor_host:
            raise ParameterError(
                "robot_host and sensor_host must differ", field=("robot_host", "sensor_host")
            )
        if not (math.isfinite(self.seconds) and 0.0 < self.seconds <= 86400.0):
            raise ParameterError(
                f"seconds must be in (0, 86400], got {self.seconds}", field="seconds"
            )
        for kind, name in (("robot", self.robot), ("sensor", self.sensor)):
            faces = twin_faces(kind)  # type: ignore[arg-type]
            if name not in faces:
                raise ParameterError(
                    f"{kind}: unknown {name!r}; known: {', '.join(faces)}", field=kind
                )
        faults = pair_faults(self.robot, self.sensor)
        if self.fault is not None and self.fault not in faults:
            raise ParameterError(
                f"fault: {self.fault!r} is declared by neither {self.robot} nor {self.sensor}; "
                f"their faults: {', '.join(faults)}",
                field="fault",
            )
        if not (math.isfinite(self.fault_at_s) and self.fault_at_s >= 0.0):
            raise ParameterError(
                f"fault_at_s must be >= 0, got {self.fault_at_s}", field="fault_at_s"
            )
        most = self.sensor_face().twin.max_rate_hz  # type: ignore[union-attr]
        rate = self.sensor_rate_hz
        if rate is not None and not (
            math.isfinite(rate) and 0.0 < rate <= (most if most is not None else math.inf)
        ):
            bound = f"{most:g}]" if most is not None else "inf)"
            raise ParameterError(
                f"sensor_rate_hz must be in (0, {bound} Hz for {self.sensor}, got {rate:g}",
                field="sensor_rate_hz",
            )

    def robot_face(self) -> Device:
        """The robot face's device."""
        return twin_faces("robot")[self.robot]

    def sensor_face(self) -> Device:
        """The sensor face's device."""
        return twin_faces("sensor")[self.sensor]

    def rate_hz(self) -> float:
        """The sensor face's output rate [Hz]: as given, the face's default, or the simulated
        sensor's."""
        if self.sensor_rate_hz is not None:
            return self.sensor_rate_hz
        default = self.sensor_face().twin.rate_hz  # type: ignore[union-attr]
        return default if default is not None else SensorSpec().output_rate_Hz

    def cell_config(self) -> CellConfig:
        """The cell served: :attr:`cell` with the robot face's arm."""
        arm = face_arm(self.robot)
        return self.cell if arm is None else dataclasses.replace(self.cell, arm=arm)

    def open_cell(self) -> SimCell:
        """The cell this twin serves (nothing is bound)."""
        return self.cell_config().open_cell()


@dataclass(frozen=True)
class TwinResult:
    """What a twin's run served.

    Attributes:
        cycles: the loop's periods run.
        late_cycles: periods that started more than one period late.
        robot_served: what the robot face served (``60251 RTDE packages``).
        sensor_served: what the sensor face served (``50213 RDT records``).
        reason: why it ended (``time``, ``signal``).
        realtime: whether the loop got real-time priority (SCHED_FIFO).
        timing: the loop's timing (:class:`~ftcomp.hardware.pacing.TimingSummary`, as every
            live loop of ftcomp reports it).
        contact: with a load and a surface, what the surface carried (the truth a client's
            placement is judged by: ``the surface carries 4.901 N of the load's 4.903 N at
            the end, at most 4.950 N``); empty otherwise.
        fault: with a fault, whether it came and when (``injected the fault bota-overrange
            0.502 s after a client first commanded the arm (asked for 0.5 s)``: later than
            asked by as much as the period that saw it was late), or that it did not: the run
            ended first; empty otherwise.
    """

    cycles: int
    late_cycles: int
    robot_served: str
    sensor_served: str
    reason: str
    realtime: bool
    timing: TimingSummary
    contact: str = ""
    fault: str = ""

    def line(self) -> str:
        """The twin's last line: what it served and its compute time."""
        t = self.timing
        step = (
            f"step p50 {t.compute_p50_s * 1e6:.0f} us, p99 {t.compute_p99_s * 1e6:.0f} us"
            if t.cycles
            else "no step"
        )
        return (
            f"twin served {self.cycles} periods ({self.late_cycles} late), {self.robot_served}, "
            f"{self.sensor_served}; {step}"
            f"{'' if self.realtime else ' (no real-time priority)'}; ended by {self.reason}"
            + "".join(f"\n{text}" for text in (self.fault, self.contact) if text)
        )


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


class _Twin:
    """The running twin: the cell, its two faces, the fault clock."""

    def __init__(
        self, config: TwinConfig, cell: SimCell, robot: RobotFace, sensor: SensorFace
    ) -> None:
        self.config = config
        self.cell = cell
        self.robot = robot
        self.sensor = sensor
        self.faults = pair_faults(config.robot, config.sensor)
        self.started_at: float | None = None
        # When the fault came, after a client first commanded the arm [s]: its asked-for time,
        # or later by as much as the loop's period that saw it was late.
        self.fault_fired_after_s: float | None = None
        # The surface's push on the load (its true contact force, >= 0) [N]: largest, last.
        self.contact_peak_N = 0.0
        self.contact_last_N = 0.0

    def _fire_fault(self, now: float) -> None:
        """The fault on its face(s) once ``fault_at_s`` passed since a client first commanded
        the arm."""
        fault = self.config.fault
        if fault is None or self.fault_fired_after_s is not None:
            return
        if self.started_at is None and self.robot.commanded():
            self.started_at = now
        if self.started_at is None or now - self.started_at < self.config.fault_at_s:
            return
        self.fault_fired_after_s = now - self.started_at
        for face, device in (
            (self.robot, self.config.robot_face()),
            (self.sensor, self.config.sensor_face()),
        ):
            assert device.twin is not None
            if any(f.name == fault for f in device.twin.faults):
                face.inject(fault)

    def run(self, seconds: float, stop: threading.Event, log: Any) -> TwinResult:
        # As every live loop of ftcomp (hardware.pacing.LoopClock): the set-up (MuJoCo, numpy,
        # scipy) frozen out of the collector (a full collection over it took 30-40 ms, a stall
        # that starved the sensor's stream), collection in the slack, SCHED_FIFO for the loop
        # and a low real-time priority for the faces' threads, so that none is preempted by an
        # ordinary process while it holds the interpreter's lock (which stalled the loop).
        clock = LoopClock(
            self.robot.period_s,
            name="ftcomp twin",
            priority=RT_PRIORITY,
            realtime=self.config.realtime,
            restart_after_s=_RESTART_AFTER_S,
        )
        with clock:
            reason = self._cycles(seconds, stop, log, clock)
        summary = clock.summary()
        self.robot.close()
        self.sensor.close()
        return TwinResult(
            cycles=summary.cycles,
            late_cycles=summary.late_cycles,
            robot_served=self.robot.served(),
            sensor_served=self.sensor.served(),
            reason=reason,
            realtime=clock.realtime,
            timing=summary,
            contact=self._contact_line(),
            fault=self._fault_line(),
        )

    def _fault_line(self) -> str:
        """Whether the fault came (a client's stop is judged against it)."""
        fault, at_s = self.config.fault, self.config.fault_at_s
        if fault is None:
            return ""
        if self.fault_fired_after_s is not None:
            return (
                f"injected the fault {fault} {self.fault_fired_after_s:.3f} s after a client "
                f"first commanded the arm (asked for {at_s:g} s)"
            )
        return f"did not inject the fault {fault}: the twin ended first"

    def _carries_a_load(self) -> bool:
        cell_config = self.config.cell
        return cell_config.load_kg is not None and cell_config.surface != "none"

    def _contact_line(self) -> str:
        """What the surface carried: the truth of a placement (``sim place``'s verdict is
        judged on it; here the client's outcome is not known, so the numbers alone)."""
        if not self._carries_a_load():
            return ""
        assert self.config.cell.load_kg is not None
        weight = LoadSpec(self.config.cell.load_kg).weight_N
        return (
            f"contact (truth): the surface carries {self.contact_last_N:.3f} N of the load's "
            f"{weight:.3f} N at the end, at most {self.contact_peak_N:.3f} N (pressed "
            f"{max(0.0, self.contact_peak_N - weight):.3f} N beyond its weight)"
        )

    def _cycles(self, seconds: float, stop: threading.Event, log: Any, clock: LoopClock) -> str:
        """The cell's loop until ``seconds`` pass or ``stop`` is set; why it ended."""
        cell, robot, sensor = self.cell, self.robot, self.sensor
        steps = max(1, round(robot.period_s / cell.control_period_s))
        start = time.monotonic()
        # The sensor's samples at its face's rate (the cell's sensor when the rates agree):
        # each physics step's wrench held for the ticks until the next, every tick a fresh draw.
        rate_hz = self.config.rate_hz()
        wrist = (
            cell.sensor
            if rate_hz == cell.sensor.spec.output_rate_Hz
            else SimWrenchSensor(
                dataclasses.replace(cell.sensor.spec, output_rate_Hz=rate_hz),
                cell.ideal_wrench_sensor,
                cell.time,
                seed=self.config.cell.seed,
            )
        )
        last_wrench = cell.sensor.read().wrench_sensor
        track_contact = self._carries_a_load()
        while True:
            now = time.monotonic()
            if stop.is_set():
                return "signal"
            if now - start >= seconds:
                return "time"
            clock.start()
            self._fire_fault(now)
            w_contact = cell.true_contact_wrench_base(cell.sensor_pose()[0])
            robot.cycle(float(np.linalg.norm(w_contact[:3])))
            samples = []
            for _ in range(steps):
                cell.wait_cycle()
                # Read after each physics step: the ticks since the last one see its state.
                samples += wrist.read_new()
            if track_contact:
                self.contact_last_N = cell.true_contact_force_N()
                self.contact_peak_N = max(self.contact_peak_N, self.contact_last_N)
            if samples:
                last_wrench = samples[-1].wrench_sensor
            sensor.push(samples)
            robot.publish(last_wrench)
            if log is not None:
                p, R = cell.sensor_pose()
                log.writerow(
                    [
                        f"{cell.time():.4f}",
                        *(f"{v:.5f}" for v in w_contact),
                        *(f"{v:.6f}" for v in _pose6(p, R)),
                        robot.safety(),
                    ]
                )
            clock.sent()
            clock.wait()


def _open_faces(config: TwinConfig, cell: SimCell) -> tuple[RobotFace, SensorFace]:
    """Both faces, bound (the sensor's first: a process of its own takes longest); nothing
    left bound when one cannot bind."""
    robot_device, sensor_device = config.robot_face(), config.sensor_face()
    assert robot_device.twin is not None and sensor_device.twin is not None
    sensor: SensorFace = load_target(sensor_device.twin.factory)(
        config.sensor_host, rate_hz=config.rate_hz(), realtime=config.realtime
    )
    try:
        robot: RobotFace = load_target(robot_device.twin.factory)(
            config.robot_host, cell, realtime=config.realtime, seed=config.cell.seed
        )
    except BaseException:
        sensor.close()
        raise
    return robot, sensor


def serve_twin(
    config: TwinConfig,
    on_ready: Callable[[str], None],
    stop: threading.Event | None = None,
    observers: Sequence[LogObserver] = (),
) -> TwinResult:
    """Build the cell, bind both faces, call ``on_ready`` with the ready line, and serve
    until ``config.seconds`` pass, ``stop`` is set, or SIGTERM / SIGINT arrives.

    The ready line is ``twin ready: robot URI sensor URI`` with the URIs that open the faces
    live. ``observers`` (e.g. :class:`ftcomp.views.foxglove_view.TwinView`, ``--view``) see
    every period's contact-log row (:data:`CONTACT_LOG_COLUMNS`, as numbers; ``safety`` 1.0
    in a safety stop) on a worker thread: the loop only queues it.

    Raises:
        ParameterError: a socket cannot be bound (busy port, address not local), or an option
            is out of range. Nothing is left bound or half-written.
    """
    stop = stop if stop is not None else threading.Event()
    # The loop, the faces' senders and sessions share the interpreter: hand it over every
    # 0.2 ms (Python's default, 5 ms, would hold a sender back by whole periods).
    sys.setswitchinterval(2e-4)
    cell = config.open_cell()
    robot, sensor = _open_faces(config, cell)
    twin = _Twin(config, cell, robot, sensor)
    previous: dict[signal.Signals, Any] = {}
    try:
        if config.truth_path is not None:
            import json

            document = truth_document(cell.true_gravity_model())
            document["mount"] = {"R_tcp_sensor": np.eye(3).tolist(), "p_tcp_sensor_m": [0, 0, 0]}
            cell_fields = dataclasses.asdict(dataclasses.replace(config.cell, arm=None))  # type: ignore[arg-type]
            del cell_fields["arm"]
            document["twin"] = {"robot": config.robot, "sensor": config.sensor, "cell": cell_fields}
            atomic_write_text(config.truth_path, json.dumps(document, indent=2) + "\n")
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGTERM, signal.SIGINT):
                previous[sig] = signal.signal(sig, lambda *_: stop.set())
        on_ready(f"twin ready: robot {robot.uri()} sensor {sensor.uri()}")
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
            return twin.run(config.seconds, stop, sink)
    finally:
        robot.close()
        sensor.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
