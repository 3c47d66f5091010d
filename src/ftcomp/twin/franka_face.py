"""The twin's Franka face: the libfranka network protocol over the cell's FR3.

Why it is built as it is: the libfranka protocol (a TCP command channel on port 1337, the
robot's state and the client's commands as UDP datagrams every millisecond, both binary and
versioned) is served by franky-sim's protocol server (``franky_sim.FrankaRobotServer``, Tim
Schneider and Baris Yazici, Apache-2.0), which franky-control's and pylibfranka's libfranka
already drive; the arm under it is this cell's Franka Research 3
(:func:`ftcomp.sim.arm.fr3_arm`, Franka's published kinematics and link masses), with the
tool, the load, the surfaces and the wrist sensor every face gets. franky-sim's own MuJoCo arm
would have needed a second simulator beside the cell and a sensor reading another model's
state; its protocol over our cell keeps one physics. franky-sim is then the Franka
protocol's one implementation here (its public classes: ``BaseRobot``, the arm it serves, and
``FrankaRobotServer``), and the franka:// backend's tests also drive franky-sim's own
simulator, so ours is not the only arm it meets.

What the arm does with a command: franky-sim's server turns each motion generator's command
into joint targets (a joint position as given; a joint velocity integrated; a Cartesian pose
by its inverse kinematics and a Cartesian velocity by its Jacobian's pseudo-inverse, both on
its Pinocchio model of the same FR3, whose flange pose agrees with the cell's to 1e-15 m), and
the cell's joint servos follow them (:meth:`~ftcomp.sim.cell.SimCell.command_joints`). The
end effector (libfranka's ``F_T_EE``, Desk's end effector) is the wrist sensor's frame where
the cell's mount puts it, as a UR face's TCP is: ``O_T_EE`` is the sensor's pose.

What this face adds to franky-sim's server, which simulates neither: **reflexes** and the
arm's **error state**. A contact force (its mean over 5 ms) above the smallest of the
Cartesian force collision thresholds the client set (``setCollisionBehavior``'s upper nominal
x, y, z; 20 N until set) is a ``cartesian_reflex``: the motion stops, its Move command ends
``kReflexAborted`` with the reason in the state's ``reflex_reason`` (libfranka's
``last_motion_errors``), the robot mode is ``kReflex`` and the errors stay (a new motion is
aborted the same way) until the client asks for automatic error recovery. The control
command success rate in the state is the share of the last 100 periods that brought a new
command during a motion.

What it does not: torque control (a motion with an external controller is refused, libfranka's
``kCommandNotPossibleRejected``), the joint-torque collision thresholds, the Franka Hand, and
timing (the cell's loop paces the state at 1 kHz on the host's clock; a client late by a
period is not punished: ``communication_constraints_violation`` comes only from its fault).

Faults (declared in :mod:`ftcomp.hardware.devices`): ``reflex`` (a ``cartesian_reflex`` now,
as a collision would), ``communication-violation`` (the robot's
``communication_constraints_violation`` reflex), ``user-stop`` (the external enabling device's
stop: the motion ends ``kEmergencyAborted``, mode ``kUserStopped``) and ``network-loss`` (no
more state datagrams; the connection stays open).
"""

from __future__ import annotations

import collections
import contextlib
import sys
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.errors import ParameterError
from ftcomp.frames import matrix_from_rotvec
from ftcomp.sim.cell import SimCell

__all__ = ["CARTESIAN_REFLEX", "FrankaFace", "server_with_errors"]

_PERIOD_S: Final = 0.001
_PORT: Final = 1337
#: libfranka's error indices (research_interface::robot::Error), of the 41 the state carries.
CARTESIAN_REFLEX: Final = 7
_COMMUNICATION_CONSTRAINTS_VIOLATION: Final = 25
_ERROR_COUNT: Final = 41
#: The Cartesian force collision threshold until the client sets one [N] (libfranka's examples'
#: setDefaultBehavior: 20 N).
_DEFAULT_FORCE_THRESHOLD_N: Final = 20.0
#: The reflex compares the mean contact force of this many periods (5 ms) with the threshold:
#: Franka's external wrench estimate is filtered, and the simulated contact's force has
#: one-period impulses (25 N as a pressed load leaves the book) no arm would react to.
_CONTACT_PERIODS: Final = 5
#: The control command success rate is over this many periods.
_SUCCESS_WINDOW: Final = 100


def _franky_sim() -> Any:
    try:
        import franky_sim
        from franky_sim import base_simulator, franka_robot_protocol
    except ImportError:
        raise ParameterError(
            "the twin's Franka face needs franky-sim (its libfranka protocol server): "
            "pip install 'ftcomp[franka-twin]'",
            field="robot",
        ) from None
    return franky_sim, base_simulator, franka_robot_protocol


