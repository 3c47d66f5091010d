"""The ``franka://`` backend: a Franka Research 3 (or Panda) arm through ``franky-control``.

URI::

    franka://HOST                 the arm's FCI address (Desk: "Activate FCI")
        ?frequency_hz=200         the control loop's rate: a new velocity target per period [Hz]
        &dynamics=0.1             blocking moves within the arm's velocity, acceleration and
                                  jerk limits scaled by this factor, in (0, 1]
        &realtime=enforce|ignore  libfranka's real-time check: ``enforce`` (its default) refuses
                                  to connect from a kernel without real-time scheduling
        &recover=1                clear the arm's errors (libfranka's automatic error recovery)
                                  when connecting; never done unless asked
        &collision_torque_nm=20   libfranka's collision thresholds (reflexes) [N*m, per joint]
        &collision_force_n=30     and [N, Cartesian]

Frames and units, converted once here: the pose is libfranka's ``O_T_EE``, the end effector's
frame in the base frame ``O`` (metres): ``p_base_tcp`` and ``R_base_tcp``. The end effector is
the flange unless one is configured in Desk (a Franka Hand puts it 0.1034 m beyond the flange,
turned -45 deg about z; libfranka's ``F_T_EE``): the ``--mount`` is the sensor frame seen from
that end effector frame, so for a wrist sensor on the flange set Desk's end effector to none or
give the mount through the hand's offset. Twists are sent as the end effector origin's velocity
in the base frame, as libfranka's Cartesian velocity interface (``O_dP_EE_c``) takes it.

Motion: franky runs libfranka's 1 kHz loop in C++; from Python a motion is handed over
asynchronously and replaces the running one smoothly (franky plans each within the arm's limits).
:meth:`FrankaRobot.command_twist` hands over a Cartesian velocity motion holding the twist for
a few periods (:data:`_HOLD_PERIODS`): a loop that stops commanding lets the arm come to rest
within the arm's limits instead of running on. Blocking moves (:meth:`FrankaRobot.move_pose`)
are franky's Cartesian motions to an absolute target, time-optimal within the limits scaled by
``dynamics``.

Faults: libfranka's reflexes (a collision threshold crossed, a joint limit, a discontinuous
command, ``communication_constraints_violation`` when the host misses the 1 kHz deadline), the
connection's loss and the arm's refusal of a command reach franky's control thread; the next
call here raises :class:`~ftcomp.errors.HardwareError` with one line naming the error as
libfranka reports it (:func:`fault_line`), and ``ftcomp run`` ends on it, its log complete.
The errors stay on the arm until recovered: from Desk, or with ``?recover=1`` on the next
connection.

Time: every stamp is the host's :func:`time.monotonic_ns` when the state was read (the
controller's own time only orders its states).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from types import TracebackType
from typing import Any, Final
from xml.etree import ElementTree

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.chain_ik import ChainIk
from ftcomp.errors import FtcompError, HardwareError, ParameterError, UnreachablePoseError
from ftcomp.extras import install_hint
from ftcomp.hardware.pacing import LatenessOfPacer, RateLimiter
from ftcomp.hardware.protocols import ClockName, PoseSample, Robot
from ftcomp.hardware.registry import Uri

__all__ = ["FrankaRobot", "Load", "ModelChain", "fault_line", "open_robot", "set_load"]

#: A velocity motion holds its twist this many control periods after it is reached, then the
#: arm comes to rest (within its limits) unless the next period's command replaced it.
_HOLD_PERIODS: Final = 5
#: End effector speeds below which the arm counts as at rest [m/s, rad/s], and for how long [s].
#: The end effector's, not the joints': a redundant arm's elbow may move with the end effector
#: still (franky-sim's seventh joint reads a steady +-77 mrad/s of chatter at rest), and the
#: sensor on the end effector is what must be still.
_STILL_M_S: Final = 1e-3
_STILL_RAD_S: Final = 5e-3
_STILL_FOR_S: Final = 0.1
#: How far from its target a finished blocking move may leave the end effector [m, rad].
_ARRIVED_M: Final = 1e-3
_ARRIVED_RAD: Final = math.radians(0.5)
#: The inverse kinematics' tolerances for a joint move's target [m, rad]: far inside the
#: arrival check's (the arm's tracking, not the solution, is what that checks).
_IK_M: Final = 1e-5
_IK_RAD: Final = math.radians(0.01)
#: The longest wait for the arm to decelerate when stopping [s] (it takes a few hundred ms from
#: a compliant loop's speeds within the arm's limits).
_STOP_WAIT_S: Final = 2.0
#: The largest payload set_load accepts [kg] (an FR3 carries 3 kg).
_MAX_LOAD_KG: Final = 20.0


def _franky() -> Any:
    try:
        import franky
    except ImportError:
        raise ParameterError(f"franka:// needs franky-control: {install_hint('franka')}") from None
    return franky


def fault_line(exc: BaseException, errors: str = "") -> str:
    """One line for a franky/libfranka exception: what happened, as libfranka names it.

    Args:
        exc: the exception franky raised (its type names the kind: ``ControlException`` for a
            reflex or an aborted motion, ``NetworkException`` for a lost connection,
            ``CommandException`` for a refused command, ``RealtimeException``).
        errors: the arm's active errors as libfranka lists them (``RobotState.last_motion_errors``),
            or ``""`` when unknown.
    """
    kind = type(exc).__name__
    text = " ".join(str(exc).split()) or kind
    if kind == "NetworkException":
        return f"lost the connection to the arm ({text})"
    if kind == "ControlException":
        why = f"; errors {errors}" if errors and errors != "[]" and errors not in text else ""
        hint = (
            " (the host missed libfranka's 1 kHz deadline: a real-time kernel, no other load)"
            if "communication_constraints_violation" in text + errors
            else ""
        )
        return f"the arm stopped: {text}{why}{hint}"
    if kind == "CommandException":
        return f"the arm refused the command ({text})"
    return f"franky {kind}: {text}"


def _revolute_limits(urdf: str) -> tuple[tuple[str, ...], NDArray[np.float64]]:
    """The revolute joints' names and ``[lower, upper]`` [rad] (n, 2) of a URDF's text, in
    its order (an arm's joints; a hand's fingers are prismatic)."""
    try:
        root = ElementTree.fromstring(urdf)
    except ElementTree.ParseError as exc:
        raise HardwareError(f"the arm's URDF is not XML ({exc})") from None
    names, limits = [], []
    for joint in root.iter("joint"):
        limit = joint.find("limit")
        if joint.get("type") != "revolute" or limit is None:
            continue
        names.append(str(joint.get("name")))
        limits.append((float(limit.get("lower", "nan")), float(limit.get("upper", "nan"))))
    if len(names) != 7 or not np.isfinite(limits).all():
        raise HardwareError(
            f"the arm's URDF names {len(names)} revolute joints with limits, not a Franka's 7"
        )
    return tuple(names), np.array(limits)


class ModelChain:
    """A Franka's kinematics as a :class:`~ftcomp.chain_ik.Chain`: the end effector's pose and
    zero Jacobian from libfranka's model of the arm (its own, as ``O_T_EE`` is computed), the
    joint ranges from the URDF the arm serves.

    Args:
        franky: the franky module.
        model: ``franky.Robot.model``.
        urdf: ``franky.Robot.model_urdf``.
        F_T_EE: the end effector on the flange (``RobotState.F_T_EE``).
        EE_T_K: the stiffness frame on it (``RobotState.EE_T_K``).
    """

    joint_revolute: tuple[bool, ...] = (True,) * 7

    def __init__(self, franky: Any, model: Any, urdf: str, F_T_EE: Any, EE_T_K: Any) -> None:
        self.joint_names, self.joint_limits = _revolute_limits(urdf)
        self.joint_limits.setflags(write=False)
        self._model = model
        self._frame = franky.Frame.EndEffector
        self._F_T_EE, self._EE_T_K = F_T_EE, EE_T_K

    def pose_and_jacobian(
        self, q: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        T = self._model.pose(self._frame, q, self._F_T_EE, self._EE_T_K).matrix
        J = self._model.zero_jacobian(self._frame, q, self._F_T_EE, self._EE_T_K)
        return np.asarray(T, dtype=float), np.asarray(J, dtype=float)


class FrankaRobot(LatenessOfPacer):
    """A Franka arm through franky (see the module docstring for the URI and the frames).
    Capabilities: :class:`~ftcomp.hardware.protocols.ReportsLateness`,
    :class:`~ftcomp.hardware.protocols.ChecksReachability`,
    :class:`~ftcomp.hardware.protocols.MovesInJointSpace`.

    Args:
        uri: the parsed URI (for messages).
        frequency_hz: the control loop's rate [Hz].
        dynamics: blocking moves' share of the arm's limits, in (0, 1].
        realtime: ``"enforce"`` or ``"ignore"`` (libfranka's real-time check).
        recover: clear the arm's errors when connecting.
        collision_torque_nm: libfranka's joint torque collision threshold [N*m].
        collision_force_n: its Cartesian force collision threshold [N].
    """

    clock_name: ClockName = "monotonic"
    pose_known = True

    def __init__(
        self,
        uri: Uri,
        *,
        frequency_hz: float,
        dynamics: float,
        realtime: str,
        recover: bool,
        collision_torque_nm: float,
        collision_force_n: float,
    ) -> None:
        self.uri = uri
        self.host = uri.host
        self.dynamics = dynamics
        self.realtime = realtime
        self.recover = recover
        self.collision_torque_nm = collision_torque_nm
        self.collision_force_n = collision_force_n
        self.pacer = RateLimiter(1.0 / frequency_hz, name=type(self).__name__, log_overruns=False)
        self.arm: Any = None
        self._franky: Any = None
        self._moving = False
        self._hold: Any = None
        self._chain_ik: ChainIk | None = None

    # ----------------------------------------------------------------- lifecycle
    @property
    def control_period_s(self) -> float:
        """The control period [s] (1 / ``frequency_hz``)."""
        return self.pacer.period_s

    def __enter__(self) -> FrankaRobot:
        """Connect to the arm's FCI (and clear its errors if ``?recover=1``).

        Raises:
            HardwareError: the arm cannot be reached, the kernel has no real-time scheduling
                (with ``realtime=enforce``), or the arm is in an error state not recovered.
        """
        franky = self._franky = _franky()
        config = (
            franky.RealtimeConfig.Enforce
            if self.realtime == "enforce"
            else franky.RealtimeConfig.Ignore
        )
        try:
            self.arm = franky.Robot(
                self.host,
                relative_dynamics_factor=1.0,
                default_torque_threshold=self.collision_torque_nm,
                default_force_threshold=self.collision_force_n,
                realtime_config=config,
            )
        except Exception as exc:  # franky's exceptions derive from Exception only
            if type(exc).__name__ == "RealtimeException":
                raise HardwareError(
                    f"{self.uri.text!r}: libfranka needs a real-time kernel ({exc}); on a test "
                    "host only, add ?realtime=ignore"
                ) from None
            raise HardwareError(
                f"{self.uri.text!r}: cannot connect to the arm's FCI (FCI activated in Desk, "
                f"brakes open, the address reachable?): {' '.join(str(exc).split())}"
            ) from None
        self._hold = franky.Duration(max(1, round(_HOLD_PERIODS * self.control_period_s * 1e3)))
        if self.recover:
            self._call(self.arm.recover_from_errors)
        state = self._call(lambda: self.arm.state)
        errors = str(state.current_errors)
        if state.robot_mode == franky.RobotMode.Reflex or errors not in ("", "[]"):
            raise HardwareError(
                f"{self.uri.text!r}: the arm is in an error state ({state.robot_mode.name}, "
                f"errors {errors}): clear it in Desk or connect with ?recover=1"
            )
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Stop motion, then drop the connection (franky closes it)."""
        try:
            self.stop()
        finally:
            self.arm = None

    def _call(self, call: Any) -> Any:
        """``call()``, a franky exception turned into one line (:func:`fault_line`)."""
        try:
            return call()
        except Exception as exc:
            if isinstance(exc, FtcompError):
                raise
            self._moving = False
            raise HardwareError(f"{self.uri.text!r}: {fault_line(exc, self._errors())}") from None

    def _errors(self) -> str:
        """The arm's last motion errors as libfranka lists them, or ``""`` when unreadable."""
        try:
            return str(self.arm.state.last_motion_errors)
        except Exception:  # the connection may be gone: the exception's text says why
            return ""

    # ----------------------------------------------------------------- state
    def now_ns(self) -> int:
        """The host's monotonic clock [ns]."""
        return time.monotonic_ns()

    def _connected(self) -> Any:
        if self.arm is None:
            raise HardwareError(f"{self.uri.text!r}: not connected (use the robot in a with block)")
        return self.arm

    def check(self) -> None:
        """Raise if the running motion ended on an error (a reflex, a lost connection).

        Raises:
            HardwareError: naming libfranka's error.
        """
        arm = self._connected()
        # poll_motion raises the motion's error; it returns True once no motion runs (franky
        # 2.0: True when idle and after a motion's end, False while one runs).
        if self._moving and self._call(arm.poll_motion):
            self._moving = False  # its hold ran out: the arm came to rest

    def pose(self) -> PoseSample:
        """The end effector's pose in the base frame (``O_T_EE``), stamped on the host's
        clock when read: while a motion runs, the control loop's newest state; else a state
        read now (libfranka's ``readOnce``: a silent arm raises within its 1 s time-out)."""
        self.check()
        arm = self.arm
        if self._moving:
            T = self._call(lambda: arm.current_pose.end_effector_pose.matrix)
        else:
            T = self._call(lambda: arm.state.O_T_EE.matrix)
        T = np.array(T, dtype=float)
        return PoseSample.owning(time.monotonic_ns(), T[:3, 3].copy(), T[:3, :3].copy())

    def joint_positions_rad(self) -> NDArray[np.float64]:
        """The joints' measured positions [rad], (7,)."""
        self.check()
        return np.array(self._call(lambda: self.arm.current_joint_positions), dtype=float)

    def end_effector_speed(self) -> tuple[float, float]:
        """The end effector's speed now: linear [m/s] and angular [rad/s] (franky's estimate
        of its twist from the joints' state)."""
        self.check()
        twist = self._call(lambda: self.arm.current_cartesian_velocity.end_effector_twist)
        return float(np.linalg.norm(twist.linear)), float(np.linalg.norm(twist.angular))

    # ----------------------------------------------------------------- motion
    def move_pose(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64], duration_s: float
    ) -> None:
        """Blocking Cartesian move of the end effector to a pose (base frame).

        franky plans it time-optimal within the arm's limits scaled by ``dynamics``, so
        ``duration_s`` is not used: the URI's ``dynamics`` sets the pace.

        Raises:
            HardwareError: the arm refused or aborted the move (a pose it cannot reach, a
                singularity, a reflex), or it ended away from its target.
        """
        del duration_s
        franky = self._franky
        p = np.asarray(p_base_tcp, dtype=float)
        R = np.asarray(R_base_tcp, dtype=float)
        if p.shape != (3,) or R.shape != (3, 3) or not np.all(np.isfinite(p)):
            raise ParameterError("move_pose needs a finite position (3,) and a rotation (3, 3)")
        self.stop()  # a velocity motion still held: one control signal type at a time
        self.check()
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R, p
        motion = franky.CartesianMotion(
            franky.Affine(T), franky.ReferenceType.Absolute, relative_dynamics_factor=self.dynamics
        )
        self._call(lambda: self._connected().move(motion))
        self._check_arrival(p, R)

    # ----------------------------------------------------------------- joint space
    def _ik(self) -> ChainIk:
        """The inverse kinematics on the arm's own model (made on first use: the URDF comes
        from the arm)."""
        if self._chain_ik is None:
            arm = self._connected()
            state = self._call(lambda: arm.state)
            chain = ModelChain(
                self._franky,
                self._call(lambda: arm.model),
                self._call(lambda: arm.model_urdf),
                state.F_T_EE,
                state.EE_T_K,
            )
            self._chain_ik = ChainIk(chain, position_tol_m=_IK_M, angle_tol_rad=_IK_RAD)
        return self._chain_ik

    def inverse_kinematics(
        self,
        p_base_tcp: NDArray[np.float64],
        R_base_tcp: NDArray[np.float64],
        q_near_rad: NDArray[np.float64],
    ) -> NDArray[np.float64] | None:
        """The joints [rad] putting the end effector at this base-frame pose, found from
        ``q_near_rad`` first (so near it), within the joint ranges the arm's URDF gives; None
        if none is found. On the arm's own kinematics (libfranka's model: ``O_T_EE``)."""
        return self._ik().solve(p_base_tcp, R_base_tcp, q_start=q_near_rad)

    def is_reachable(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64]
    ) -> bool:
        """Whether the end effector can be brought to this pose within the joint ranges
        (ignoring collisions, as every reach check here)."""
        return (
            self.inverse_kinematics(p_base_tcp, R_base_tcp, self.joint_positions_rad()) is not None
        )

    def move_pose_joints(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64], duration_s: float
    ) -> None:
        """Blocking joint move (franky's ``JointMotion``, within the arm's limits scaled by
        ``dynamics``) to the inverse kinematics nearest the joints now.

        Raises:
            UnreachablePoseError: no joints within the ranges reach the pose; not moved.
            HardwareError: the arm refused or aborted the move, or it ended away from the
                target.
        """
        del duration_s
        p = np.asarray(p_base_tcp, dtype=float)
        R = np.asarray(R_base_tcp, dtype=float)
        self.stop()
        q = self.inverse_kinematics(p, R, self.joint_positions_rad())
        if q is None:
            raise UnreachablePoseError(
                f"{self.uri.text!r}: no joints within the arm's ranges reach "
                f"{np.round(p * 1e3, 1).tolist()} mm at that orientation; not moved"
            )
        franky = self._franky
        motion = franky.JointMotion(
            franky.JointState(q.tolist()), relative_dynamics_factor=self.dynamics
        )
        self._call(lambda: self._connected().move(motion))
        self._check_arrival(p, R)

    def _check_arrival(self, p: NDArray[np.float64], R: NDArray[np.float64]) -> None:
        at = self.pose()
        off_m = float(np.linalg.norm(at.p_base_tcp - p))
        off_rad = float(Rotation.from_matrix(R @ at.R_base_tcp.T).magnitude())
        if off_m > _ARRIVED_M or off_rad > _ARRIVED_RAD:
            raise HardwareError(
                f"{self.uri.text!r}: the move ended {off_m * 1e3:.1f} mm and "
                f"{math.degrees(off_rad):.2f} deg from its target"
            )

    def settle(self, max_duration_s: float) -> float:
        """Wait until the end effector is slower than 1 mm/s and 5 mrad/s for 0.1 s; return
        the time taken [s].

        Raises:
            HardwareError: still moving after ``max_duration_s``, or a fault.
        """
        return self.pacer.wait_at_rest(
            self._end_effector_still, _STILL_FOR_S, max_duration_s, repr(self.uri.text)
        )

    def _end_effector_still(self) -> bool:
        linear, angular = self.end_effector_speed()
        return linear < _STILL_M_S and angular < _STILL_RAD_S

    def command_twist(self, twist_base: NDArray[np.float64]) -> None:
        """Hand franky a Cartesian velocity motion holding this end effector twist (base frame)
        for :data:`_HOLD_PERIODS` periods; it replaces the running one. A zero twist while
        nothing moves is not sent.

        Raises:
            ParameterError: not 6 finite numbers.
            HardwareError: the running motion ended on an error (a reflex, a lost connection).
        """
        tw = np.asarray(twist_base, dtype=float)
        if tw.shape != (6,) or not np.all(np.isfinite(tw)):
            raise ParameterError(f"twist_base must be 6 finite numbers, got {twist_base!r}")
        arm = self._connected()
        if not np.any(tw) and not self._moving:
            return
        franky = self._franky
        motion = franky.CartesianVelocityMotion(franky.Twist(tw[:3], tw[3:]), duration=self._hold)
        self.check()  # the running motion's error first: it names the cause
        self._call(lambda: arm.move(motion, asynchronous=True))
        self._moving = True

    def wait_cycle(self) -> None:
        """Wait for the next control period (host clock)."""
        self.pacer.sleep()

    def stop(self) -> None:
        """Bring the arm to rest within its limits (franky's stop motion), waiting at most
        :data:`_STOP_WAIT_S`; if that fails, libfranka's stop. A motion that ended on an error
        has stopped already (the error was raised where it was seen)."""
        if self.arm is None or not self._moving:
            return
        self._moving = False
        arm, franky = self.arm, self._franky
        try:
            arm.move(franky.CartesianVelocityStopMotion(), asynchronous=True)
            if arm.join_motion(_STOP_WAIT_S):
                return
        except Exception:  # the arm stopped by itself (a reflex) or the connection is gone
            return
        try:
            arm.stop()
        except Exception:  # nothing more to do: the connection's end stops it
            return


