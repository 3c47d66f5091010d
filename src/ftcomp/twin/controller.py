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
- any other command runs once (the program blocks in it: ``moveJ`` 1, ``moveJ_IK`` 2,
  ``moveL`` 3 and ``moveL_FK`` 4 until the arm arrived, the stops 15, 16, 33, 34 until it
  stands), then the program writes done (``output_int_register_0 = 2``) and waits for the
  client to clear the command to 0; a move the arm cannot complete (a joint held at its
  limit), a ``moveJ`` target outside the joint ranges and an inverse kinematics without a
  solution end the program instead, as a URScript runtime error does on a UR controller,
  and ur_rtde's call returns False;
- answers go to ``output_int_register_1`` (yes/no of 36, 60, 61) and
  ``output_double_register_0..5`` (joint positions of 30 and 46, the pose of 43, 44, the
  TCP offset of 40); ``set_payload`` (17) sets the payload RTDE reports and
  ``actual_TCP_force`` subtracts, ``zero_ftsensor`` (8) zeroes ``actual_TCP_force`` (the face
  does both, :class:`~ftcomp.twin.ur_face.UrFace`); 255 ends the program.

Every command of ur_rtde 1.6's script (its ``process_cmd``) that this twin does not model
ends the program with a line on stderr naming it: a client sees the failure a controller
gives for a script that stopped, never a success for a command that did nothing.

:class:`UrController` runs that loop on registers set by the RTDE clients, and turns the
commands into the motion of the simulated cell: a reference TCP pose that moves with UR's
profiles (``moveL``: trapezoidal in the path at speed ``v`` and acceleration ``a``, the tool
turning at most 4 rad/s per m/s; ``speedL``: the TCP twist ramped at ``a``; ``servoL``: toward
the streamed target within the command's time ``t``; ``stopL``: decelerating at ``a``), which
the cell's joints follow by differential inverse kinematics with a feedback on the commanded
joints' forward kinematics, so the arm lands where the profile ends. Joint moves (``moveJ``,
``speedJ``) run a reference in joint space (``moveJ``: trapezoidal, the joint with the
longest way at ``v`` and ``a``, the others scaled to arrive with it, as ``movej`` does),
turned into the TCP twist that moves the commanded joints along it (the Jacobian at the
commanded joints, with a feedback on the joint error).

Inverse kinematics (``getInverseKinematics``, ``moveJ_IK``, the has-solution checks): the
configuration within the joint ranges nearest ``qnear`` (the commanded joints when none is
given): as UR's own solver, in closed form (:mod:`ftcomp.sim.ur_kinematics`), each of the
up to eight branches with its joints turned by whole turns to the values nearest ``qnear``
within their ranges, the branch nearest ``qnear`` (Euclidean) that the simulated arm's forward
kinematics confirms.