class FrankaFace:
    """A Franka Research 3's controller over the cell's arm (module docstring; a
    :class:`~ftcomp.twin.faces.RobotFace`).

    Args:
        host: the arm's loopback address (its FCI address).
        cell: the cell, its arm an FR3; its sensor frame is the end effector.
        realtime: unused (the server runs in the cell's loop).
        seed: unused (nothing random).

    Raises:
        ParameterError: port 1337 on ``host`` cannot be bound, or franky-sim is not installed.
    """

    period_s: float = _PERIOD_S

    def __init__(self, host: str, cell: SimCell, *, realtime: bool, seed: int) -> None:
        del realtime, seed
        franky_sim, base, protocol = _franky_sim()
        if cell.n_joints != 7:
            raise ParameterError(
                f"the Franka face serves a seven-joint arm; the cell's has {cell.n_joints}",
                field="robot",
            )
        self.host = host
        self.cell = cell
        R_flange_sensor = matrix_from_rotvec(cell.config.rotvec_flange_sensor_rad)
        p_flange_sensor = np.array(cell.config.p_flange_sensor_m, dtype=float)
        # Desk's end effector as a user who weighed the tool would set it: the tool below the
        # sensor (the cell's truth), its centre of gravity in the flange frame.
        tool = cell.true_gravity_model()
        self.arm = _cell_arm(franky_sim, base)(
            cell,
            franky_sim.RobotParameters(
                ee_mass=tool.weight_N / float(np.linalg.norm(cell.model.opt.gravity)),
                ee_com=tuple(
                    (p_flange_sensor + R_flange_sensor @ tool.center_of_gravity_m).tolist()
                ),
                ee_tcp_xyz=tuple(p_flange_sensor.tolist()),
                # Pinocchio's rpyToMatrix(r, p, y) is Rz(y) Ry(p) Rx(r): scipy's extrinsic xyz.
                ee_tcp_rpy=tuple(Rotation.from_matrix(R_flange_sensor).as_euler("xyz").tolist()),
                ee_inertia=(0.0,) * 9,
            ),
            base.InnerRobotState,
        )
        self.server = _server(franky_sim, protocol)(self.arm, host)
        try:
            self.server.init()
        except OSError as exc:
            raise ParameterError(
                f"robot: cannot bind {host}:{_PORT} for the Franka face: {exc}", field="robot"
            ) from None
        self.silent = False
        self.states_sent = 0
        #: The contact force of the last periods [N]: the reflex looks at their mean.
        self.contact_N: collections.deque[float] = collections.deque(maxlen=_CONTACT_PERIODS)

    # ------------------------------------------------------------------ RobotFace
    def uri(self) -> str:
        # libfranka's real-time check is about the client's host, the twin's: a host that
        # simulates the arm is not a real-time control host (docs/hardware.md).
        return f"franka://{self.host}?realtime=ignore"

    def commanded(self) -> bool:
        return self.server.commanded

    def cycle(self, contact_force_N: float) -> None:
        server = self.server
        self.contact_N.append(contact_force_N)
        if sum(self.contact_N) / len(self.contact_N) > server.force_threshold_N:
            server.reflex(CARTESIAN_REFLEX)
        server.process_commands()

    def publish(self, wrench_sensor: NDArray[np.float64]) -> None:
        del wrench_sensor  # a Franka reports no wrist sensor's reading
        self.arm.finish_step()
        if self.silent or not self.server.udp_connected:
            return
        self.server.send_state()
        self.states_sent += 1

    def inject(self, fault: str) -> None:
        if fault == "network-loss":
            self.silent = True
        elif fault == "reflex":
            self.server.reflex(CARTESIAN_REFLEX)
        elif fault == "communication-violation":
            self.server.reflex(_COMMUNICATION_CONSTRAINTS_VIOLATION)
        elif fault == "user-stop":
            self.server.user_stop()

    def safety(self) -> str:
        return self.server.mode_name()

    def served(self) -> str:
        return f"{self.states_sent} libfranka states"

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self.server.reset_state()
        with contextlib.suppress(OSError):
            self.server.cleanup()


