"""The ``ur://`` backend: a Universal Robots arm (and its built-in F/T sensor) through ``ur_rtde``.

URI::

    ur://HOST                     the controller (RTDE on port 30004)
        ?frequency_hz=500         RTDE and control rate (default: 500 on e-Series, 125 on CB3)
        &max_speed_mm_s=100       speed limit of blocking moves (moveL) [mm/s]
        &max_accel_mm_s2=500      their acceleration [mm/s^2], and speedL's
        &max_joint_speed_deg_s=60 speed limit of joint moves (moveJ), leading joint [deg/s]
        &max_joint_accel_deg_s2=80  their acceleration [deg/s^2]
        &command=speedl|servol    how a twist is sent: speedL, or servoL to the integrated pose
        &timeout_s=0.5            the controller's data older than this is a lost connection [s]
        &connect_timeout_s=2      longest wait for the controller to answer [s]

    --sensor ur://HOST?wrench=raw|tcp&sign=1|-1     the built-in sensor (:mod:`.ur_sensor`)
             &tcp_offset_mm=X,Y,Z&tcp_rotvec_rad=RX,RY,RZ  the TCP offset (wrench=tcp, e-Series)

Frames and units, converted once here: the controller reports the TCP pose as ``[x, y, z, rx,
ry, rz]`` in the base frame (metres, rotation vector): ``p_base_tcp`` and
``R_base_tcp = Rotation.from_rotvec(r)``. Twists are sent as base-frame TCP twists, as speedL
takes them. The built-in sensor gives ``wrench=raw`` (default): ``ft_raw_wrench`` (PolyScope 5.9
or later), the raw, payload-uncompensated reading in the tool flange frame: with a TCP offset
configured on the controller, give ``--mount`` the flange frame seen from the TCP.
``wrench=tcp``: ``actual_TCP_force``, compensated for the controller's payload setting, in
*base* orientation; on an e-Series (major version 5 or later) it is the wrench about the
*flange* origin (as UR's own ROS drivers read it), on a CB3 about the TCP. It is converted here
into the TCP frame about the TCP origin, with the controller's TCP offset given in the URI on an
e-Series (:func:`ftcomp.hardware.ur_sensor.tcp_wrench_from_flange`), so the sensor frame is the
TCP frame (identity mount). ``sign=-1`` flips
the reading, for a controller whose convention is the force on the tool rather than by it:
check with a hanging tool that ``fz`` is +weight when the flange points down.

Time: every stamp is the host's :func:`time.monotonic_ns` when the value was read (the
controller's own ``timestamp`` only detects a stalled stream). The control interface (which
uploads a URScript program that takes over the arm) is opened only for the first motion
command, so recording by hand (free-drive) and streaming never move the robot.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from types import TracebackType
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.errors import HardwareError, ParameterError, UnreachablePoseError
from ftcomp.extras import install_hint
from ftcomp.frames import matrix_from_rotvec, rotvec_from_matrix
from ftcomp.hardware.pacing import LatenessOfPacer, RateLimiter
from ftcomp.hardware.protocols import ClockName, PoseSample, Robot
from ftcomp.hardware.registry import Uri
from ftcomp.hardware.rtde_probe import probe_rtde

__all__ = [
    "RECEIVE_VARIABLES",
    "Payload",
    "URRobot",
    "exit_process_if_abandoned",
    "open_robot",
    "set_payload",
]

#: RTDE outputs the backend reads (``ft_raw_wrench`` is added on PolyScope 5.9 or later).
RECEIVE_VARIABLES = (
    "timestamp",
    "actual_TCP_pose",
    "actual_q",
    "actual_qd",
    "actual_TCP_force",
    "robot_mode",
    "safety_mode",
    "safety_status_bits",
)
#: Joint speed below which the arm counts as at rest [rad/s], and for how long [s].
_STILL_QD_RAD_S = 2e-3
_STILL_FOR_S = 0.1
#: moveL turns the tool at this many rad/s per m/s of its speed parameter (UR's trajectory
#: generator: angular speed = 4 x linear speed, in rad/s).
_MOVEL_RAD_PER_M = 4.0
#: How far from its target a finished moveL may leave the TCP [m, rad]: a controller ends moveL
#: at the target; further, and the arm did not get there (a joint limit, a singularity).
_ARRIVED_M = 1e-3
_ARRIVED_RAD = math.radians(0.5)
#: Joint moves (moveJ) at most this fast and with this acceleration by default, leading joint
#: [rad/s, rad/s^2]: ur_rtde's and PolyScope's defaults for moveJ (the URI's
#: ``max_joint_speed_deg_s`` and ``max_joint_accel_deg_s2``, up to the limits below: a UR5e's
#: joints turn at most 180 deg/s; ur_rtde's moveJ refuses more than 3.14 rad/s, 179.9 deg/s, with
#: a ValueError).
_JOINT_SPEED_RAD_S: Final = 1.05
_JOINT_ACCEL_RAD_S2: Final = 1.4
_MAX_JOINT_SPEED_DEG_S: Final = 179.0
_MAX_JOINT_ACCEL_DEG_S2: Final = 1000.0


#: RTDE ``safety_status_bits``: protective stopped (bit 2), emergency stopped (bit 7), as
#: ur_rtde's ``isProtectiveStopped`` and ``isEmergencyStopped`` test them.
_PROTECTIVE_STOPPED: Final = 1 << 2
_STOPPED_BITS: Final = _PROTECTIVE_STOPPED | 1 << 7


def _pose_list(p: NDArray[np.float64], R: NDArray[np.float64]) -> list[float]:
    return [*map(float, p), *rotvec_from_matrix(R)]


class URRobot(LatenessOfPacer):
    """A UR arm over RTDE (see the module docstring for the URI and the frames). Capabilities:
    :class:`~ftcomp.hardware.protocols.TakesControl`,
    :class:`~ftcomp.hardware.protocols.ReportsLateness`,
    :class:`~ftcomp.hardware.protocols.ChecksReachability`,
    :class:`~ftcomp.hardware.protocols.MovesInJointSpace`.

    Args:
        uri: the parsed URI (for messages).
        frequency_hz: RTDE rate and control rate [Hz]; None: by controller generation.
        max_speed_m_s: speed limit of blocking moves [m/s].
        max_accel_m_s2: their acceleration, and speedL's [m/s^2].
        max_joint_speed_rad_s: speed limit of joint moves, leading joint [rad/s].
        max_joint_accel_rad_s2: their acceleration [rad/s^2].
        command: ``"speedl"`` or ``"servol"``.
        timeout_s: controller data older than this is a lost connection [s].
        connect_timeout_s: the connection check's time limit [s].
    """

    clock_name: ClockName = "monotonic"
    pose_known = True

    def __init__(
        self,
        uri: Uri,
        *,
        frequency_hz: float | None,
        max_speed_m_s: float,
        max_accel_m_s2: float,
        max_joint_speed_rad_s: float = _JOINT_SPEED_RAD_S,
        max_joint_accel_rad_s2: float = _JOINT_ACCEL_RAD_S2,
        command: str,
        timeout_s: float,
        connect_timeout_s: float,
    ) -> None:
        self.uri = uri
        self.host = uri.host
        self.max_speed_m_s = max_speed_m_s
        self.max_accel_m_s2 = max_accel_m_s2
        self.max_joint_speed_rad_s = max_joint_speed_rad_s
        self.max_joint_accel_rad_s2 = max_joint_accel_rad_s2
        self.command = command
        self.timeout_s = timeout_s
        self.connect_timeout_s = connect_timeout_s
        self._frequency_hz = frequency_hz
        self.version: tuple[int, int, int, int] = (0, 0, 0, 0)
        self.variables: tuple[str, ...] = RECEIVE_VARIABLES
        self.receive: Any = None
        self.control: Any = None
        self.pacer = RateLimiter(
            1.0 / frequency_hz if frequency_hz else 0.002, name=type(self).__name__
        )
        # The controller's newest timestamp [s] and when it changed, on the host's clock [s].
        self._last_timestamp_s = -math.inf
        self._fresh_at_s = -math.inf
        self._servo_target: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        self._moving = False
        # The controller's stream went silent or the connection dropped: ur_rtde's blocking
        # commands would wait on it (see stop).
        self._silent = False

    # ----------------------------------------------------------------- lifecycle
    @property
    def control_period_s(self) -> float:
        """The control period [s] (1 / the RTDE frequency)."""
        return self.pacer.period_s

    def __enter__(self) -> URRobot:
        """Check the controller answers, then connect ``ur_rtde``'s receive interface."""
        try:
            import rtde_receive
        except ImportError:
            raise ParameterError(f"ur:// needs ur_rtde: {install_hint('ur')}") from None
        probe = ("timestamp", "actual_TCP_pose")
        self.version = probe_rtde(
            self.host, probe, timeout_s=self.connect_timeout_s, label=repr(self.uri.text)
        )
        major, minor = self.version[0], self.version[1]
        frequency = self._frequency_hz or (500.0 if major > 3 else 125.0)
        self.pacer = RateLimiter(1.0 / frequency, name=type(self).__name__, log_overruns=False)
        raw = major > 5 or (major == 5 and minor >= 9)
        self.variables = RECEIVE_VARIABLES + (("ft_raw_wrench",) if raw else ())
        try:
            self.receive = rtde_receive.RTDEReceiveInterface(
                self.host, frequency, list(self.variables)
            )
        except RuntimeError as exc:
            raise HardwareError(f"{self.uri.text!r}: ur_rtde could not connect: {exc}") from None
        self._last_timestamp_s = self.receive.getTimestamp()
        self._fresh_at_s = time.monotonic()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Stop motion, end the control script, disconnect; with a silent controller (it may
        go silent at any moment) each call is bounded in time (:data:`_EXIT_WAIT_S`).

        Both interfaces disconnect at once (:func:`_disconnect`): ur_rtde 1.6's ``disconnect``
        ends in a fixed 0.5 s sleep, and each destructor disconnects again, so one after the
        other and destroyed, the two cost every command on a UR 1 s here (2 s with explicit
        disconnects before the destructors)."""
        try:
            self.stop()
        finally:
            if not self._silent and not self._stream_alive():
                self._silent = True
            control, receive, self.control, self.receive = self.control, self.receive, None, None
            try:
                if control is not None and not self._silent:
                    control.stopScript()  # with silent data it would wait for the program's end
            finally:
                interfaces = [i for i in (control, receive) if i is not None]
                _disconnect(interfaces, silent=self._silent)

    def _stream_alive(self) -> bool:
        """Whether the controller's data still come: a new timestamp within a few periods.

        ur_rtde's ``disconnect`` joins its receive thread, which, once the data have stopped,
        reconnects without a time limit: a disconnect must know."""
        r = self.receive
        if r is None or not r.isConnected():
            return False
        deadline = time.monotonic() + _ALIVE_WAIT_PERIODS * self.control_period_s
        last = r.getTimestamp()
        while time.monotonic() < deadline:
            time.sleep(self.control_period_s / 4)
            if r.getTimestamp() != last:
                return True
        return False

    def connect_control(self) -> None:
        """Take control of the arm now (uploads ur_rtde's URScript, about a second), rather than
        in the first cycle that moves it."""
        self._control()

    def _control(self) -> Any:
        """The control interface, connected on first use (uploads ur_rtde's URScript)."""
        if self.control is None:
            import rtde_control

            self.check()
            try:
                self.control = rtde_control.RTDEControlInterface(
                    self.host, 1.0 / self.control_period_s
                )
            except RuntimeError as exc:
                raise HardwareError(
                    f"{self.uri.text!r}: cannot take control of the arm (remote control mode "
                    f"on, program stopped?): {exc}"
                ) from None
        return self.control

    # ----------------------------------------------------------------- state
    def now_ns(self) -> int:
        """The host's monotonic clock [ns]."""
        return time.monotonic_ns()

    def check(self) -> None:
        """Raise if the connection is lost, the data stalled, or the arm is stopped by safety.

        Raises:
            HardwareError: naming what happened.
        """
        r = self.receive
        if r is None or not r.isConnected():
            self._silent = True
            raise HardwareError(f"{self.uri.text!r}: lost the connection to the controller")
        # New data is a timestamp that changed; none for timeout_s on the host's clock is a
        # stalled stream. (Comparing the controller's clock with the host's instead read a
        # controller clock running slow, the twin's simulated one under load, as a stall: a
        # real controller's crystal drifts too, 0.5 s in hours at 50 ppm.)
        timestamp, now = r.getTimestamp(), time.monotonic()
        if timestamp != self._last_timestamp_s:
            self._last_timestamp_s, self._fresh_at_s = timestamp, now
        elif now - self._fresh_at_s > self.timeout_s:
            self._silent = True
            raise HardwareError(  # the limit, then what was seen (the line's start is fixed)
                f"{self.uri.text!r}: no new data from the controller within "
                f"{self.timeout_s:.2f} s (the last {now - self._fresh_at_s:.2f} s ago)"
            )
        # One getter for both stops (ur_rtde's isProtectiveStopped and isEmergencyStopped each
        # read these bits again: every getter crosses into the client, ~10 us a call).
        bits = int(r.getSafetyStatusBits())
        if bits & _STOPPED_BITS:
            kind = "protective" if bits & _PROTECTIVE_STOPPED else "emergency"
            raise HardwareError(f"{self.uri.text!r}: the arm is in a {kind} stop")

    def pose(self) -> PoseSample:
        """The TCP pose in the base frame, stamped on the host's clock when read."""
        self.check()
        x = self.receive.getActualTCPPose()
        R = matrix_from_rotvec(x[3:6])
        return PoseSample(time.monotonic_ns(), np.array(x[0:3], dtype=float), R)

    def joint_speed_rad_s(self) -> float:
        """The fastest joint's speed now [rad/s]."""
        self.check()
        return float(np.max(np.abs(self.receive.getActualQd())))

    # ----------------------------------------------------------------- motion
    def is_reachable(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64]
    ) -> bool:
        """Inverse kinematics has a solution and the pose is within the safety limits."""
        control = self._control()
        pose = _pose_list(p_base_tcp, R_base_tcp)
        return bool(
            control.getInverseKinematicsHasSolution(pose) and control.isPoseWithinSafetyLimits(pose)
        )

    def joint_positions_rad(self) -> NDArray[np.float64]:
        """The joints' measured positions [rad] (``actual_q``)."""
        self.check()
        return np.array(self.receive.getActualQ(), dtype=float)

    def inverse_kinematics(
        self,
        p_base_tcp: NDArray[np.float64],
        R_base_tcp: NDArray[np.float64],
        q_near_rad: NDArray[np.float64],
    ) -> NDArray[np.float64] | None:
        """The controller's inverse kinematics nearest ``q_near_rad`` (ur_rtde's
        ``getInverseKinematics(pose, qnear)``), or None where it has no solution or the pose is
        outside the safety limits (asked first: a ``get_inverse_kin`` without a solution ends
        the control script)."""
        control = self._control()
        pose = _pose_list(np.asarray(p_base_tcp, dtype=float), np.asarray(R_base_tcp, dtype=float))
        near = [float(v) for v in q_near_rad]
        if not (
            control.getInverseKinematicsHasSolution(pose, near)
            and control.isPoseWithinSafetyLimits(pose)
        ):
            return None
        q = np.array(control.getInverseKinematics(pose, near), dtype=float)
        self.check()  # a program that ended on the way answers nothing worth reading
        return q

    def move_pose_joints(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64], duration_s: float
    ) -> None:
        """Blocking joint move (moveJ) to the inverse kinematics nearest the current joints,
        the leading joint at a speed that takes about ``duration_s`` (at most
        ``max_joint_speed_rad_s``).

        Raises:
            UnreachablePoseError: no inverse kinematics or outside the safety limits (checked
                before moving).
            HardwareError: the move failed, ended away from its target, or the connection was
                lost.
        """
        p = np.asarray(p_base_tcp, dtype=float)
        R = np.asarray(R_base_tcp, dtype=float)
        q_now = self.joint_positions_rad()
        q = self.inverse_kinematics(p, R, q_now)
        if q is None:
            raise UnreachablePoseError(
                f"{self.uri.text!r}: pose p={np.round(p, 4).tolist()} m is not reachable "
                "(no inverse kinematics or outside the safety limits); not moved"
            )
        way = float(np.max(np.abs(q - q_now)))
        speed = min(self.max_joint_speed_rad_s, max(way / max(duration_s, 1e-3), 1e-3))
        self._moving = True
        ok = self._control().moveJ(q.tolist(), speed, self.max_joint_accel_rad_s2, False)
        self._moving = False
        self._check_arrival(ok, "moveJ", p, R)

    def _check_arrival(
        self, ok: bool, command: str, p: NDArray[np.float64], R: NDArray[np.float64]
    ) -> None:
        """Raise unless a blocking move returned True and the TCP is at its target."""
        self.check()
        at = self.pose()
        off_m = float(np.linalg.norm(at.p_base_tcp - p))
        off_rad = float(Rotation.from_matrix(R @ at.R_base_tcp.T).magnitude())
        away = f"{off_m * 1e3:.1f} mm and {math.degrees(off_rad):.1f} deg from its target"
        if not ok:
            raise HardwareError(
                f"{self.uri.text!r}: {command} did not complete: the arm stopped {away} (the "
                "program ended: a joint limit or a singularity on the way, or the pendant; "
                "the controller's log says which)"
            )
        if off_m > _ARRIVED_M or off_rad > _ARRIVED_RAD:
            raise HardwareError(
                f"{self.uri.text!r}: {command} ended {away} (a joint limit or a singularity on "
                "the way?)"
            )

    def move_pose(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64], duration_s: float
    ) -> None:
        """Blocking linear move (moveL) at a speed that takes about ``duration_s``, capped at the
        URI's speed limit.

        Raises:
            UnreachablePoseError: no inverse kinematics or outside the safety limits (checked
                before moving).
            HardwareError: the move failed, ended away from its target, or the connection was
                lost.
        """
        p = np.asarray(p_base_tcp, dtype=float)
        R = np.asarray(R_base_tcp, dtype=float)
        if not self.is_reachable(p, R):
            raise UnreachablePoseError(
                f"{self.uri.text!r}: pose p={np.round(p, 4).tolist()} m is not reachable "
                "(no inverse kinematics or outside the safety limits); not moved"
            )
        here = self.pose()
        distance = float(np.linalg.norm(p - here.p_base_tcp))
        angle = float(Rotation.from_matrix(R @ here.R_base_tcp.T).magnitude())
        # moveL's profile takes the longer of the linear move at v and the rotation at 4 v rad/s.
        wanted = max(distance, angle / _MOVEL_RAD_PER_M) / max(duration_s, 1e-3)
        speed = min(self.max_speed_m_s, max(wanted, 1e-3))
        self._moving = True
        ok = self._control().moveL(_pose_list(p, R), speed, self.max_accel_m_s2, False)
        self._moving = False
        self._check_arrival(ok, "moveL", p, R)

    def settle(self, max_duration_s: float) -> float:
        """Wait until every joint is slower than 2 mrad/s for 0.1 s; return the time taken [s].

        Raises:
            HardwareError: still moving after ``max_duration_s``.
        """
        return self.pacer.wait_at_rest(
            lambda: self.joint_speed_rad_s() < _STILL_QD_RAD_S,
            _STILL_FOR_S,
            max_duration_s,
            repr(self.uri.text),
        )

    def command_twist(self, twist_base: NDArray[np.float64]) -> None:
        """Send the TCP twist (base frame) by speedL, or by servoL to the integrated pose.

        A zero twist while nothing moves is not sent: it needs no control interface.
        """
        tw = np.asarray(twist_base, dtype=float)
        if tw.shape != (6,) or not np.all(np.isfinite(tw)):
            raise ParameterError(f"twist_base must be 6 finite numbers, got {twist_base!r}")
        if not np.any(tw) and not self._moving:
            return
        control = self._control()
        self._moving = True
        dt = self.control_period_s
        if self.command == "speedl":
            self._sent(control.speedL(tw.tolist(), self.max_accel_m_s2, 0.0), "speedL")
            return
        if self._servo_target is None:
            here = self.pose()
            self._servo_target = (here.p_base_tcp.copy(), here.R_base_tcp.copy())
        p, R = self._servo_target
        p = p + tw[:3] * dt
        R = matrix_from_rotvec(tw[3:] * dt) @ R
        self._servo_target = (p, R)
        self._sent(control.servoL(_pose_list(p, R), 0.0, 0.0, dt, 0.1, 300.0), "servoL")

    def _sent(self, accepted: bool, command: str) -> None:
        """Raise when the controller refused a motion command: ``ur_rtde`` returns False when
        its control script no longer runs (stopped from the pendant, another program started),
        and a loop that keeps commanding into nothing no longer controls the arm. A protective
        or emergency stop also ends the script, and the receive side may show it a period
        later: it is waited for (a few periods) so the error names the real cause."""
        if not accepted:
            deadline = time.monotonic() + 3 * self.control_period_s
            while True:
                self.check()  # raises naming a safety stop or a lost connection
                if time.monotonic() >= deadline:
                    break
                time.sleep(self.control_period_s / 4)
            raise HardwareError(
                f"{self.uri.text!r}: the controller refused {command} (its control script is not "
                "running: stopped from the pendant or another program started?); motion stopped"
            )

    def wait_cycle(self) -> None:
        """Wait for the next control period (host clock)."""
        self.pacer.sleep()

    def stop(self) -> None:
        """Decelerate to rest at once (speedStop, or servoStop in servo mode); when that does
        not return in time (the controller went silent), stop the program through the
        dashboard server.

        ur_rtde's ``speedStop``/``servoStop`` send the command, then poll the received state
        for the script's *done* for up to 300 s (``UR_EXECUTION_TIMEOUT``), and its receive
        thread, once the data stop, reconnects without a time limit (ur_rtde 1.6.5,
        ``rtde_control_interface.cpp``). A controller can go silent at any moment (a cable
        pulled: the sensor's stale reading may be what stopped the loop, 20 ms before the
        robot's own stream is judged lost), so the stop command is always sent from a worker
        thread and waited for at most :data:`_EXIT_WAIT_S` (it reaches a controller whose
        output alone stalled); then the dashboard's ``stop`` (port 29999) ends the program,
        which stops the arm.
        """
        self._servo_target = None
        if self.control is None or not self._moving:
            return
        self._moving = False
        halt = self.control.speedStop if self.command == "speedl" else self.control.servoStop
        if not _bounded(lambda: halt(10.0), "ur-stop") or self._silent:
            self._silent = True
            _bounded(self._dashboard_stop, "ur-dashboard-stop")

    def _dashboard_stop(self) -> None:
        """Stop the program through the dashboard server (port 29999)."""
        import dashboard_client

        dashboard = dashboard_client.DashboardClient(self.host)
        dashboard.connect(round(_EXIT_WAIT_S * 1000))
        try:
            dashboard.stop()
        finally:
            dashboard.disconnect()


