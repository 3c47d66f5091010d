"""The hardware seam: what ftcomp needs of a wrench sensor and of a robot.

Every backend (the MuJoCo cell now; ATI Net F/T, Universal Robots, ROS 2 topics and recorded
files later) implements these :class:`typing.Protocol` classes, so calibration, compensation
and control run unchanged on any of them. Backends are chosen by URI
(:mod:`ftcomp.hardware.registry`).

Lifecycle: a sensor and a robot are context managers. Entering connects; leaving *stops motion
first* and then closes the connection, also when the block ends by an exception or Ctrl-C.

Clock: every time stamp is an integer number of nanoseconds (``t_ns``) on the clock of the
*robot* the session runs with, so a sample's age is ``robot.now_ns() - sample.t_ns``. Hardware
backends use the host's monotonic clock (:func:`time.monotonic_ns`), stamping each reading when
it arrives; the simulated cell uses its simulation time. Seconds (float) appear only in
arithmetic.

Capabilities beyond these protocols are protocols too, all here, checked with ``isinstance``
(never by probing attributes); which backend has which:

=========================  =====================================================================
capability                 backends that have it
=========================  =====================================================================
:class:`TakesControl`      ``ur://`` (uploads its control script before the first motion)
:class:`ReportsLateness`   ``ur://``, ``franka://``, ``fixed://`` (paced on the host's clock)
:class:`ChecksReachability`  ``ur://`` (IK and safety limits), ``sim://`` (the cell's IK),
                           ``franka://`` (IK on the arm's own model and URDF ranges)
:class:`MovesInJointSpace`  ``ur://`` (moveJ), ``franka://`` (franky's JointMotion)
:class:`CountsLostPackets`  ``netft://`` (RDT sequence numbers)
:class:`ReportsStreamHealth`  ``netft://``
:class:`TaresInHardware`   ``netft://`` (RDT's software bias, ``?bias=1``)
:class:`ReportsExtraChannels`  ``bota://`` (temperature; through bota-driver an IMU too)
=========================  =====================================================================

Two things every robot states (members of :class:`Robot`, not capabilities): its clock
(:attr:`Robot.clock_name`) and whether its pose is the sensor's real pose
(:attr:`Robot.pose_known`: ``fixed://`` without a pose has a placeholder pose).

Frames and units (``docs/conventions.md``): a robot reports the pose of its *TCP* (or flange)
in its base frame; the sensor frame is fixed to the TCP by a :class:`Mount`, which is the one
place where ``R_base_sensor = R_base_tcp @ R_tcp_sensor`` is computed. Wrenches are what the tool
exerts on the sensor, sensor frame [N, N*m]. Twists ``[vx, vy, vz, wx, wy, wz]`` [m/s, rad/s]
are in the base frame, of the TCP origin when sent to a robot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import TracebackType
from typing import Final, Literal, Protocol, Self, TypeVar, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.arrays import freeze_field
from ftcomp.errors import ParameterError
from ftcomp.frames import cross3

__all__ = [
    "HOST_CLOCK",
    "IMU_CHANNELS",
    "TEMPERATURE_CHANNEL",
    "ChecksReachability",
    "ClockName",
    "CountsLostPackets",
    "Mount",
    "MovesInJointSpace",
    "NothingToClose",
    "PoseSample",
    "ReportsExtraChannels",
    "ReportsLateness",
    "ReportsRate",
    "ReportsStreamHealth",
    "Robot",
    "StreamHealth",
    "TakesControl",
    "TaresInHardware",
    "WrenchSample",
    "WrenchSensor",
]

#: The clocks a robot's :meth:`~Robot.now_ns` may run on: the host's monotonic clock
#: (:func:`time.monotonic_ns`, that of sensors stamped on arrival), a simulation's time, or a
#: replayed recording's time.
ClockName = Literal["monotonic", "simulation", "replay"]
#: The host's monotonic clock.
HOST_CLOCK: Final = "monotonic"

_NS_PER_S = 1_000_000_000
_SensorT = TypeVar("_SensorT", bound="WrenchSensor")
_RobotT = TypeVar("_RobotT", bound="Robot")


@dataclass(frozen=True)
class WrenchSample:
    """One time-stamped sensor reading.

    Attributes:
        t_ns: time stamp [ns] on the session's clock (see the module docstring).
        wrench_sensor: ``[fx, fy, fz, tx, ty, tz]`` [N, N*m], sensor frame, shape (6,); may hold
            NaN when the sensor reports garbage: consumers check (see ``ftcomp.control.safety``).
        extras: the values of the sensor's extra channels in the frame this wrench came in, in
            the order of its :attr:`ReportsExtraChannels.extra_channels` (empty for a sensor
            without them).
    """

    t_ns: int
    wrench_sensor: NDArray[np.float64] = field(repr=False)
    extras: tuple[float, ...] = field(default=(), repr=False)

    def __post_init__(self) -> None:
        freeze_field(self, "wrench_sensor", (6,))
        if self.extras != ():  # none, the common case, costs nothing (a simulated 1 kHz sensor)
            object.__setattr__(self, "extras", tuple(float(v) for v in self.extras))

    @property
    def t_s(self) -> float:
        """The time stamp in seconds (for arithmetic)."""
        return self.t_ns / _NS_PER_S

    @classmethod
    def owning(
        cls, t_ns: int, wrench_sensor: NDArray[np.float64], extras: tuple[float, ...] = ()
    ) -> WrenchSample:
        """A sample that takes ownership of a fresh float64 (6,) array without copying it
        (for a backend's 1 kHz path; the array is made read-only, so pass one nobody else keeps).
        """
        wrench_sensor.setflags(write=False)
        sample = object.__new__(cls)
        object.__setattr__(sample, "t_ns", t_ns)
        object.__setattr__(sample, "wrench_sensor", wrench_sensor)
        object.__setattr__(sample, "extras", extras)
        return sample


@dataclass(frozen=True)
class PoseSample:
    """A time-stamped pose of the robot's TCP (or flange) in its base frame.

    Attributes:
        t_ns: time stamp [ns] on the session's clock.
        p_base_tcp: TCP origin [m], base frame, shape (3,).
        R_base_tcp: TCP orientation, shape (3, 3).
    """

    t_ns: int
    p_base_tcp: NDArray[np.float64] = field(repr=False)
    R_base_tcp: NDArray[np.float64] = field(repr=False)

    def __post_init__(self) -> None:
        freeze_field(self, "p_base_tcp", (3,))
        freeze_field(self, "R_base_tcp", (3, 3))

    @classmethod
    def owning(
        cls, t_ns: int, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64]
    ) -> PoseSample:
        """A pose that takes ownership of fresh float64 arrays of shapes (3,) and (3, 3) without
        copying them (a backend's 1 kHz path; they are made read-only)."""
        p_base_tcp.setflags(write=False)
        R_base_tcp.setflags(write=False)
        sample = object.__new__(cls)
        object.__setattr__(sample, "t_ns", t_ns)
        object.__setattr__(sample, "p_base_tcp", p_base_tcp)
        object.__setattr__(sample, "R_base_tcp", R_base_tcp)
        return sample


def _rotation_matrix(name: str, value: ArrayLike) -> NDArray[np.float64]:
    R = np.array(value, dtype=float)
    if R.shape != (3, 3) or not np.all(np.isfinite(R)):
        raise ParameterError(f"{name} must be a finite 3x3 matrix, got shape {R.shape}")
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0.0:
        raise ParameterError(f"{name} is not a rotation matrix (R R^T != I or det < 0)")
    return R


@dataclass(frozen=True)
class Mount:
    """Where the sensor frame sits on the robot's TCP (or flange).

    Attributes:
        R_tcp_sensor: the sensor frame's orientation in the TCP frame, shape (3, 3);
            identity by default (the sensor's axes are the TCP's).
        p_tcp_sensor_m: the sensor frame's origin in the TCP frame [m], shape (3,); zeros by
            default.
    """

    R_tcp_sensor: NDArray[np.float64] = field(default_factory=lambda: np.eye(3))
    p_tcp_sensor_m: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    is_identity: bool = field(init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "R_tcp_sensor", _rotation_matrix("R_tcp_sensor", self.R_tcp_sensor)
        )
        freeze_field(self, "R_tcp_sensor", (3, 3))
        freeze_field(self, "p_tcp_sensor_m", (3,), finite=True)
        identity = bool(
            np.array_equal(self.R_tcp_sensor, np.eye(3)) and not np.any(self.p_tcp_sensor_m)
        )
        object.__setattr__(self, "is_identity", identity)

    @classmethod
    def from_xyz_rpy(
        cls, xyz_m: ArrayLike = (0.0, 0.0, 0.0), rpy_deg: ArrayLike = (0.0, 0.0, 0.0)
    ) -> Mount:
        """From an offset [m] and fixed-axis roll, pitch, yaw [deg] (as in a URDF ``<origin>``:
        ``R = Rz(yaw) Ry(pitch) Rx(roll)``)."""
        from scipy.spatial.transform import Rotation

        rpy = np.asarray(rpy_deg, dtype=float)
        if rpy.shape != (3,) or not np.all(np.isfinite(rpy)):
            raise ParameterError(f"rpy_deg must be 3 finite angles, got {rpy.tolist()}")
        R = Rotation.from_euler("xyz", rpy, degrees=True).as_matrix()
        return cls(R, np.asarray(xyz_m, dtype=float))

    @classmethod
    def from_mm_deg(cls, values: ArrayLike) -> Mount:
        """From six numbers as a user types them: ``x, y, z`` [mm], fixed-axis ``roll, pitch,
        yaw`` [deg] (:meth:`from_xyz_rpy`).

        Raises:
            ParameterError: not six finite numbers (naming the field ``mount``).
        """
        v = np.asarray(values, dtype=float)
        if v.shape != (6,) or not np.all(np.isfinite(v)):
            raise ParameterError(
                "mount must be six finite numbers X,Y,Z,ROLL,PITCH,YAW (mm, deg), e.g. "
                f"0,0,35,0,0,90; got {np.atleast_1d(v).tolist()}",
                field="mount",
            )
        return cls.from_xyz_rpy(v[:3] * 1e-3, v[3:])

    def sensor_pose(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(p_base_sensor, R_base_sensor)`` from the TCP's pose in the base frame."""
        if self.is_identity:
            return p_base_tcp, R_base_tcp
        return p_base_tcp + R_base_tcp @ self.p_tcp_sensor_m, R_base_tcp @ self.R_tcp_sensor

    def tcp_pose(
        self, p_base_sensor: NDArray[np.float64], R_base_sensor: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The TCP pose that puts the sensor frame at ``(p_base_sensor, R_base_sensor)``."""
        if self.is_identity:
            return p_base_sensor, R_base_sensor
        R_base_tcp = R_base_sensor @ self.R_tcp_sensor.T
        return p_base_sensor - R_base_tcp @ self.p_tcp_sensor_m, R_base_tcp

    def tcp_twist(
        self, twist_sensor_base: NDArray[np.float64], R_base_tcp: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """The TCP origin's twist giving the sensor origin ``twist_sensor_base`` (base frame).

        Both origins share the angular velocity w; ``v_tcp = v_sensor + w x (p_tcp - p_sensor)``
        with ``p_tcp - p_sensor = -R_base_tcp @ p_tcp_sensor_m``.
        """
        if self.is_identity or not np.any(self.p_tcp_sensor_m):
            return twist_sensor_base
        lever = -(R_base_tcp @ self.p_tcp_sensor_m)
        out = np.array(twist_sensor_base, dtype=float)
        out[:3] += cross3(out[3:], lever)
        return out


class NothingToClose:
    """The lifecycle of a backend with nothing to connect or close (a simulated or replayed
    sensor, a fixed robot): entering returns it, leaving does nothing. A backend that connects
    overrides ``__enter__`` and keeps this ``__exit__`` if it has nothing of its own to close."""

    def __enter__(self) -> Self:
        """Nothing to connect."""
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Nothing to close."""


@runtime_checkable
class WrenchSensor(Protocol):
    """A six-axis force/torque sensor (a context manager: connect on enter, close on exit)."""

    def __enter__(self: _SensorT) -> _SensorT:
        """Connect (start streaming)."""
        ...

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Stop streaming and close."""
        ...

    def read(self) -> WrenchSample:
        """The newest reading (non-blocking; the same sample again if none arrived since)."""
        ...

    def read_new(self) -> list[WrenchSample]:
        """Every reading since the previous call (oldest first; empty if none arrived)."""
        ...


@runtime_checkable
class Robot(Protocol):
    """A position-controlled arm with a Cartesian velocity interface, driven one cycle at a time.

    A context manager: connect on enter; on exit (also by an exception or Ctrl-C) stop motion
    first, then close.
    """

    @property
    def control_period_s(self) -> float:
        """Period of the control cycle [s]."""
        ...

    @property
    def clock_name(self) -> ClockName:
        """The clock of :meth:`now_ns` and of every stamp (see :data:`ClockName`)."""
        ...

    @property
    def pose_known(self) -> bool:
        """Whether :meth:`pose` is the TCP's real pose (measured, recorded or given by the user);
        False for a robot that only paces the loop (``fixed://`` given no pose), whose pose is a
        placeholder that must not be used to compensate."""
        ...

    def __enter__(self: _RobotT) -> _RobotT:
        """Connect."""
        ...

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Stop motion, then close."""
        ...

    def now_ns(self) -> int:
        """The session's clock [ns]."""
        ...

    def pose(self) -> PoseSample:
        """The TCP's pose in the base frame now, time-stamped."""
        ...

    def move_pose(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64], duration_s: float
    ) -> None:
        """Blocking Cartesian move of the TCP to a pose (base frame) in about ``duration_s``.

        Raises:
            UnreachablePoseError: no joint configuration within the limits reaches it.
        """
        ...

    def settle(self, max_duration_s: float) -> float:
        """Hold still until the arm is at rest (blocking); return how long it took [s].

        Raises:
            FtcompError: still moving after ``max_duration_s`` [s].
        """
        ...

    def command_twist(self, twist_base: NDArray[np.float64]) -> None:
        """Set the TCP origin's velocity (base frame, shape (6,)) for the coming cycles."""
        ...

    def wait_cycle(self) -> None:
        """Advance (simulation) or wait for (hardware) the next control period."""
        ...

    def stop(self) -> None:
        """Zero the commanded velocity at once."""
        ...


@runtime_checkable
class TakesControl(Protocol):
    """A robot whose control side is connected apart from its state, on first motion or when
    asked: a caller about to move it connects first, so the first cycle is not late.

    Backends: ``ur://`` (uploads ur_rtde's URScript program, about a second).
    """

    def connect_control(self) -> None:
        """Take control of the arm now (idempotent).

        Raises:
            HardwareError: the controller refuses (not in remote control, program stopped...).
        """
        ...


@runtime_checkable
class ReportsLateness(Protocol):
    """A robot that waits for its control periods on the host's clock and counts the periods
    its caller missed (a loop treats ``periods_behind`` beyond a limit as a fault).

    Backends: ``ur://``, ``franka://``, ``fixed://`` (by
    :class:`ftcomp.hardware.pacing.RateLimiter`). Not
    ``sim://`` (simulated time is never late) nor ``replay://`` (a dry run).
    """

    @property
    def periods_behind(self) -> int:
        """Periods the loop has fallen behind the robot's schedule: the time stalls took, net of
        the slack of the periods since (0 once it has caught up)."""
        ...

    @property
    def late_cycles(self) -> int:
        """Cycles that overran their period since the robot was opened."""
        ...

    @property
    def worst_lateness_s(self) -> float:
        """The largest overrun seen [s] (0 when none)."""
        ...

    def restart_schedule(self) -> None:
        """A loop starts: the periods from now on, nothing owed for the time before (set-up,
        or a pause since an earlier loop on the same robot)."""
        ...


@runtime_checkable
class ChecksReachability(Protocol):
    """A robot that can check a target before moving (inverse kinematics, safety limits).

    Backends: ``ur://`` (the controller's inverse kinematics and safety limits; connects the
    control side), ``sim://`` (the cell's inverse kinematics within the joint ranges),
    ``franka://`` (inverse kinematics on libfranka's model within the arm's URDF's ranges).
    """

    def is_reachable(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64]
    ) -> bool:
        """Whether the TCP can be brought to this pose (base frame [m]) within the robot's
        limits."""
        ...


@runtime_checkable
class MovesInJointSpace(Protocol):
    """A robot that visits a pose by a joint move to the inverse kinematics nearest its
    current joints, within its joint ranges (as a pose design's visit check plans it,
    :func:`ftcomp.calibration.reachable_design.plan_visit`).

    Backends: ``ur://`` (``getInverseKinematics(pose, qnear)`` and ``moveJ``), ``franka://``
    (:class:`ftcomp.chain_ik.ChainIk` on libfranka's model from the joints now, franky's
    ``JointMotion``).
    """

    def joint_positions_rad(self) -> NDArray[np.float64]:
        """The joints' positions now [rad], (N,)."""
        ...

    def inverse_kinematics(
        self,
        p_base_tcp: NDArray[np.float64],
        R_base_tcp: NDArray[np.float64],
        q_near_rad: NDArray[np.float64],
    ) -> NDArray[np.float64] | None:
        """The joints [rad] putting the TCP at this base-frame pose nearest ``q_near_rad``
        within the joint ranges, or None."""
        ...

    def move_pose_joints(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64], duration_s: float
    ) -> None:
        """Blocking joint move to the inverse kinematics nearest the current joints."""
        ...


@runtime_checkable
class CountsLostPackets(Protocol):
    """A streaming sensor that numbers its packets and so knows how many never arrived.

    Backends: ``netft://`` (RDT sequence numbers).
    """

    @property
    def lost_packets(self) -> int:
        """Packets lost since the stream started."""
        ...

    @property
    def rate_hz(self) -> float:
        """The measured rate of arriving samples [Hz]."""
        ...


@runtime_checkable
class ReportsRate(Protocol):
    """A sensor that tells the rate its samples come at: the mean rate of the samples it has
    handed out or kept since its stream started, or its simulation's (``ftcomp run`` sets its
    wrench filter from it).

    Backends: ``netft://``, ``robotiq://``, ``bota://`` (from their readings' stamps),
    ``sim://``.
    """

    @property
    def sample_rate_hz(self) -> float:
        """Samples per second [Hz]; NaN while too few have come to tell."""
        ...


@runtime_checkable
class TaresInHardware(Protocol):
    """A sensor that can zero its readings in the device when its stream starts.

    A sensor zeroed with the tool on it reads the tool's weight as zero, which a calibration
    subtracts again: a session with a calibration refuses a sensor that tares itself
    (``ftcomp rebias`` re-biases a calibration gravity-aware instead).

    Backends: ``netft://`` (RDT's software bias, ``?bias=1``).
    """

    @property
    def tares_in_hardware(self) -> bool:
        """Whether this sensor zeroes its readings when its stream starts."""
        ...


#: The extra channels' names, as sensors report them and the logs carry them: a temperature
#: [degC] and an IMU's acceleration [m/s^2] and angular rate [rad/s] (sensor frame).
TEMPERATURE_CHANNEL: Final = "temperature_C"
IMU_CHANNELS: Final = (
    "accel_x_m_s2",
    "accel_y_m_s2",
    "accel_z_m_s2",
    "gyro_x_rad_s",
    "gyro_y_rad_s",
    "gyro_z_rad_s",
)


@runtime_checkable
class ReportsExtraChannels(Protocol):
    """A sensor that measures more than the wrench in each frame (its temperature, an IMU's
    acceleration and angular rate): every :class:`WrenchSample` it gives carries those values
    of the same frame in :attr:`WrenchSample.extras`, so a log row holds the values that came
    with its wrench, not the newest.

    Backends: ``bota://`` (``temperature_C``; through bota-driver also ``accel_x_m_s2``,
    ``accel_y_m_s2``, ``accel_z_m_s2`` and ``gyro_x_rad_s``, ``gyro_y_rad_s``,
    ``gyro_z_rad_s``, sensor frame).
    """

    @property
    def extra_channels(self) -> tuple[str, ...]:
        """The channels' names, each with its unit (``temperature_C``, ``accel_x_m_s2``...),
        in the order of :attr:`WrenchSample.extras`; fixed for the sensor's life."""
        ...


@dataclass(frozen=True)
class StreamHealth:
    """One consistent snapshot of a sensor stream's health.

    Attributes:
        received: packets received since the stream started.
        lost_packets: packets lost since then (gaps in the sequence numbers).
        last_sequence: the device's sequence number of the newest packet (None before one).
        rate_hz: the measured rate of arriving samples [Hz].
        force_unit: the device's force unit, as it names it (readings are converted to N).
        torque_unit: its torque unit (readings are converted to N*m).
    """

    received: int
    lost_packets: int
    last_sequence: int | None
    rate_hz: float
    force_unit: str
    torque_unit: str

    def __post_init__(self) -> None:
        if self.received < 0 or self.lost_packets < 0:
            raise ParameterError(
                f"packet counts must be >= 0, got received={self.received}, "
                f"lost_packets={self.lost_packets}"
            )


@runtime_checkable
class ReportsStreamHealth(Protocol):
    """A streaming sensor that reports its stream's health in one snapshot.

    Backends: ``netft://``.
    """

    def stream_health(self) -> StreamHealth:
        """The health now."""
        ...


def seconds_to_ns(t_s: float) -> int:
    """``t_s`` [s] as integer nanoseconds (rounded to the nearest)."""
    if not math.isfinite(t_s):
        raise ParameterError(f"a time stamp must be finite, got {t_s}")
    return round(t_s * _NS_PER_S)
