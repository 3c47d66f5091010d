"""The safety envelope around an admittance law: limits, protective stops and a sample watchdog.

All functions are pure, and each check exists once: the controller
(:mod:`ftcomp.control.controller`) calls these same functions each period, in this order: watchdog
on the sample (:func:`check_sample`), the sensor's range on the raw reading (:func:`check_range`),
force/torque limit on the *unfiltered* contact wrench (:func:`check_wrench`), then (after the law)
velocity and acceleration limits on the twist (:func:`limit_twist`), then the travel limit
(:func:`check_travel`).
A stop is latched and zeroes the twist at once (not ramped by the acceleration limit): a
protective stop must act within the control period that saw the fault.

Gain changes are bumpless by construction: the position term of the laws is executed
incrementally (a new K1 acts on later force changes only) and the acceleration limit caps any
step a new K2 would cause in the command.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.arrays import frozen_array
from ftcomp.config_fields import check_fields, check_value, param
from ftcomp.errors import ParameterError
from ftcomp.samples import SENSOR_RANGE

__all__ = [
    "MAX_ROTATION_ACCEL_RAD_S2",
    "MAX_ROTATION_SPEED_RAD_S",
    "SafetyLimits",
    "StopReason",
    "UniformLimits",
    "WatchdogState",
    "check_range",
    "check_sample",
    "check_travel",
    "check_wrench",
    "limit_twist",
]


#: The rotation speed limit of a session that limits only its translation by choice (``ftcomp
#: run``, a placement) [rad/s]: a rotation K1/K2 of 1 deg/(N*m) turns this fast under 30 N*m.
MAX_ROTATION_SPEED_RAD_S = 0.5
#: Its rotation acceleration limit [rad/s^2].
MAX_ROTATION_ACCEL_RAD_S2 = 5.0


class StopReason(enum.StrEnum):
    """Why the controller stopped the motion (a protective stop)."""

    NON_FINITE_SAMPLE = "non_finite_sample"
    REPEATED_SAMPLE = "repeated_sample"
    STALE_SAMPLE = "stale_sample"
    FROZEN_SAMPLE = "frozen_sample"
    SENSOR_SATURATED = "sensor_saturated"
    CLOCK_FAULT = "clock_fault"
    NON_FINITE_POSE = "non_finite_pose"
    INVALID_INPUT = "invalid_input"
    NON_FINITE_COMMAND = "non_finite_command"
    FORCE_LIMIT = "force_limit"
    TORQUE_LIMIT = "torque_limit"
    TRAVEL_LIMIT = "travel_limit"


def _positive6(name: str, value: ArrayLike) -> NDArray[np.float64]:
    arr = np.asarray(value, dtype=float)
    if arr.shape == ():
        arr = np.full(6, float(arr))
    if arr.shape != (6,) or not np.all(arr > 0.0):
        raise ParameterError(
            f"{name} must be > 0 on all six axes, got {np.asarray(value).tolist()}", field=name
        )
    return frozen_array(arr, (6,), name=name)


@dataclass(frozen=True)
class SafetyLimits:
    """The envelope. Vectors are per axis ``[x, y, z, rx, ry, rz]`` in the *base* frame.

    Attributes:
        max_twist: velocity limit [m/s, rad/s], shape (6,) or a scalar, > 0 (``inf`` allowed).
        max_twist_rate: acceleration limit [m/s^2, rad/s^2], shape (6,) or a scalar, > 0.
        max_travel: largest displacement from the start [m, rad], shape (6,) or a scalar, > 0.
        max_force_N: protective stop when the contact force's norm exceeds this [N].
        max_torque_Nm: protective stop when the contact torque's norm exceeds this [N*m].
        stale_after_s: a sample older than this (robot clock minus sample stamp) stops [s].
        max_repeated_samples: consecutive samples with an already seen time stamp tolerated
            (0: the first repeat stops; raise it when the sensor is slower than the loop);
            None: no count, a repeat is judged by its age alone (``stale_after_s``): a tick
            that comes late is not a fault, data older than the stale limit is. A live
            sensor whose packets jitter (a Net F/T over a network) needs None.
        max_identical_samples: consecutive *new* samples (fresh stamps) with bit-identical values
            tolerated before FROZEN_SAMPLE (a driver repeating a dead value with new stamps);
            None: no check. Set it only for a sensor whose noise makes identical readings
            unlikely (one count of noise on six channels: fewer than 1 in 200 pairs).
        sensor_range: the sensor's measuring range ``(force_N, torque_Nm)`` per axis; a raw
            reading at or beyond it is saturated and stops (SENSOR_SATURATED) even below the
            force limit. None: no check.
    """

    max_twist: NDArray[np.float64] = param(
        gt=0.0, length=6, allow_inf=True, unit="m/s, rad/s", help="speed limit"
    )
    max_twist_rate: NDArray[np.float64] = param(
        gt=0.0, length=6, allow_inf=True, unit="m/s^2, rad/s^2", help="acceleration limit"
    )
    max_travel: NDArray[np.float64] = param(
        gt=0.0, length=6, allow_inf=True, unit="m, rad", help="largest travel per axis"
    )
    max_force_N: float = param(gt=0.0, allow_inf=True, unit="N", help="protective stop above")
    max_torque_Nm: float = param(gt=0.0, allow_inf=True, unit="N*m", help="protective stop above")
    stale_after_s: float = param(
        gt=0.0, allow_inf=True, unit="s", help="a reading older than this stops"
    )
    max_repeated_samples: int | None = param(
        0,
        ge=0,
        integer=True,
        optional=True,
        help="samples with an already seen time stamp tolerated in a row",
    )
    max_identical_samples: int | None = param(
        None,
        ge=1,
        integer=True,
        optional=True,
        help="new readings identical to the last that stop as a frozen sensor, beyond this many",
    )
    sensor_range: tuple[float, float] | None = None
    # sensor_range per axis, [F, F, F, T, T, T], prepared once for check_range.
    _range_per_axis: NDArray[np.float64] | None = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name in ("max_twist", "max_twist_rate", "max_travel"):
            object.__setattr__(self, name, _positive6(name, getattr(self, name)))
        check_fields(
            self,
            (
                "max_force_N",
                "max_torque_Nm",
                "stale_after_s",
                "max_repeated_samples",
                "max_identical_samples",
            ),
        )
        r = self.sensor_range
        if r is not None:
            check_value("sensor_range", SENSOR_RANGE, r)
        per_axis = None if r is None else frozen_array(np.repeat(r, 3), (6,), name="sensor_range")
        object.__setattr__(self, "_range_per_axis", per_axis)


@dataclass(frozen=True)
class UniformLimits:
    """A safety envelope given as one limit on x, y and z and one on every rotation (``ftcomp
    run``'s): :meth:`safety_limits` makes the per-axis :class:`SafetyLimits`, the rotation's
    speed and acceleration those of :data:`MAX_ROTATION_SPEED_RAD_S` and
    :data:`MAX_ROTATION_ACCEL_RAD_S2`. Units are SI; each field's range is declared with it.

    Attributes:
        max_speed_m_s: speed limit on x, y, z [m/s].
        max_accel_m_s2: acceleration limit on x, y, z [m/s^2].
        max_travel_m: largest travel on x, y, z from the start [m].
        max_rotation_rad: largest rotation about each axis from the start [rad].
        max_force_N, max_torque_Nm, stale_after_s, max_repeated_samples, max_identical_samples:
            as :class:`SafetyLimits`' (no count of repeated stamps by default: a late tick is no
            fault, data older than ``stale_after_s`` is).
    """

    max_speed_m_s: float = param(0.02, gt=0.0, unit="m/s", help="speed limit")
    max_accel_m_s2: float = param(0.5, gt=0.0, unit="m/s^2", help="acceleration limit")
    max_travel_m: float = param(0.02, gt=0.0, unit="m", help="largest travel per axis")
    max_rotation_rad: float = param(
        math.radians(5.0), gt=0.0, unit="rad", help="largest rotation per axis"
    )
    max_force_N: float = param(40.0, gt=0.0, unit="N", help="protective stop above")
    max_torque_Nm: float = param(8.0, gt=0.0, unit="N*m", help="protective stop above")
    stale_after_s: float = param(0.02, gt=0.0, unit="s", help="a reading older than this stops")
    max_repeated_samples: int | None = param(
        None,
        ge=0,
        integer=True,
        optional=True,
        help="samples with an already seen time stamp tolerated in a row",
    )
    max_identical_samples: int | None = param(
        5,
        ge=1,
        integer=True,
        optional=True,
        help="new readings identical to the last that stop as a frozen sensor, beyond this many",
    )

    def __post_init__(self) -> None:
        check_fields(self)

    def safety_limits(self, sensor_range: tuple[float, float] | None = None) -> SafetyLimits:
        """The per-axis envelope (base-frame axes), with the sensor's range if given."""
        return SafetyLimits(
            max_twist=np.array([self.max_speed_m_s] * 3 + [MAX_ROTATION_SPEED_RAD_S] * 3),
            max_twist_rate=np.array([self.max_accel_m_s2] * 3 + [MAX_ROTATION_ACCEL_RAD_S2] * 3),
            max_travel=np.array([self.max_travel_m] * 3 + [self.max_rotation_rad] * 3),
            max_force_N=self.max_force_N,
            max_torque_Nm=self.max_torque_Nm,
            stale_after_s=self.stale_after_s,
            max_repeated_samples=self.max_repeated_samples,
            max_identical_samples=self.max_identical_samples,
            sensor_range=sensor_range,
        )