#: A controller that sends no new data within this many periods is silent (at exit): 0.2 s at
#: 500 Hz, past the stalls of a loaded host's twin (its stream's gaps reached 70 ms in clean-clone
#: runs). At 25 periods (50 ms) a clean clone's run took a live twin for silent after a moveL
#: and took the silent path (a bounded disconnect on a thread), where ur_rtde 1.6's disconnect
#: crashed the process with a segmentation fault; a healthy controller's interfaces are only
#: dropped.
_ALIVE_WAIT_PERIODS: Final = 100

#: How long a stop, the script's end or a disconnect may take before the controller is taken
#: for silent [s]. A healthy controller answers each within a few periods (speedStop
#: decelerates from 0.25 m/s at 10 m/s^2 in 25 ms).
_EXIT_WAIT_S: Final = 0.5
#: How long the interfaces' disconnects may take [s]: ur_rtde 1.6's fixed 0.5 s sleep at the end
#: of each, and the time of any other call at exit.
_DISCONNECT_WAIT_S: Final = 0.5 + _EXIT_WAIT_S


def _disconnect(interfaces: list[Any], *, silent: bool) -> None:
    """Disconnect ur_rtde interfaces, all at once, each on a daemon thread (ur_rtde releases
    the interpreter's lock in its calls), waiting at most :data:`_DISCONNECT_WAIT_S` in all;
    then keep each one, never destroyed.

    A healthy interface is kept (:func:`_keep`) because its destructor would disconnect again
    and sleep another 0.5 s (ur_rtde 1.6); disconnected, it holds no thread and no socket,
    a few kilobytes until the process ends. One whose controller went silent (``silent``), or
    whose ``disconnect`` did not return in time or raised, is abandoned (:func:`_abandon`)."""
    started = [_on_thread(i.disconnect, "ur-disconnect") for i in interfaces]
    deadline = time.monotonic() + _DISCONNECT_WAIT_S
    for worker, _ in started:
        worker.join(max(0.0, deadline - time.monotonic()))
    for interface, (_, returned) in zip(interfaces, started, strict=True):
        if silent or not returned.is_set():
            _abandon(interface)
        else:
            _keep(interface)


