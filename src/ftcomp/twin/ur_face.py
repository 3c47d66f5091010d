"""The twin's UR e-Series face: RTDE, the dashboard and the script ports over the cell's arm.

Bound on the robot's loopback address: RTDE (TCP 30004, the controller's 500 Hz stream),
the dashboard (29999) and the script ports (30001-30003), as ``ur_rtde``'s
``RTDEControlInterface`` and ``RTDEReceiveInterface`` need them. The controller
(:class:`~ftcomp.twin.controller.UrController`: the control script's register protocol and the
motion profiles) runs once a period in the cell's loop; each period's data package goes to
every RTDE client.

What is faithful: the wire protocols (RTDE v2 with its real types, the dashboard's answers,
the script's register protocol as ``ur_rtde`` 1.6 uses it); the 500 Hz stream;
moveJ/moveJ_IK/moveL/speedJ/speedL/servoL/stops as profiles, the inverse kinematics nearest
``qnear`` (:mod:`ftcomp.twin.controller`); the arm, a UR5e from UR's published DH table and link
masses (:func:`ftcomp.sim.arm.ur5e_arm`), its TCP the wrist sensor's frame where the cell's
flange offset puts it. What is not: the joint servos (stiff PD loops, not UR's), force
mode and the watchdog (a command the twin does not model ends the program, as a URScript error
does); ``actual_TCP_force`` and ``ft_raw_wrench`` are the wrist
sensor's readings (the same physics, not a second sensor).

The payload, as a UR handles it: ``set_payload(mass, cog)`` (the centre of gravity from the tool
flange, in the flange frame) is what RTDE's ``payload`` and ``payload_cog`` report, and
``actual_TCP_force`` is the reading less the payload's weight (its force in base orientation,
down the base's z as the controller's installation has it, and its moment about the flange
origin); ``zero_ftsensor`` makes ``actual_TCP_force`` read zero there from then on (an offset
in the TCP frame, the mean of the next 0.1 s of readings: UR does not publish how many its
zeroing averages). ``ft_raw_wrench`` stays raw.

Faults (declared in :mod:`ftcomp.hardware.devices`): ``rtde-stop`` and ``network-loss`` (no
more data packages, connections open), ``protective-stop``, ``script-stop``, ``latency``
(every package 8-14 ms late).
"""

from __future__ import annotations

import collections
import contextlib
import socket
import threading
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.frames import cross3, matrix_from_rotvec, rotvec_from_matrix
from ftcomp.sim.cell import SimCell
from ftcomp.twin.controller import UrController
from ftcomp.twin.netft import bind_socket
from ftcomp.twin.ports import (
    DASHBOARD_PORT,
    SCRIPT_PORTS,
    accept_forever,
    serve_dashboard,
    serve_script,
)
from ftcomp.twin.rtde import RtdeSession

__all__ = ["UrFace", "flange_wrenches"]

_CYCLE_S: Final = 0.002
_VERSION: Final = (5, 11, 1, 108318)
_RTDE_PORT: Final = 30004
#: zero_ftsensor averages this many periods' readings (0.1 s).
_ZERO_PACKAGES: Final = 50
#: The latency fault: each package this late, plus up to the jitter [s].
_LATENCY_S: Final = 0.008
_JITTER_S: Final = 0.004