class WatchdogState(NamedTuple):
    """What the watchdog remembers between periods.

    Attributes:
        last_t: last accepted sample stamp [s] (``-inf`` before the first).
        repeats: consecutive samples with an already seen stamp.
        last_now: the robot clock at the last period [s] (``-inf`` before the first).
        identical: consecutive new samples with the same values as ``last_wrench``.
        last_wrench: the last accepted sample's values (empty before the first).
    """

    last_t: float = -math.inf
    repeats: int = 0
    last_now: float = -math.inf
    identical: int = 0
    last_wrench: tuple[float, ...] = ()


def _vector6(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """``value`` as a float array of shape (6,) (not copied when it already is one)."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != (6,):
        raise ParameterError(f"{name} must have shape (6,), got {arr.shape}")
    return arr


def check_sample(
    limits: SafetyLimits,
    state: WatchdogState,
    t_sample: float,
    wrench: ArrayLike,
    now: float,
) -> tuple[WatchdogState, StopReason | None]:
    """Judge one sample: a robot clock that is not finite or goes backwards, non-finite values
    or stamp, a repeated or older stamp, a stale one, or a value frozen under fresh stamps.

    Args:
        limits: the envelope.
        state: watchdog state from the previous sample.
        t_sample: the sample's stamp [s].
        wrench: the sample's wrench, shape (6,) (any frame).
        now: the robot's clock [s].

    Returns:
        ``(new_state, reason)``; ``reason`` is None when the sample may be used.
    """
    # A clock that is NaN or runs backwards would disable the stale check: stop instead.
    if not (now >= state.last_now and math.isfinite(now)):
        return state, StopReason.CLOCK_FAULT
    values = tuple(np.asarray(wrench, dtype=float).ravel().tolist())
    if not (math.isfinite(t_sample) and all(map(math.isfinite, values))):
        return state, StopReason.NON_FINITE_SAMPLE
    if t_sample <= state.last_t:
        repeats = state.repeats + 1
        new = state._replace(repeats=repeats, last_now=now)
        m = limits.max_repeated_samples
        if m is not None and repeats > m:
            return new, StopReason.REPEATED_SAMPLE
        if now - state.last_t > limits.stale_after_s:
            return new, StopReason.STALE_SAMPLE
        return new, None
    if now - t_sample > limits.stale_after_s:
        return state, StopReason.STALE_SAMPLE
    identical = state.identical + 1 if values == state.last_wrench else 0
    new = WatchdogState(t_sample, 0, now, identical, values)
    if limits.max_identical_samples is not None and identical > limits.max_identical_samples:
        return new, StopReason.FROZEN_SAMPLE
    return new, None


def check_range(limits: SafetyLimits, wrench_raw: ArrayLike) -> StopReason | None:
    """SENSOR_SATURATED when a raw reading is at or beyond the sensor's range on any axis.

    Args:
        limits: the envelope; without ``sensor_range`` nothing is checked.
        wrench_raw: the uncompensated reading [N, N*m], sensor frame, shape (6,).
    """
    if limits._range_per_axis is None:
        return None
    if (abs(_vector6(wrench_raw, "wrench_raw")) >= limits._range_per_axis).any():
        return StopReason.SENSOR_SATURATED
    return None


def check_wrench(limits: SafetyLimits, wrench: ArrayLike) -> StopReason | None:
    """FORCE_LIMIT or TORQUE_LIMIT when the contact wrench's force or torque norm is too large.

    Args:
        limits: the envelope.
        wrench: the contact wrench [N, N*m], any frame, shape (6,).
    """
    fx, fy, fz, tx, ty, tz = _vector6(wrench, "wrench").tolist()
    if math.hypot(fx, fy, fz) > limits.max_force_N:
        return StopReason.FORCE_LIMIT
    if math.hypot(tx, ty, tz) > limits.max_torque_Nm:
        return StopReason.TORQUE_LIMIT
    return None


def limit_twist(
    limits: SafetyLimits,
    twist_cmd: ArrayLike,
    twist_prev: ArrayLike,
    dt: float,
) -> NDArray[np.float64]:
    """Clamp a twist per axis to the velocity limit, then its change to ``max_twist_rate * dt``.

    Args:
        limits: the envelope.
        twist_cmd: wanted twist [m/s, rad/s], base frame, shape (6,).
        twist_prev: twist commanded in the previous period, shape (6,).
        dt: period [s], > 0.

    Returns:
        The twist to command, shape (6,).
    """
    if not dt > 0.0:
        raise ParameterError(f"dt must be > 0 s, got {dt}")
    prev = _vector6(twist_prev, "twist_prev")
    twist = _vector6(twist_cmd, "twist_cmd").clip(-limits.max_twist, limits.max_twist)
    rate_step = limits.max_twist_rate * dt
    return twist.clip(prev - rate_step, prev + rate_step)


def check_travel(
    limits: SafetyLimits, travel: ArrayLike, twist: ArrayLike, dt: float
) -> tuple[NDArray[np.float64], StopReason | None]:
    """Integrate the commanded twist into the travel from the start; stop before leaving it.

    Args:
        limits: the envelope.
        travel: displacement commanded so far [m, rad], base frame, shape (6,).
        twist: twist about to be commanded, shape (6,).
        dt: period [s].

    Returns:
        ``(new_travel, reason)``: with TRAVEL_LIMIT the travel is left unchanged (the twist must
        not be sent).
    """
    current = _vector6(travel, "travel")
    new = current + _vector6(twist, "twist") * dt
    if (abs(new) > limits.max_travel).any():
        return current, StopReason.TRAVEL_LIMIT
    return new, None