def _on_thread(call: Callable[[], object], name: str) -> tuple[threading.Thread, threading.Event]:
    """``call`` started on a daemon thread, and the event it sets once it returned without
    raising (what it raises is dropped: on the way to a stop the next resort follows, the
    dashboard's stop, not an error)."""
    returned = threading.Event()

    def run() -> None:
        with contextlib.suppress(Exception):
            call()
            returned.set()

    worker = threading.Thread(target=run, name=name, daemon=True)
    worker.start()
    return worker, returned


def _bounded(call: Callable[[], object], name: str) -> bool:
    """Run ``call`` on a daemon thread and wait for it at most :data:`_EXIT_WAIT_S` (ur_rtde
    releases the interpreter's lock in its calls, so a call that hangs holds only its own
    thread). Whether it returned in time without raising (:func:`_on_thread`)."""
    worker, returned = _on_thread(call, name)
    worker.join(_EXIT_WAIT_S)
    return returned.is_set()


#: ur_rtde interfaces whose controller went silent, kept until the process ends (see _abandon).
_ABANDONED: list[object] = []


def _keep(interface: object) -> None:
    """Never destroy a disconnected interface of a healthy controller: its destructor would
    only disconnect again, with ur_rtde's 0.5 s sleep (a reference the interpreter never
    drops, not even when it clears modules at exit; the process may end normally)."""
    ctypes.pythonapi.Py_IncRef(ctypes.py_object(interface))