def flange_wrenches(
    wrench_tcp: NDArray[np.float64],
    R_base_tcp: NDArray[np.float64],
    R_flange_tcp: NDArray[np.float64],
    p_flange_tcp_m: NDArray[np.float64],
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


def _pose6(p: NDArray[np.float64], R: NDArray[np.float64]) -> list[float]:
    return [*p.tolist(), *rotvec_from_matrix(R)]


class UrFace:
    """A UR e-Series controller over the cell's arm (module docstring; a
    :class:`~ftcomp.twin.faces.RobotFace`).

    Args:
        host: the robot's loopback address.
        cell: the cell; its sensor frame is the controller's TCP.
        realtime: unused (the face's threads share the twin's process and its priority).
        seed: seeds the latency fault's jitter.

    Raises:
        ParameterError: a port cannot be bound (nothing is left bound).
    """

    period_s: float = _CYCLE_S

    def __init__(self, host: str, cell: SimCell, *, realtime: bool, seed: int) -> None:
        del realtime
        self.host = host
        self.cell = cell
        self.controller = UrController(cell, _CYCLE_S)
        self.tcp_offset = (
            matrix_from_rotvec(cell.config.rotvec_flange_sensor_rad),
            np.array(cell.config.p_flange_sensor_m, dtype=float),
        )
        #: zero_ftsensor's offset, TCP frame: the mean of the readings (less the payload) of the
        #: first _ZERO_PACKAGES periods after it (None: not zeroing now).
        self.ft_offset = np.zeros(6)
        self.zeroing: list[NDArray[np.float64]] | None = None
        self.sessions: list[RtdeSession] = []
        self.sessions_lock = threading.Lock()
        self.packets_closed = 0
        self.silent = False
        self.latency = False
        self.rng = np.random.default_rng(seed + 7)
        #: The latency fault's packages held back: (due time, state, registers), in order; the
        #: cell's loop sends each in its first period past its due time (no thread of its own:
        #: one holding the interpreter's lock while preempted held up the cell, and with it the
        #: sensor's stream, which the fault must leave alone).
        self.delayed: collections.deque[tuple[float, dict[str, object], dict[str, Any]]] = (
            collections.deque()
        )
        self.ports = self._bind(host)
        threading.Thread(
            target=accept_forever, args=(self.ports["rtde"], self._rtde_session), daemon=True
        ).start()
        threading.Thread(
            target=serve_dashboard, args=(self.ports["dashboard"], self.controller), daemon=True
        ).start()
        for port in SCRIPT_PORTS:
            threading.Thread(
                target=serve_script,
                args=(self.ports[f"script{port}"], self.controller),
                daemon=True,
            ).start()

    @staticmethod
    def _bind(host: str) -> dict[str, socket.socket]:
        """Every socket, bound before anything runs (a busy port is one error, nothing left)."""
        ports: dict[str, socket.socket] = {}
        try:
            ports["rtde"] = bind_socket(host, _RTDE_PORT)
            ports["dashboard"] = bind_socket(host, DASHBOARD_PORT)
            for port in SCRIPT_PORTS:
                ports[f"script{port}"] = bind_socket(host, port)
            for sock in ports.values():
                sock.listen(8)
        except BaseException:
            for sock in ports.values():
                sock.close()
            raise
        return ports

    def _rtde_session(self, conn: socket.socket) -> None:
        session = RtdeSession(conn, _VERSION, self.controller.write_inputs)
        with self.sessions_lock:
            self.packets_closed += sum(s.packets for s in self.sessions if s.closed)
            self.sessions = [s for s in self.sessions if not s.closed] + [session]
        session.serve()

    # ------------------------------------------------------------------ RobotFace
    def uri(self) -> str:
        return f"ur://{self.host}"

    def commanded(self) -> bool:
        return self.controller.commanded

    def cycle(self, contact_force_N: float) -> None:
        self.cell.command_twist(self.controller.cycle(contact_force_N))

    def publish(self, wrench_sensor: NDArray[np.float64]) -> None:
        if self.silent or not self._listened_to():
            return
        state = self._state(wrench_sensor)
        registers = {**self.controller.inputs, **self.controller.registers}
        if not self.latency:
            self._send(state, registers)
            return
        # The network holds the package back; the cell goes on.
        now = self.cell.time()
        self.delayed.append(
            (now + _LATENCY_S + _JITTER_S * float(self.rng.random()), state, registers)
        )
        while self.delayed and self.delayed[0][0] <= now:
            _, late_state, late_registers = self.delayed.popleft()
            self._send(late_state, late_registers)

    def _listened_to(self) -> bool:
        """Whether a period's state goes anywhere: a started RTDE session, a package the
        latency fault holds back, or a zero_ftsensor averaging the next packages. Building it
        took a fifth of an idle twin's cycle (0.16 of 0.77 ms, 2-core host)."""
        ctl = self.controller
        return (
            any(session.started for session in self.sessions)
            or bool(self.delayed)
            or ctl.zero_ft_requested
            or self.zeroing is not None
        )

    def inject(self, fault: str) -> None:
        if fault in ("rtde-stop", "network-loss"):
            self.silent = True
        elif fault == "protective-stop":
            self.controller.protective_stop(
                "a protective stop on demand (the twin's protective-stop fault)"
            )
        elif fault == "script-stop":
            self.controller.stop_program()
        elif fault == "latency":
            self.latency = True

    def safety(self) -> str:
        return "protective_stop" if self.controller.safety.protective_stop else "normal"

    def served(self) -> str:
        packets = self.packets_closed + sum(s.packets for s in self.sessions)
        return f"{packets} RTDE packages"

    def close(self) -> None:
        self.controller.stop_program()
        for sock in self.ports.values():
            with contextlib.suppress(OSError):
                sock.close()

    # ------------------------------------------------------------------ state
    def _state(self, wrench_sensor: NDArray[np.float64]) -> dict[str, object]:
        cell, ctl = self.cell, self.controller
        p, R = cell.sensor_pose()
        _, raw_wrench = flange_wrenches(wrench_sensor, R, *self.tcp_offset)
        tcp_force, _ = flange_wrenches(self._less_payload(wrench_sensor, R), R, *self.tcp_offset)
        runtime, robot_bits, robot_mode = ctl.status()
        q = cell.q_rad.tolist()
        qd = cell.data.qvel[: len(q)].tolist()
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
            "joint_mode": [255] * len(q),
            "payload": ctl.payload_kg,
            "payload_cog": ctl.payload_cog_m.tolist(),
            "actual_main_voltage": 48.0,
            "actual_robot_voltage": 48.0,
        }

    def _less_payload(
        self, wrench_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """The reading less the payload's weight and zero_ftsensor's offset, TCP frame (torque
        about the TCP origin)."""
        ctl = self.controller
        R_flange_tcp, p_flange_tcp = self.tcp_offset
        f = R_base_tcp.T @ np.array([0.0, 0.0, -STANDARD_GRAVITY_MPS2 * ctl.payload_kg])
        cog_tcp = R_flange_tcp.T @ (ctl.payload_cog_m - p_flange_tcp)
        wrench = wrench_tcp - np.concatenate([f, cross3(cog_tcp, f)])
        if ctl.zero_ft_requested:
            ctl.zero_ft_requested = False
            self.zeroing = []
        if self.zeroing is not None:
            self.zeroing.append(wrench)
            if len(self.zeroing) >= _ZERO_PACKAGES:
                self.ft_offset = np.mean(self.zeroing, axis=0)
                self.zeroing = None
        return wrench - self.ft_offset

    def _send(self, state: dict[str, object], registers: dict[str, Any]) -> None:
        with self.sessions_lock:
            sessions = list(self.sessions)
        for session in sessions:
            session.publish(state, registers)