@dataclass(frozen=True)
class Load:
    """The payload libfranka's model carries (``RobotState.m_load``, ``F_x_Cload``, ``I_load``).

    Attributes:
        mass_kg: its mass [kg].
        cog_flange_m: its centre of gravity in the flange frame [m], (3,).
        inertia_kgm2: its inertia about the centre of gravity, flange axes [kg m^2], (3, 3).
    """

    mass_kg: float
    cog_flange_m: tuple[float, float, float]
    inertia_kgm2: tuple[tuple[float, float, float], ...]


def _load_of(state: Any) -> Load:
    cog = tuple(float(v) for v in np.ravel(state.F_x_Cload))
    inertia = np.asarray(state.I_load, dtype=float).reshape(3, 3)
    return Load(
        float(state.m_load),
        (cog[0], cog[1], cog[2]),
        tuple((float(r[0]), float(r[1]), float(r[2])) for r in inertia),
    )


def set_load(
    uri: Uri,
    mass_kg: float,
    cog_tcp_m: NDArray[np.float64],
    inertia_tcp_kgm2: NDArray[np.float64] | None = None,
) -> tuple[Load, Load]:
    """Write the payload to the arm (franky's ``set_load``); ``(before, after)`` as the robot
    state reports them.

    The centre of gravity and the inertia are given in the end effector frame (the pose's
    frame, ``O_T_EE``) and written in the flange frame, as ``set_load`` takes them, through
    the end effector's offset the arm reports (``F_T_EE``).

    Args:
        uri: the arm (``franka://HOST``; its ``realtime`` option is used).
        mass_kg: the payload's mass [kg], in [0, 20].
        cog_tcp_m: its centre of gravity in the end effector frame [m], (3,), each within 1 m.
        inertia_tcp_kgm2: its inertia about the centre of gravity, end effector axes [kg m^2],
            (3, 3), or None: zero (a point mass).

    Raises:
        ParameterError: a value out of range, or franky missing.
        HardwareError: the arm cannot be reached or refused the setting.
    """
    cog = np.asarray(cog_tcp_m, dtype=float)
    if not (math.isfinite(mass_kg) and 0.0 <= mass_kg <= _MAX_LOAD_KG):
        raise ParameterError(f"mass_kg must be in [0, {_MAX_LOAD_KG:g}] kg, got {mass_kg:g}")
    if cog.shape != (3,) or not np.all(np.isfinite(cog)) or np.any(np.abs(cog) > 1.0):
        raise ParameterError(f"cog_tcp_m must be 3 finite numbers within 1 m, got {cog_tcp_m!r}")
    inertia = np.zeros((3, 3)) if inertia_tcp_kgm2 is None else np.asarray(inertia_tcp_kgm2, float)
    if inertia.shape != (3, 3) or not np.all(np.isfinite(inertia)):
        raise ParameterError("inertia_tcp_kgm2 must be a finite 3x3 matrix")
    robot = open_robot(uri)
    assert isinstance(robot, FrankaRobot)
    with robot:
        arm = robot.arm
        state = robot._call(lambda: arm.state)
        before = _load_of(state)
        F_T_EE = np.asarray(state.F_T_EE.matrix, dtype=float)
        R_flange_tcp = F_T_EE[:3, :3]
        cog_flange = F_T_EE[:3, 3] + R_flange_tcp @ cog
        inertia_flange = R_flange_tcp @ inertia @ R_flange_tcp.T
        robot._call(
            lambda: arm.set_load(
                float(mass_kg), cog_flange.tolist(), inertia_flange.flatten(order="F").tolist()
            )
        )
        deadline = time.monotonic() + 1.0  # states already on their way carry the old load
        while True:
            after = _load_of(robot._call(lambda: arm.state))
            done = abs(after.mass_kg - mass_kg) < 1e-6 and np.allclose(
                after.cog_flange_m, cog_flange, atol=1e-6
            )
            if done or time.monotonic() > deadline:
                break
    return before, after