def _abandon(interface: object) -> None:
    """Never destroy a ur_rtde interface whose controller went silent (once its bounded
    ``disconnect`` has been asked).

    Its receive thread (the control interface has one of its own) reconnects without a time
    limit once the data stop; destroying the interface then ends the process in ur_rtde's
    teardown: ``terminate called without an active exception``, exit -6, after ``run`` had
    stopped on the fault and written its log (ur_rtde 1.6.5; issue 34: 2 of 3 rtde-stop tries
    on a busy host). Skipping the ``disconnect`` as well is worse (every try aborted at exit:
    the library's threads must be told to stop). So ``disconnect`` is asked on a worker
    (:func:`_disconnect`) and the interface is kept (:func:`_keep`), and noted so that a
    command line program ends without the teardown (:func:`exit_process_if_abandoned`); the
    operating system reclaims the rest with the process."""
    _ABANDONED.append(interface)
    _keep(interface)


def exit_process_if_abandoned(code: int) -> None:
    """For a command line program: end the process now with ``code`` (output flushed) if an
    interface was abandoned (:func:`_abandon`), before the interpreter and the C++ runtime tear
    down: ur_rtde's threads for a silent controller abort that teardown (``terminate called
    without an active exception``, exit -6) even when the interface is never destroyed. A
    program that goes on after a silent controller keeps the abandoned interfaces instead."""
    if _ABANDONED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


