"""The twin's UR controller: the register protocol of ``ur_rtde``'s control script, and motion.

``ur_rtde``'s :class:`RTDEControlInterface` (1.6, the ``[ur]`` extra's range; tested with
1.6.5) uploads a URScript program
(``rtde_control``) to the script port and then talks to it through RTDE registers only. The
program's main loop, every controller cycle:

- reads the command from ``input_int_register_0`` (registers offset by the program's
  ``reg_offset_int`` / ``reg_offset_float``, 0 or 24);
- *real-time* commands (``speedL`` 10, ``servoJ`` 11, ``servoL`` 24, ...) are taken and the
  program signals ready (``output_int_register_0 = 1``) in the same cycle;
- command 0 means idle: ready (1);
- any other command runs once (the program blocks in it: ``moveL`` 3 until the arm arrived,
  the stops 15, 16, 33, 34 until it stands), then the program writes done
  (``output_int_register_0 = 2``) and waits for the client to clear the command to 0; a
  ``moveL`` the arm cannot complete (a joint held at its limit) ends the program instead, as
  a UR controller does, and ur_rtde's ``moveL`` returns False;
- answers go to ``output_int_register_1`` (yes/no of 36, 60, 61) and
  ``output_double_register_0..5`` (joint positions of 30); 255 ends the program.

:class:`UrController` runs that loop on registers set by the RTDE clients, and turns the
commands into the motion of the simulated cell: a reference TCP pose that moves with UR's
profiles (``moveL``: trapezoidal in the path at speed ``v`` and acceleration ``a``, the tool
turning at most 4 rad/s per m/s; ``speedL``: the TCP twist ramped at ``a``; ``servoL``: toward
the streamed target within the command's time ``t``; ``stopL``: decelerating at ``a``), which
the cell's joints follow by differential inverse kinematics with a feedback on the commanded
joints' forward kinematics, so the arm lands where the profile ends.

Not modelled: ``servoL``'s ``lookahead_time`` and ``gain`` (the target is reached within ``t``),
``movej`` and force mode (a command the twin does not know is signalled done at once and
named on stderr), the RTDE watchdog.
"""

from __future__ import annotations

import math
import re
import sys
import threading
from dataclasses import dataclass
from typing import Final

import mujoco
import numpy as np
from numpy.typing import NDArray

from ftcomp.frames import matrix_from_rotvec, rotvec_from_matrix
from ftcomp.sim.arm import ARM_JOINT_NAMES
from ftcomp.sim.cell import SimCell
from ftcomp.sim.scene import NAMES

__all__ = [
    "PROTECTIVE_STOP_FORCE_N",
    "SafetyState",
    "UrController",
    "script_register_offsets",
]

#: The TCP force above which the controller makes a protective stop [N] (UR's default
#: force limit of the safety configuration: 150 N).
PROTECTIVE_STOP_FORCE_N: Final = 150.0
#: moveL turns the tool at this many rad/s per m/s of its speed parameter.
_RAD_PER_M: Final = 4.0
#: Feedback gain pulling the commanded pose onto the reference [1/s], and its caps.
_GAIN_PER_S: Final = 40.0
_MAX_CORRECTION_M_S: Final = 0.05
_MAX_CORRECTION_RAD_S: Final = 0.2
#: Speed limits of servoL's approach to its target [m/s, rad/s].
_SERVO_MAX_M_S: Final = 1.0
_SERVO_MAX_RAD_S: Final = math.pi
#: moveL is done once the arm is this close to the target [m, rad], or after this long [s]
#: if it is within the second pair; further from it then, a joint held the arm (at its limit)
#: and the program stops.
_ARRIVED_M: Final = 5e-5
_ARRIVED_RAD: Final = 2e-4
_ARRIVE_TIMEOUT_S: Final = 0.5
_HELD_M: Final = 1e-3
_HELD_RAD: Final = math.radians(0.5)
_REALTIME: Final = frozenset({6, 9, 10, 11, 24, 25, 26, 27, 38, 58, 66, 67, 68, 69, 70, 71})
_STOP_COMMANDS: Final = frozenset({15, 16, 33, 34})
_IDLE, _READY, _DONE = 0, 1, 2