def open_robot(uri: Uri) -> Robot:
    """A Franka arm from its URI (connects when entered)."""
    if not uri.host:
        raise ParameterError(f"{uri.text!r}: give the arm's FCI address, e.g. franka://172.16.0.2")
    if uri.port is not None or uri.path not in ("", "/"):
        raise ParameterError(f"{uri.text!r}: franka:// takes a host only (FCI is on port 1337)")
    options = uri.reader()
    frequency = options.positive("frequency_hz", 200.0)
    dynamics = options.positive("dynamics", 0.1)
    realtime = options.text("realtime", "enforce", ("enforce", "ignore"))
    recover = options.flag("recover", False)
    torque = options.positive("collision_torque_nm", 20.0)
    force = options.positive("collision_force_n", 30.0)
    options.done()
    if not 1.0 <= frequency <= 1000.0:
        raise ParameterError(f"{uri.text!r}: frequency_hz must be in [1, 1000], got {frequency:g}")
    if dynamics > 1.0:
        raise ParameterError(f"{uri.text!r}: dynamics must be in (0, 1], got {dynamics:g}")
    return FrankaRobot(
        uri,
        frequency_hz=frequency,
        dynamics=dynamics,
        realtime=realtime,
        recover=recover,
        collision_torque_nm=torque,
        collision_force_n=force,
    )