@dataclass(frozen=True)
class Payload:
    """A UR controller's payload setting.

    Attributes:
        mass_kg: the payload's mass [kg].
        cog_flange_m: its centre of gravity from the tool flange, flange frame [m], (3,) (as
            URScript's ``set_payload`` takes it).
    """

    mass_kg: float
    cog_flange_m: tuple[float, float, float]


def set_payload(
    host: str, mass_kg: float, cog_tcp_m: NDArray[np.float64], *, label: str = ""
) -> tuple[Payload, Payload]:
    """Write the payload to a UR controller (ur_rtde's ``setPayload``); ``(before, after)``,
    both as RTDE's ``payload`` and ``payload_cog`` report them.

    The centre of gravity is given in the controller's TCP frame and written from the flange
    (``setPayload``'s frame), through the TCP offset the controller reports (``getTCPOffset``).

    Args:
        host: the controller's address.
        mass_kg: the payload's mass [kg], in [0, 100].
        cog_tcp_m: its centre of gravity in the TCP frame [m], (3,), each within 2 m.
        label: names the controller in messages (default: the host).

    Raises:
        ParameterError: a value out of range, or ur_rtde missing.
        HardwareError: the controller cannot be reached or refused the setting.
    """
    name = label or host
    cog = np.asarray(cog_tcp_m, dtype=float)
    if not (math.isfinite(mass_kg) and 0.0 <= mass_kg <= _MAX_PAYLOAD_KG):
        raise ParameterError(f"mass_kg must be in [0, {_MAX_PAYLOAD_KG:g}] kg, got {mass_kg:g}")
    if cog.shape != (3,) or not np.all(np.isfinite(cog)) or np.any(np.abs(cog) > 2.0):
        raise ParameterError(f"cog_tcp_m must be 3 finite numbers within 2 m, got {cog_tcp_m!r}")
    try:
        import rtde_control
        import rtde_receive
    except ImportError:
        raise ParameterError(f"ur:// needs ur_rtde: {install_hint('ur')}") from None
    try:
        receive = rtde_receive.RTDEReceiveInterface(host, 125.0, ["payload", "payload_cog"])
    except RuntimeError as exc:
        raise HardwareError(f"{name}: ur_rtde could not connect: {exc}") from None
    try:
        before = Payload(
            float(receive.getPayload()),
            tuple(map(float, receive.getPayloadCog())),  # type: ignore[arg-type]
        )
        try:
            control = rtde_control.RTDEControlInterface(host)
        except RuntimeError as exc:
            raise HardwareError(f"{name}: cannot take control of the arm: {exc}") from None
        try:
            offset = control.getTCPOffset()
            R_flange_tcp = matrix_from_rotvec(offset[3:6])
            cog_flange = np.array(offset[:3], dtype=float) + R_flange_tcp @ cog
            if not control.setPayload(float(mass_kg), cog_flange.tolist()):
                raise HardwareError(f"{name}: the controller refused setPayload")
        finally:
            try:
                control.stopScript()
            finally:
                _disconnect([control], silent=False)
        deadline = time.monotonic() + 1.0  # the next packages carry it
        while True:
            after = Payload(
                float(receive.getPayload()),
                tuple(map(float, receive.getPayloadCog())),  # type: ignore[arg-type]
            )
            done = abs(after.mass_kg - mass_kg) < 1e-9 and np.allclose(
                after.cog_flange_m, cog_flange, atol=1e-9
            )
            if done or time.monotonic() > deadline:
                break
            time.sleep(0.01)
    finally:
        _disconnect([receive], silent=False)
    return before, after