@dataclass
class _Move:
    """A moveL in progress: start, displacement, profile (trapezoid in the path length)."""

    p0: NDArray[np.float64]
    R0: NDArray[np.float64]
    dp: NDArray[np.float64]
    w: NDArray[np.float64]
    length: float
    a: float
    v: float
    t_acc: float
    total: float
    t: float = 0.0
    arrived_t: float = 0.0


def script_register_offsets(script: str) -> tuple[int, int]:
    """``(int offset, float offset)`` of the registers an uploaded ``rtde_control`` program
    uses (0, or 24 for the upper range); 0 where the program does not say."""

    def offset(name: str) -> int:
        match = re.search(rf"{name}\s*=\s*(?:#[^\n]*\n)?\s*(\d+)", script)
        return int(match.group(1)) if match else 0

    return offset("reg_offset_int"), offset("reg_offset_float")


@dataclass(frozen=True)
class SafetyState:
    """The controller's safety state as RTDE reports it.

    Attributes:
        protective_stop: the arm is in a protective stop.
        reason: why (empty when none).
    """

    protective_stop: bool = False
    reason: str = ""

    @property
    def safety_mode(self) -> int:
        """RTDE ``safety_mode``: 1 normal, 3 protective stop."""
        return 3 if self.protective_stop else 1

    @property
    def safety_status_bits(self) -> int:
        """RTDE ``safety_status_bits``: bit 0 normal mode, bit 2 protective stopped."""
        return 0b100 if self.protective_stop else 0b1


def _skew_free_error(R_target: NDArray[np.float64], R: NDArray[np.float64]) -> NDArray[np.float64]:
    """The rotation vector taking ``R`` to ``R_target``, base frame [rad]."""
    return np.array(rotvec_from_matrix(R_target @ R.T))


def _clip_norm(v: NDArray[np.float64], limit: float) -> NDArray[np.float64]:
    n = float(np.linalg.norm(v))
    return v * (limit / n) if n > limit else v