Not modelled: ``servoL``'s ``lookahead_time`` and ``gain`` (the target is reached within ``t``),
force mode, freedrive, jogging, contact detection, path moves (each ends the program, see
above), the RTDE watchdog (``setWatchdog`` is accepted and not enforced).
"""

from __future__ import annotations

import math
import re
import sys
import threading
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

import mujoco
import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import ParameterError
from ftcomp.frames import matrix_from_rotvec, rotvec_from_matrix
from ftcomp.sim.arm import ARM_JOINT_NAMES
from ftcomp.sim.cell import SimCell
from ftcomp.sim.scene import NAMES
from ftcomp.sim.ur_kinematics import is_ur_shaped, ur_inverse_kinematics

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
#: moveJ is done once every commanded joint is this close to its target [rad] (or within
#: ``_HELD_JOINT_RAD`` after :data:`_ARRIVE_TIMEOUT_S`); joint moves' feedback gain [1/s].
_ARRIVED_JOINT_RAD: Final = 1e-4
_HELD_JOINT_RAD: Final = math.radians(0.5)
_JOINT_GAIN_PER_S: Final = 40.0
#: An inverse kinematics answer puts the TCP within this of the pose asked [m, rad] (forward
#: kinematics of the simulated arm).
_IK_TOLERANCE: Final = 1e-9
_REALTIME: Final = frozenset({6, 9, 10, 11, 24, 25, 26, 27, 38, 58, 66, 67, 68, 69, 70, 71})
_STOP_COMMANDS: Final = frozenset({15, 16, 33, 34})
#: rtde_control's motion commands: moveJ, moveJ_IK, moveL, moveL_FK, speedJ, speedL, servoL.
_MOTION_COMMANDS: Final = frozenset({1, 2, 3, 4, 9, 10, 24})
_IDLE, _READY, _DONE = 0, 1, 2
#: ur_rtde 1.6's script commands by number, for the line naming one the twin does not model.
_COMMAND_NAMES: Final = {
    5: "forceMode",
    6: "forceMode (update)",
    7: "forceModeStop",
    11: "servoJ",
    12: "servoC",
    18: "teachMode",
    19: "endTeachMode",
    20: "forceModeSetDamping",
    21: "forceModeSetGainScaling",
    25: "toolContact",
    26: "getStepTime",
    27: "getActualJointPositionsHistory",
    28: "getTargetWaypoint",
    29: "setTcp",
    32: "isJointsWithinSafetyLimits",
    37: "getJointTorques",
    39: "poseTrans",
    41: "jogStart",
    42: "jogStop",
    45: "movePath",
    47: "isSteady",
    51: "moveUntilContact",
    52: "freedriveMode",
    53: "endFreedriveMode",
    54: "getFreedriveStatus",
    56: "ftRtdeInputEnable",
    57: "enableExternalFtSensor",
    58: "getActualToolFlangePose",
    59: "setGravity",
    62: "startContactDetection",
    63: "stopContactDetection",
    64: "readContactDetection",
    65: "setTargetPayload",
}


def _trapezoid(
    t: float, length: float, a: float, v: float, t_acc: float, total: float
) -> tuple[float, float]:
    """Where a trapezoidal profile over ``length`` is at time ``t``: ``(s, ds/dt)``, ``s`` the
    fraction of the way (0 to 1)."""
    if length <= 0.0 or t >= total:
        return 1.0, 0.0
    if t < t_acc:
        return 0.5 * a * t * t / length, a * t / length
    if t > total - t_acc:
        r = total - t
        return 1.0 - 0.5 * a * r * r / length, a * r / length
    return (0.5 * a * t_acc * t_acc + v * (t - t_acc)) / length, v / length


def _profile(length: float, v: float, a: float) -> tuple[float, float, float]:
    """``(v, t_acc, total)`` of a trapezoid over ``length`` at speed ``v`` and acceleration
    ``a`` (a triangle, never reaching ``v``, when the way is short)."""
    t_acc = v / a
    if a * t_acc * t_acc >= length:
        t_acc = math.sqrt(length / a)
        v = a * t_acc
    total = 2.0 * t_acc + (length - a * t_acc * t_acc) / v if length > 0 else 0.0
    return v, t_acc, total


@dataclass
class _JointMove:
    """A moveJ in progress: start and displacement of the joints [rad], and the profile of the
    joint with the longest way."""

    q0: NDArray[np.float64]
    dq: NDArray[np.float64]
    length: float
    a: float
    v: float
    t_acc: float
    total: float
    t: float = 0.0
    arrived_t: float = 0.0

    @property
    def target(self) -> NDArray[np.float64]:
        return self.q0 + self.dq


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
        #: The payload's centre of gravity, flange frame [m] (``set_payload``'s ``cog``).
        self.payload_cog_m = np.zeros(3)
        #: zero_ftsensor asked for (the face takes the offset from its next reading).
        self.zero_ft_requested = False
        self._fk = mujoco.MjData(cell.model)
        self._ik_data = mujoco.MjData(cell.model)
        self._n = cell.n_joints
        lower, upper = cell.joint_range_rad
        self._lower, self._upper = lower, upper
        arm = cell.config.arm
        if not is_ur_shaped(arm):
            raise ParameterError("the UR controller needs a UR arm's kinematics (ur_kinematics)")
        self._arm = arm
        self._jacp = np.zeros((3, cell.model.nv))
        self._jacr = np.zeros((3, cell.model.nv))
        self._site = cell.model.site(NAMES["ft_site"]).id
        self._R_base_world = cell.R_world_base.T
        p, R = self.commanded_pose()
        self.p_ref, self.R_ref = p, R
        self.v_ref = np.zeros(6)
        self.mode = "hold"
        self.executing = False
        self.blocking: str | None = None
        self.move: _Move | None = None
        self.joint_move: _JointMove | None = None
        self.q_ref = cell.q_command_rad
        self.qd_ref = np.zeros(self._n)
        self.speedj_target = np.zeros(self._n)
        self.speed_target = np.zeros(6)
        self.speed_acc = 0.5
        self.stop_dec = 10.0
        self.servo_target: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        self.servo_time = 0.002
        self.unknown: set[int] = set()
        #: Whether a client commanded a motion (the twin's fault clock starts then).
        self.commanded = False

    # ---------------------------------------------------------------- registers
    def write_inputs(self, package: Mapping[str, float | int | tuple[float, ...]]) -> None:
        """Apply one RTDE input package whole (called from the RTDE sessions' threads).

        It waits for the cycle's lock: a cycle that read the registers between two fields of
        one package would see a new command with the previous command's arguments (an inverse
        kinematics question asked of a moveJ's joints, answered "no solution").
        """
        with self.lock:
            self.inputs.update(package)

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
        self.joint_move = None
        self.v_ref = np.zeros(6)
        self.servo_target = None
        self.speed_target = np.zeros(6)

    # ---------------------------------------------------------------- commands
    def _q_in(self, i: int) -> NDArray[np.float64]:
        return np.array([self._in_float(i + k) for k in range(self._n)])

    def _out_pose(self, p: NDArray[np.float64], R: NDArray[np.float64]) -> None:
        for k, value in enumerate([*p.tolist(), *rotvec_from_matrix(R)]):
            self._out_float(k, float(value))

    def _fail(self, why: str) -> None:
        """A URScript runtime error: the program ends, the arm holds where it is."""
        print(f"twin: {why}: the program stops, as a UR controller's does", file=sys.stderr)
        self.script_running = False
        self.blocking = None
        self._enter_hold()

    def _process(self, cmd: int) -> None:
        self.commanded = self.commanded or cmd in _MOTION_COMMANDS
        if cmd == 1:  # moveJ
            self._start_joint_move(self._q_in(0), "moveJ")
        elif cmd == 2:  # moveJ_IK
            q = self.inverse_kinematics(*self._pose_in(0), self.cell.q_command_rad)
            if q is None:
                self._fail("moveJ_IK: the pose has no inverse kinematics within the joint ranges")
                return
            self._start_joint_move(q, "moveJ_IK")
        elif cmd in (3, 4):  # moveL, moveL_FK
            p1, R1 = self._pose_in(0) if cmd == 3 else self.forward_kinematics(self._q_in(0))
            v, a, asynchronous = self._in_float(6), self._in_float(7), self._in_int(1)
            self._start_move(p1, R1, max(v, 1e-4), max(a, 1e-4))
            if asynchronous != 1:
                self.blocking = "move"
        elif cmd == 9:  # speedJ
            self.speedj_target = self._q_in(0)
            self.speed_acc = max(self._in_float(6), 1e-4)
            if self.mode != "speedj":
                self.q_ref, self.qd_ref = self.cell.q_command_rad, np.zeros(self._n)
            self.mode = "speedj"
        elif cmd == 10:  # speedL
            self.speed_target = np.array([self._in_float(k) for k in range(6)])
            self.speed_acc = max(self._in_float(6), 1e-4)
            self._leave_joint_mode()
            self.mode = "speed"
        elif cmd == 24:  # servoL
            self.servo_target = self._pose_in(0)
            self.servo_time = max(self._in_float(8), self.dt)
            self._leave_joint_mode()
            self.mode = "servo"
        elif cmd in _STOP_COMMANDS:
            self.stop_dec = max(self._in_float(0), 1e-4)
            self._leave_joint_mode()
            self.mode = "stopping"
            self.servo_target = None
            self.blocking = "stop"
        elif cmd == 36:  # pose within the safety limits: here, the joint ranges reach it
            self._out_int(1, int(self.inverse_kinematics(*self._pose_in(0), None) is not None))
        elif cmd in (60, 61):  # the inverse kinematics has a solution (61: near qnear)
            qnear = self._q_in(6) if cmd == 61 else None
            self._out_int(1, int(self.inverse_kinematics(*self._pose_in(0), qnear) is not None))
        elif cmd in (30, 46):  # inverse kinematics (30: near qnear; 46: near the joints)
            qnear = self._q_in(6) if cmd == 30 else None
            q = self.inverse_kinematics(*self._pose_in(0), qnear)
            if q is None:
                self._fail("get_inverse_kin: no solution within the joint ranges")
                return
            for k in range(self._n):
                self._out_float(k, float(q[k]))
        elif cmd == 43:  # forward kinematics of the commanded joints
            self._out_pose(*self.forward_kinematics(self.cell.q_command_rad))
        elif cmd == 44:  # forward kinematics of given joints with a given TCP offset
            p, R = self.forward_kinematics(self._q_in(0))
            p_ft, R_ft = self._tcp_offset()
            p_tcp, R_tcp = self._q_in(6)[:3], matrix_from_rotvec(self._q_in(6)[3:])
            R_flange = R @ R_ft.T  # the flange: the twin's TCP less its offset
            p_flange = p - R_flange @ p_ft
            self._out_pose(p_flange + R_flange @ p_tcp, R_flange @ R_tcp)
        elif cmd == 40:  # the TCP offset: the sensor's place on the flange
            self._out_pose(*self._tcp_offset())
        elif cmd == 8:  # zero_ftsensor: the face zeroes actual_TCP_force at its next package
            self.zero_ft_requested = True
        elif cmd == 17:  # set_payload (a zero cog keeps the one set before, as on PolyScope 5)
            self.payload_kg = self._in_float(0)
            cog = np.array([self._in_float(k) for k in (1, 2, 3)])
            if cog.any():
                self.payload_cog_m = cog
        elif cmd == 31:
            self.safety = SafetyState(True, "protective_stop() from the program")
            self.script_running = False
            self._enter_hold()
        elif cmd == 255:
            self.script_running = False
        elif cmd == 35:  # set_watchdog: accepted, not enforced (the module docstring)
            pass
        else:
            name = _COMMAND_NAMES.get(cmd, "a command ur_rtde 1.6 does not have")
            self._fail(f"command {cmd} ({name}) of the control script is not modelled")

    # ---------------------------------------------------------------- kinematics
    def _tcp_offset(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The TCP (the sensor frame) in the flange frame: position [m], rotation."""
        config = self.cell.config
        return (
            np.array(config.p_flange_sensor_m, dtype=float),
            matrix_from_rotvec(config.rotvec_flange_sensor_rad),
        )

    def forward_kinematics(
        self, q: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The TCP pose of joints ``q`` [rad], base frame (``p`` [m], ``R``)."""
        d = self._ik_data
        d.qpos[: self._n] = q
        mujoco.mj_kinematics(self.cell.model, d)
        Rbw = self._R_base_world
        return Rbw @ d.site_xpos[self._site], Rbw @ d.site_xmat[self._site].reshape(3, 3)

    def inverse_kinematics(
        self,
        p_base_tcp: NDArray[np.float64],
        R_base_tcp: NDArray[np.float64],
        qnear: NDArray[np.float64] | None,
    ) -> NDArray[np.float64] | None:
        """The joints [rad] within the ranges putting the TCP at this base-frame pose nearest
        ``qnear`` (the commanded joints when None), or None (module docstring)."""
        near = self.cell.q_command_rad if qnear is None else np.asarray(qnear, dtype=float)
        if near.shape != (self._n,) or not np.isfinite(near).all():
            return None
        p_ft, R_ft = self._tcp_offset()
        R_flange = R_base_tcp @ R_ft.T
        p_flange = p_base_tcp - R_flange @ p_ft
        turn = 2.0 * math.pi
        candidates = []
        for q in ur_inverse_kinematics(self._arm, p_flange, R_flange, float(near[5])):
            # each joint by whole turns to the value nearest qnear within its range
            nearest = q + turn * np.round((near - q) / turn)
            nearest = np.where(nearest > self._upper, nearest - turn, nearest)
            nearest = np.where(nearest < self._lower, nearest + turn, nearest)
            if np.all((nearest >= self._lower) & (nearest <= self._upper)):
                candidates.append(nearest)
        candidates.sort(key=lambda q: float(np.linalg.norm(q - near)))
        for q in candidates:
            p, R = self.forward_kinematics(q)
            if max(np.max(np.abs(p - p_base_tcp)), np.max(np.abs(R - R_base_tcp))) < _IK_TOLERANCE:
                return q
        return None

    def _joint_twist(self, qd: NDArray[np.float64]) -> NDArray[np.float64]:
        """The TCP twist (base frame) that joint velocities ``qd`` give at the commanded joints
        (:meth:`commanded_pose` has set them)."""
        mujoco.mj_comPos(self.cell.model, self._fk)
        mujoco.mj_jacSite(self.cell.model, self._fk, self._jacp, self._jacr, self._site)
        n, Rbw = self._n, self._R_base_world
        return np.concatenate([Rbw @ (self._jacp[:, :n] @ qd), Rbw @ (self._jacr[:, :n] @ qd)])

    def _start_joint_move(self, q1: NDArray[np.float64], name: str) -> None:
        outside = np.flatnonzero((q1 < self._lower) | (q1 > self._upper) | ~np.isfinite(q1))
        if outside.size:
            j = int(outside[0])
            self._fail(
                f"{name}: joint {ARM_JOINT_NAMES[j]} target {math.degrees(q1[j]):.1f} deg is "
                f"outside its range [{math.degrees(self._lower[j]):.0f}, "
                f"{math.degrees(self._upper[j]):.0f}] deg"
            )
            return
        v, a, asynchronous = self._in_float(6), self._in_float(7), self._in_int(1)
        q0 = self.cell.q_command_rad
        dq = q1 - q0
        length = float(np.max(np.abs(dq)))
        v, t_acc, total = _profile(length, max(v, 1e-4), max(a, 1e-4))
        self.joint_move = _JointMove(q0, dq, length, max(a, 1e-4), v, t_acc, total)
        self.q_ref, self.qd_ref = q0, np.zeros(self._n)
        self.mode = "jmove"
        if asynchronous != 1:
            self.blocking = "jmove"

    def _leave_joint_mode(self) -> None:
        """A Cartesian command after a joint move: its reference starts where the arm is."""
        if self.mode in ("jmove", "speedj"):
            self.joint_move = None
            self.p_ref, self.R_ref = self.commanded_pose()
            self.v_ref = self._joint_twist(self.qd_ref)
            self.mode = "hold"

    def _joint_arrival(self, m: _JointMove) -> str:
        """``"moving"``, ``"arrived"`` or ``"held"`` (as :meth:`_arrival`, in joint space)."""
        if m.t < m.total:
            return "moving"
        m.arrived_t += self.dt
        off = float(np.max(np.abs(self.cell.q_command_rad - m.target)))
        if off < _ARRIVED_JOINT_RAD:
            return "arrived"
        if m.arrived_t < _ARRIVE_TIMEOUT_S:
            return "moving"
        if off < _HELD_JOINT_RAD:
            return "arrived"
        print(
            f"twin: moveJ ended {math.degrees(off):.1f} deg from its target (the arm could not "
            "follow): the program stops, as a UR controller's does on a move it cannot complete",
            file=sys.stderr,
        )
        return "held"

    def _start_move(
        self, p1: NDArray[np.float64], R1: NDArray[np.float64], v: float, a: float
    ) -> None:
        p0, R0 = self.p_ref.copy(), self.R_ref.copy()
        dp = p1 - p0
        w = _skew_free_error(R1, R0)
        length = max(float(np.linalg.norm(dp)), float(np.linalg.norm(w)) / _RAD_PER_M)
        v, t_acc, total = _profile(length, v, a)
        self.move = _Move(p0, R0, dp, w, length, a, v, t_acc, total)
        self.mode = "move"

    def _move_ref(self, m: _Move) -> None:
        m.t += self.dt
        s, ds = _trapezoid(m.t, m.length, m.a, m.v, m.t_acc, m.total)
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

    def _joint_reference_cycle(self) -> None:
        """moveJ's and speedJ's reference, in joint space."""
        dt = self.dt
        if self.mode == "speedj":
            step = np.clip(
                self.speedj_target - self.qd_ref, -self.speed_acc * dt, self.speed_acc * dt
            )
            self.qd_ref = self.qd_ref + step
            self.q_ref = np.clip(self.q_ref + self.qd_ref * dt, self._lower, self._upper)
            return
        m = self.joint_move
        if m is None:
            return
        m.t += dt
        s, ds = _trapezoid(m.t, m.length, m.a, m.v, m.t_acc, m.total)
        self.q_ref, self.qd_ref = m.q0 + s * m.dq, ds * m.dq
        if self.blocking != "jmove":
            return
        arrival = self._joint_arrival(m)
        if arrival == "arrived":
            self.blocking = None
            self._out_int(0, _DONE)
        elif arrival == "held":  # the program ends and the arm holds where it is
            self.script_running = False
            self.blocking = None
            self._enter_hold()

    def _reference_cycle(self) -> None:
        dt = self.dt
        if self.mode in ("jmove", "speedj"):
            self._joint_reference_cycle()
            return
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
            if self.mode in ("jmove", "speedj"):
                self.p_ref, self.R_ref = p, R
                error = self.q_ref - self.cell.q_command_rad
                return self._joint_twist(self.qd_ref + _JOINT_GAIN_PER_S * error)
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