#: The largest payload set_payload accepts [kg] (above any UR's rated payload, 30 kg).
_MAX_PAYLOAD_KG: Final = 100.0


def open_robot(uri: Uri) -> Robot:
    """A UR arm from its URI (connects when entered)."""
    if not uri.host:
        raise ParameterError(f"{uri.text!r}: give the controller's address, e.g. ur://192.168.1.10")
    if uri.port is not None or uri.path not in ("", "/"):
        raise ParameterError(f"{uri.text!r}: ur:// takes a host only (RTDE is on port 30004)")
    options = uri.reader()
    frequency = options.number("frequency_hz", None)
    speed = options.positive("max_speed_mm_s", 100.0)
    accel = options.positive("max_accel_mm_s2", 500.0)
    joint_speed = options.positive("max_joint_speed_deg_s", math.degrees(_JOINT_SPEED_RAD_S))
    joint_accel = options.positive("max_joint_accel_deg_s2", math.degrees(_JOINT_ACCEL_RAD_S2))
    command = options.text("command", "speedl", ("speedl", "servol"))
    timeout_s = options.positive("timeout_s", 0.5)
    connect_s = options.positive("connect_timeout_s", 2.0)
    options.done()
    if frequency is not None and not 1.0 <= frequency <= 500.0:
        raise ParameterError(f"{uri.text!r}: frequency_hz must be in [1, 500], got {frequency:g}")
    if speed > 1000.0:
        raise ParameterError(f"{uri.text!r}: max_speed_mm_s above 1000 mm/s is not allowed")
    for name, value, limit in (
        ("max_joint_speed_deg_s", joint_speed, _MAX_JOINT_SPEED_DEG_S),
        ("max_joint_accel_deg_s2", joint_accel, _MAX_JOINT_ACCEL_DEG_S2),
    ):
        if value > limit:
            raise ParameterError(f"{uri.text!r}: {name} above {limit:g} is not allowed")
    return URRobot(
        uri,
        frequency_hz=frequency,
        max_speed_m_s=speed * 1e-3,
        max_accel_m_s2=accel * 1e-3,
        max_joint_speed_rad_s=math.radians(joint_speed),
        max_joint_accel_rad_s2=math.radians(joint_accel),
        command=command,
        timeout_s=timeout_s,
        connect_timeout_s=connect_s,
    )