def _cell_arm(franky_sim: Any, base: Any) -> Any:
    """franky-sim's ``BaseRobot`` over the cell's arm: its joint commands become the cell's
    servo targets (made here: franky-sim is imported only when a Franka face is served)."""

    class CellArm(franky_sim.BaseRobot):
        def __init__(self, cell: SimCell, parameters: Any, state_type: Any) -> None:
            self.cell = cell
            self.state_type = state_type
            self.rate = 1.0 / cell.control_period_s
            self.last_target: NDArray[np.float64] | None = None
            #: No motion runs (the server's idle mode): hold (set by the server).
            self.holding = True
            super().__init__(parameters, has_gripper=False)

        def hold(self) -> None:
            """No motion runs (the server is idle): hold the last desired joints."""
            self.last_target = None
            self.holding = True

        def _get_state(self) -> Any:
            cell = self.cell
            d = cell.data
            n = cell.n_joints
            # The joints' torques: the servo's and the gravity feed-forward it applies.
            tau = d.qfrc_actuator[:n] + d.qfrc_applied[:n]
            return self.state_type(
                tuple(d.qpos[:n].tolist()), tuple(d.qvel[:n].tolist()), tuple(tau.tolist())
            )

        def _joint_position_control(self, target_q: NDArray[np.float64]) -> None:
            # The velocity feed-forward is the targets' rate within a stream of position
            # targets; a first target (a hold where the arm stands, a new motion) has none:
            # the step from the last command is a new set point, not a speed.
            if self.holding:
                # Idle: the arm holds its last desired position, as Franka's controller holds
                # q_d (franky-sim's hold is the measured joints, which in contact differ from
                # the command by the servo's error: a step of the set point, a jolt).
                self.cell.command_joints(self.cell.q_command_rad, np.zeros(self.cell.n_joints))
                self._commanded()
                return
            q = np.asarray(target_q, dtype=float)
            last = self.last_target
            qd = np.zeros(q.shape) if last is None else (q - last) * self.rate
            self.cell.command_joints(q, qd)
            self.last_target = q
            self._commanded()

        def _joint_velocity_control(self, target_dq: NDArray[np.float64]) -> None:
            cell = self.cell
            dq = np.asarray(target_dq, dtype=float)
            cell.command_joints(cell.q_command_rad + dq * cell.control_period_s, dq)
            self.last_target = None
            self._commanded()

        def _commanded(self) -> None:
            """franky-sim's bookkeeping of the commanded torque (its state's ``tau_J_d``): the
            servo's torques, through its torque interface, whose output goes nowhere."""
            self.torque_control(np.asarray(self._get_state().tau_j))

        def _torque_control(self, torques: NDArray[np.float64]) -> None:
            del torques  # the cell's arm takes joint targets, not torques (module docstring)

        def set_hand_goal(self, width: float, max_velocity: float, max_force: float) -> None:
            del width, max_velocity, max_force  # no hand

        def _get_hand_width(self) -> float:
            return 0.0

        def finish_step(self) -> None:
            """The period's physics done: franky-sim's derived state (its finite differences,
            the desired values) advances, as its simulator's step does."""
            self._post_step()

    return CellArm