class UrController:
    """The UR controller's cycle on a simulated cell.

    Args:
        cell: the cell whose sensor frame is the TCP (identity mount).
        cycle_s: the controller's cycle [s] (2 ms: the e-Series' 500 Hz).
        force_limit_N: protective stop above this TCP force [N].
    """

    def __init__(
        self,
        cell: SimCell,
        cycle_s: float = 0.002,
        force_limit_N: float = PROTECTIVE_STOP_FORCE_N,
    ) -> None:
        self.cell = cell
        self.dt = cycle_s
        self.force_limit_N = force_limit_N
        self.lock = threading.Lock()
        self.inputs: dict[str, float | int | tuple[float, ...]] = {}
        self.registers: dict[str, float | int] = {}
        self.script_running = False
        self.offset_int = 0
        self.offset_float = 0
        self.safety = SafetyState()
        self.payload_kg = 0.0
        self._fk = mujoco.MjData(cell.model)
        self._site = cell.model.site(NAMES["ft_site"]).id
        self._R_base_world = cell.R_world_base.T
        p, R = self.commanded_pose()
        self.p_ref, self.R_ref = p, R
        self.v_ref = np.zeros(6)
        self.mode = "hold"
        self.executing = False
        self.blocking: str | None = None
        self.move: _Move | None = None
        self.speed_target = np.zeros(6)
        self.speed_acc = 0.5
        self.stop_dec = 10.0
        self.servo_target: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        self.servo_time = 0.002
        self.unknown: set[int] = set()

    # ---------------------------------------------------------------- registers
    def write_input(self, name: str, value: float | int | tuple[float, ...]) -> None:
        """Set one RTDE input (called from the RTDE sessions' threads)."""
        self.inputs[name] = value

    def _in_int(self, i: int) -> int:
        return int(self.inputs.get(f"input_int_register_{i + self.offset_int}", 0))  # type: ignore[arg-type]

    def _in_float(self, i: int) -> float:
        return float(self.inputs.get(f"input_double_register_{i + self.offset_float}", 0.0))  # type: ignore[arg-type]

    def _out_int(self, i: int, value: int) -> None:
        self.registers[f"output_int_register_{i + self.offset_int}"] = value

    def _out_float(self, i: int, value: float) -> None:
        self.registers[f"output_double_register_{i + self.offset_float}"] = value

    def _pose_in(self, i: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        v = [self._in_float(i + k) for k in range(6)]
        return np.array(v[:3]), matrix_from_rotvec(v[3:])

    # ---------------------------------------------------------------- program
    def start_program(self, script: str) -> None:
        """A program arrived on the script port: ``rtde_control`` starts its loop."""
        with self.lock:
            if "def rtde_control" not in script:
                return
            self.offset_int, self.offset_float = script_register_offsets(script)
            self.registers.clear()
            self.executing = False
            self.blocking = None
            self._enter_hold()
            if not self.safety.protective_stop:
                self.script_running = True
                self._out_int(2, 0)
                self._out_int(0, _READY)

    def stop_program(self) -> None:
        """The program stops (dashboard ``stop``, pendant, 255): the arm stops at once."""
        with self.lock:
            self.script_running = False
            self.blocking = None
            self._enter_hold()

    def protective_stop(self, reason: str) -> None:
        """A protective stop: motion stops in this cycle, the program ends."""
        with self.lock:
            self.safety = SafetyState(True, reason)
            self.script_running = False
            self.blocking = None
            self._enter_hold()

    def unlock_protective_stop(self) -> None:
        """The pendant's (or dashboard's) unlock."""
        with self.lock:
            self.safety = SafetyState()

    # ---------------------------------------------------------------- kinematics
    def commanded_pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The TCP pose of the commanded joints, base frame (``p`` [m], ``R``)."""
        d = self._fk
        d.qpos[:6] = self.cell.q_command_rad
        mujoco.mj_kinematics(self.cell.model, d)
        Rbw = self._R_base_world
        return Rbw @ d.site_xpos[self._site], Rbw @ d.site_xmat[self._site].reshape(3, 3)

    def _enter_hold(self) -> None:
        self.mode = "hold"
        self.v_ref = np.zeros(6)
        self.servo_target = None
        self.speed_target = np.zeros(6)

    # ---------------------------------------------------------------- commands
    def _process(self, cmd: int) -> None:
        if cmd == 3:  # moveL
            p1, R1 = self._pose_in(0)
            v, a, asynchronous = self._in_float(6), self._in_float(7), self._in_int(1)
            self._start_move(p1, R1, max(v, 1e-4), max(a, 1e-4))
            if asynchronous != 1:
                self.blocking = "move"
        elif cmd == 10:  # speedL
            self.speed_target = np.array([self._in_float(k) for k in range(6)])
            self.speed_acc = max(self._in_float(6), 1e-4)
            self.mode = "speed"
        elif cmd == 24:  # servoL
            self.servo_target = self._pose_in(0)
            self.servo_time = max(self._in_float(8), self.dt)
            self.mode = "servo"
        elif cmd in _STOP_COMMANDS:
            self.stop_dec = max(self._in_float(0), 1e-4)
            self.mode = "stopping"
            self.servo_target = None
            self.blocking = "stop"
        elif cmd in (36, 60, 61):  # pose within safety limits / IK has a solution
            p, R = self._pose_in(0)
            self._out_int(1, int(self.cell.is_reachable(p, R)))
        elif cmd == 30:  # inverse kinematics
            p, R = self._pose_in(0)
            try:
                q = self.cell.solve_ik(p, R)
            except Exception:  # an unreachable pose: the controller faults the program
                q = self.cell.q_rad
            for k in range(6):
                self._out_float(k, float(q[k]))
        elif cmd == 17:  # set_payload
            self.payload_kg = self._in_float(0)
        elif cmd == 31:
            self.safety = SafetyState(True, "protective_stop() from the program")
            self.script_running = False
            self._enter_hold()
        elif cmd == 255:
            self.script_running = False
        elif cmd not in (35, 9) and cmd not in self.unknown:
            self.unknown.add(cmd)
            print(f"twin: command {cmd} of the control script is not modelled", file=sys.stderr)

    def _start_move(
        self, p1: NDArray[np.float64], R1: NDArray[np.float64], v: float, a: float
    ) -> None:
        p0, R0 = self.p_ref.copy(), self.R_ref.copy()
        dp = p1 - p0
        w = _skew_free_error(R1, R0)
        length = max(float(np.linalg.norm(dp)), float(np.linalg.norm(w)) / _RAD_PER_M)
        t_acc = v / a
        if a * t_acc * t_acc >= length:  # a triangle: never reaches v
            t_acc = math.sqrt(length / a)
            v = a * t_acc
        total = 2.0 * t_acc + (length - a * t_acc * t_acc) / v if length > 0 else 0.0
        self.move = _Move(p0, R0, dp, w, length, a, v, t_acc, total)
        self.mode = "move"

    def _move_ref(self, m: _Move) -> None:
        m.t += self.dt
        t, L, a, v, t_acc, T = m.t, m.length, m.a, m.v, m.t_acc, m.total
        if L <= 0.0 or t >= T:
            s, ds = 1.0, 0.0
        elif t < t_acc:
            s, ds = 0.5 * a * t * t / L, a * t / L
        elif t > T - t_acc:
            r = T - t
            s, ds = 1.0 - 0.5 * a * r * r / L, a * r / L
        else:
            s, ds = (0.5 * a * t_acc * t_acc + v * (t - t_acc)) / L, v / L
        self.p_ref = m.p0 + s * m.dp
        self.R_ref = matrix_from_rotvec(s * m.w) @ m.R0
        self.v_ref = np.concatenate([ds * m.dp, ds * m.w])

    def _arrival(self, m: _Move) -> str:
        """``"moving"``, ``"arrived"``, or ``"held"``: the profile ended
        :data:`_ARRIVE_TIMEOUT_S` ago and the arm is still further than ``_HELD_M`` or
        ``_HELD_RAD`` from its target."""
        if m.t < m.total:
            return "moving"
        m.arrived_t += self.dt
        p, R = self.cell.sensor_pose()
        off_m = float(np.linalg.norm(p - self.p_ref))
        off_rad = float(np.linalg.norm(_skew_free_error(self.R_ref, R)))
        if off_m < _ARRIVED_M and off_rad < _ARRIVED_RAD:
            return "arrived"
        if m.arrived_t < _ARRIVE_TIMEOUT_S:
            return "moving"
        if off_m < _HELD_M and off_rad < _HELD_RAD:
            return "arrived"
        q = self.cell.q_command_rad
        lower, upper = self.cell.joint_range_rad
        at_limit = np.flatnonzero((q <= lower + 1e-6) | (q >= upper - 1e-6))
        why = (
            f"joint {ARM_JOINT_NAMES[int(at_limit[0])]} at its limit"
            if at_limit.size
            else "the arm could not follow"
        )
        print(
            f"twin: moveL ended {off_m * 1e3:.1f} mm and {math.degrees(off_rad):.1f} deg from "
            f"its target ({why}): the program stops, as a UR controller's does on a move it "
            "cannot complete",
            file=sys.stderr,
        )
        return "held"

    # ---------------------------------------------------------------- the cycle
    def _program_cycle(self) -> None:
        if self.blocking is not None:
            return
        cmd = self._in_int(0)
        if cmd in _REALTIME:
            self._process(cmd)
            self._out_int(0, _READY)
        elif cmd == _IDLE:
            self.executing = False
            self._out_int(0, _READY)
        elif not self.executing:
            self.executing = True
            self._process(cmd)
            if self.blocking is None and self.script_running:
                self._out_int(0, _DONE)

    def _reference_cycle(self) -> None:
        dt = self.dt
        if self.mode == "move" and self.move is not None:
            self._move_ref(self.move)
            if self.blocking == "move":
                arrival = self._arrival(self.move)
                if arrival == "arrived":
                    self.blocking = None
                    self._out_int(0, _DONE)
                elif arrival == "held":  # the program ends and the arm holds where it is
                    self.script_running = False
                    self.blocking = None
                    self._enter_hold()
            return
        if self.mode == "speed":
            dv = self.speed_target - self.v_ref
            dv = np.concatenate(
                [
                    _clip_norm(dv[:3], self.speed_acc * dt),
                    _clip_norm(dv[3:], self.speed_acc * _RAD_PER_M * dt),
                ]
            )
            self.v_ref = self.v_ref + dv
        elif self.mode == "servo" and self.servo_target is not None:
            p_t, R_t = self.servo_target
            k = 1.0 / self.servo_time
            self.v_ref = np.concatenate(
                [
                    _clip_norm((p_t - self.p_ref) * k, _SERVO_MAX_M_S),
                    _clip_norm(_skew_free_error(R_t, self.R_ref) * k, _SERVO_MAX_RAD_S),
                ]
            )
        elif self.mode == "stopping":
            self.v_ref = np.concatenate(
                [
                    _clip_norm(
                        self.v_ref[:3],
                        max(0.0, float(np.linalg.norm(self.v_ref[:3])) - self.stop_dec * dt),
                    ),
                    _clip_norm(
                        self.v_ref[3:],
                        max(
                            0.0,
                            float(np.linalg.norm(self.v_ref[3:])) - self.stop_dec * _RAD_PER_M * dt,
                        ),
                    ),
                ]
            )
            if not self.v_ref.any():
                self.mode = "hold"
                if self.blocking == "stop":
                    self.blocking = None
                    self._out_int(0, _DONE)
        else:
            self.v_ref = np.zeros(6)
        self.p_ref = self.p_ref + self.v_ref[:3] * dt
        self.R_ref = matrix_from_rotvec(self.v_ref[3:] * dt) @ self.R_ref

    def cycle(self, contact_force_N: float) -> NDArray[np.float64]:
        """One controller cycle: the program's loop, the reference, and the twist to command
        the cell with (base frame, shape (6,)).

        Args:
            contact_force_N: the TCP force magnitude the safety system sees [N].
        """
        with self.lock:
            if contact_force_N > self.force_limit_N and not self.safety.protective_stop:
                self.safety = SafetyState(
                    True, f"TCP force {contact_force_N:.0f} N above {self.force_limit_N:g} N"
                )
                self.script_running = False
                self.blocking = None
                self._enter_hold()
            if self.script_running:
                self._program_cycle()
            elif self.mode != "hold":
                self._enter_hold()
            self._reference_cycle()
            p, R = self.commanded_pose()
            if self.mode == "hold" and not self.script_running:
                self.p_ref, self.R_ref = p, R  # a stopped arm holds where it is
                return np.zeros(6)
            correction = np.concatenate(
                [
                    _clip_norm((self.p_ref - p) * _GAIN_PER_S, _MAX_CORRECTION_M_S),
                    _clip_norm(
                        _skew_free_error(self.R_ref, R) * _GAIN_PER_S, _MAX_CORRECTION_RAD_S
                    ),
                ]
            )
            return self.v_ref + correction

    def status(self) -> tuple[int, int, int]:
        """``(runtime_state, robot_status_bits, robot_mode)`` as RTDE reports them."""
        running = self.script_running
        return (2 if running else 1), (0b11 if running else 0b1), 7