def server_with_errors(franky_sim: Any, protocol: Any) -> Any:
    """franky-sim's ``FrankaRobotServer`` with the arm's error state (module docstring): the
    reflexes and the user stop as libfranka's protocol reports them, error recovery, the
    Cartesian force thresholds kept, the control command success rate. Over any franky-sim
    ``BaseRobot``: the twin's cell arm (:class:`FrankaFace`) and franky-sim's own MuJoCo FR3
    (``tests/standins/franky_sim_faults.py``). ``franky_sim`` and its ``protocol`` module are
    passed in (imported only when a Franka is served)."""
    MoveStatus = protocol.MoveStatus
    RobotCommand = protocol.RobotCommand
    RobotMode = protocol.RobotMode

    class CollisionBehavior(protocol.SetCollisionBehaviorCommand):
        """setCollisionBehavior, its Cartesian force thresholds kept (franky-sim only
        acknowledges it)."""

        def handle(self, server: Any) -> None:
            server.force_threshold_N = float(min(self.upper_force_thresholds_nominal[:3]))
            super().handle(server)

    class ErrorRecovery(protocol.AutomaticErrorRecoveryCommand):
        """automaticErrorRecovery: the errors cleared, then acknowledged."""

        def handle(self, server: Any) -> None:
            server.clear_errors()
            super().handle(server)

    class ServerWithErrors(franky_sim.FrankaRobotServer):
        def __init__(self, arm: Any, host: str) -> None:
            super().__init__(arm, [host])
            # franky-sim 1.0's table of command handlers (the pinned range keeps its name).
            commands = self._FrankaServer__command_class_map
            commands[RobotCommand.kSetCollisionBehavior] = CollisionBehavior
            commands[RobotCommand.kAutomaticErrorRecovery] = ErrorRecovery
            self.force_threshold_N = _DEFAULT_FORCE_THRESHOLD_N
            self.errors = [False] * _ERROR_COUNT
            self.reflex_reason = [False] * _ERROR_COUNT
            self.mode: Any = None  # RobotMode.kReflex / kUserStopped, or None: no error
            #: The Move response owed to a motion started while in error, its status.
            self.abort_owed: Any = None
            self.new_commands: collections.deque[bool] = collections.deque(maxlen=_SUCCESS_WINDOW)
            self.new_command = False
            #: Whether a client started a motion (the twin's fault clock starts then).
            self.commanded = False

        def _pre_process_commands(self) -> None:
            super()._pre_process_commands()
            if self.current_motion_id:
                self.new_commands.append(self.new_command)
            self.new_command = False

        def _handle_udp_command(self, command_data: bytes) -> None:
            self.new_command = True
            super()._handle_udp_command(command_data)

        def _post_process_commands(self) -> None:
            if self.abort_owed is not None and self.current_motion_id:
                self._abort(self.abort_owed)
            super()._post_process_commands()

        def start_motion(self, controller_mode: Any, generator_mode: Any, motion_id: int) -> None:
            super().start_motion(controller_mode, generator_mode, motion_id)
            self.commanded = True
            self.new_commands.clear()
            self.abort_owed = self.refusal(controller_mode)

        def refusal(self, controller_mode: Any) -> Any:
            """The Move status that ends a motion as soon as it started (None: it runs): in
            error, the error's."""
            del controller_mode
            if self.mode is None:
                return None
            if self.mode == RobotMode.kUserStopped:
                return MoveStatus.kEmergencyAborted
            return MoveStatus.kReflexAborted

        def _abort(self, status: Any) -> None:
            motion_id = self.current_motion_id
            self.stop_motion(send_preemption_signal=False)
            self.reset_current_motion_id()
            self.abort_owed = None
            if motion_id and self.tcp_connected:
                protocol.BaseCommand.send_response(
                    self._tcp_socket, RobotCommand.kMove, motion_id, status
                )

        def reflex(self, error: int) -> None:
            """A reflex for libfranka's error ``error``: the motion aborted, the arm in error."""
            if self.mode is not None:
                return
            self.errors[error] = True
            self.reflex_reason[error] = True
            self.mode = RobotMode.kReflex
            self._abort(MoveStatus.kReflexAborted)
            self.stop_here()

        def user_stop(self) -> None:
            """The user stop: the motion aborted, the arm stopped until recovered."""
            self.mode = RobotMode.kUserStopped
            self._abort(MoveStatus.kEmergencyAborted)
            self.stop_here()

        def stop_here(self) -> None:
            """After a stop: where the arm holds (franky-sim's own stop: its desired joints)."""

        def clear_errors(self) -> None:
            self.errors = [False] * _ERROR_COUNT
            self.mode = None

        def mode_name(self) -> str:
            """``normal``, ``reflex`` or ``user_stopped`` (the contact log's safety column)."""
            if self.mode is None:
                return "normal"
            return "reflex" if self.mode == RobotMode.kReflex else "user_stopped"

        @property
        def robot_state(self) -> Any:
            state = super().robot_state
            rate = sum(self.new_commands) / len(self.new_commands) if self.new_commands else 1.0
            changes: dict[str, Any] = {
                "errors": tuple(self.errors),
                "reflex_reason": tuple(self.reflex_reason),
                "control_command_success_rate": rate,
            }
            if self.mode is not None:
                changes["robot_mode"] = self.mode
            return state.replace(**changes)

    return ServerWithErrors


def _server(franky_sim: Any, protocol: Any) -> Any:
    """:func:`server_with_errors` over the cell's arm: the arm holds its commanded joints
    when idle, holds where it is after a stop, and a torque-controlled motion is refused."""
    MoveStatus = protocol.MoveStatus
    ControllerMode = protocol.MoveCommandControllerMode

    class Server(server_with_errors(franky_sim, protocol)):  # type: ignore[misc]
        def _reset_state(self) -> None:  # a client connected or left: the arm holds
            super()._reset_state()
            self.robot.hold()

        def stop_motion(self, send_preemption_signal: bool = True) -> None:
            super().stop_motion(send_preemption_signal)
            self.robot.hold()

        def start_motion(self, controller_mode: Any, generator_mode: Any, motion_id: int) -> None:
            self.robot.last_target = None
            self.robot.holding = False
            super().start_motion(controller_mode, generator_mode, motion_id)

        def refusal(self, controller_mode: Any) -> Any:
            in_error = super().refusal(controller_mode)
            if in_error is None and controller_mode == ControllerMode.kExternalController:
                # Torques are not simulated: refused, never accepted and ignored.
                print(
                    "twin: a torque-controlled motion (libfranka's external controller) is "
                    "refused: the twin's FR3 takes joint and Cartesian motion generators only",
                    file=sys.stderr,
                )
                return MoveStatus.kCommandNotPossibleRejected
            return in_error

        def stop_here(self) -> None:
            """A stop holds the arm where it is (the measured joints), not where its motion
            was heading: in a stiff contact the command runs ahead of the arm, and holding it
            would press on."""
            cell = self.robot.cell
            cell.command_joints(cell.q_rad, np.zeros(cell.n_joints))

    return Server
