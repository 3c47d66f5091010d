"""The safety envelope around an admittance law: limits, protective stops and a sample watchdog.

All functions are pure. The controller (:mod:`ftcomp.control.controller`) applies them each
period in this order: watchdog on the sample, force/torque limit on the *unfiltered* contact
wrench, then (after the law) velocity and acceleration limits on the twist, then the travel limit.
A stop is latched and zeroes the twist at once (not ramped by the acceleration limit): a
protective stop must act within the control period that saw the fault.

Gain changes are bumpless by construction: the position term of the laws is executed
incrementally (a new K1 acts on later force changes only) and the acceleration limit caps any
step a new K2 would cause in the command.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.arrays import frozen_array
from ftcomp.errors import ParameterError

__all__ = [
    "SafetyLimits",
    "StopReason",
    "WatchdogState",
    "check_sample",
    "check_travel",
    "check_wrench",
    "limit_twist",
]


class StopReason(str, enum.Enum):
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
            f"{name} must be > 0 on all six axes, got {np.asarray(value).tolist()}"
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
            (0: the first repeat stops; raise it when the sensor is slower than the loop).
        max_identical_samples: consecutive *new* samples (fresh stamps) with bit-identical values
            tolerated before FROZEN_SAMPLE (a driver repeating a dead value with new stamps);
            None: no check. Set it only for a sensor whose noise makes identical readings
            unlikely (one count of noise on six channels: fewer than 1 in 200 pairs).
        sensor_range: the sensor's measuring range ``(force_N, torque_Nm)`` per axis; a raw
            reading at or beyond it is saturated and stops (SENSOR_SATURATED) even below the
            force limit. None: no check.
    """

    max_twist: NDArray[np.float64]
    max_twist_rate: NDArray[np.float64]
    max_travel: NDArray[np.float64]
    max_force_N: float
    max_torque_Nm: float
    stale_after_s: float
    max_repeated_samples: int = 0
    max_identical_samples: int | None = None
    sensor_range: tuple[float, float] | None = None
    # The three vectors as floats, prepared once for the float kernels the controller calls.
    _max_twist: tuple[float, ...] = field(init=False, repr=False, compare=False)
    _max_twist_rate: tuple[float, ...] = field(init=False, repr=False, compare=False)
    _max_travel: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name in ("max_twist", "max_twist_rate", "max_travel"):
            arr = _positive6(name, getattr(self, name))
            object.__setattr__(self, name, arr)
            object.__setattr__(self, f"_{name}", tuple(arr.tolist()))
        for name in ("max_force_N", "max_torque_Nm", "stale_after_s"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value > 0.0 and not math.isnan(value)):
                raise ParameterError(f"{name} must be > 0, got {value!r}")
        if not (isinstance(self.max_repeated_samples, int) and self.max_repeated_samples >= 0):
            raise ParameterError(
                f"max_repeated_samples must be an integer >= 0, got {self.max_repeated_samples!r}"
            )
        n = self.max_identical_samples
        if n is not None and not (isinstance(n, int) and n >= 1):
            raise ParameterError(f"max_identical_samples must be an integer >= 1, got {n!r}")
        r = self.sensor_range
        if r is not None and not (
            len(r) == 2 and all(isinstance(v, (int, float)) and v > 0.0 for v in r)
        ):
            raise ParameterError(f"sensor_range must be (force_N, torque_Nm) > 0, got {r!r}")


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


def _floats(value: ArrayLike, name: str | None = None) -> list[float]:
    """``value`` as a flat list of floats; with a ``name``, it must have shape (6,)."""
    arr = np.asarray(value, dtype=float)
    if name is not None and arr.shape != (6,):
        raise ParameterError(f"{name} must have shape (6,), got {arr.shape}")
    return arr.ravel().tolist()


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
    return _check_sample(limits, state, t_sample, _floats(wrench), now)


def _check_sample(
    limits: SafetyLimits,
    state: WatchdogState,
    t_sample: float,
    wrench: Sequence[float],
    now: float,
) -> tuple[WatchdogState, StopReason | None]:
    """:func:`check_sample` on a list of floats (the controller's kernel)."""
    # A clock that is NaN or runs backwards would disable the stale check: stop instead.
    if not (now >= state.last_now and math.isfinite(now)):
        return state, StopReason.CLOCK_FAULT
    # One sum is finite exactly when every term is, unless finite terms overflow: then look closer.
    if not math.isfinite(t_sample + sum(wrench)) and not (
        math.isfinite(t_sample) and all(map(math.isfinite, wrench))
    ):
        return state, StopReason.NON_FINITE_SAMPLE
    if t_sample <= state.last_t:
        repeats = state.repeats + 1
        new = state._replace(repeats=repeats, last_now=now)
        if repeats > limits.max_repeated_samples:
            return new, StopReason.REPEATED_SAMPLE
        if now - state.last_t > limits.stale_after_s:
            return new, StopReason.STALE_SAMPLE
        return new, None
    if now - t_sample > limits.stale_after_s:
        return state, StopReason.STALE_SAMPLE
    values = tuple(wrench)
    identical = state.identical + 1 if values == state.last_wrench else 0
    new = WatchdogState(t_sample, 0, now, identical, values)
    if limits.max_identical_samples is not None and identical > limits.max_identical_samples:
        return new, StopReason.FROZEN_SAMPLE
    return new, None


def _saturated(limits: SafetyLimits, raw: Sequence[float]) -> bool:
    """Whether a raw reading is at or beyond the sensor's range on any axis."""
    if limits.sensor_range is None:
        return False
    force, torque = limits.sensor_range
    f0, f1, f2, t0, t1, t2 = raw
    return max(abs(f0), abs(f1), abs(f2)) >= force or max(abs(t0), abs(t1), abs(t2)) >= torque


def check_wrench(limits: SafetyLimits, wrench: ArrayLike) -> StopReason | None:
    """FORCE_LIMIT or TORQUE_LIMIT when the contact wrench's force or torque norm is too large."""
    return _check_wrench(limits, _floats(wrench, "wrench"))


def _check_wrench(limits: SafetyLimits, wrench: Sequence[float]) -> StopReason | None:
    """:func:`check_wrench` on six floats (the controller's kernel)."""
    fx, fy, fz, tx, ty, tz = wrench
    if math.sqrt(fx * fx + fy * fy + fz * fz) > limits.max_force_N:
        return StopReason.FORCE_LIMIT
    if math.sqrt(tx * tx + ty * ty + tz * tz) > limits.max_torque_Nm:
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
    cmd, prev = _floats(twist_cmd, "twist_cmd"), _floats(twist_prev, "twist_prev")
    return np.array(_limit_twist(limits, cmd, prev, dt))


def _limit_twist(
    limits: SafetyLimits, twist_cmd: Sequence[float], twist_prev: Sequence[float], dt: float
) -> list[float]:
    """:func:`limit_twist` on six floats each, ``dt`` already checked (the controller's kernel).

    Exactly :func:`numpy.clip` twice, written out per axis (a loop costs more than the clamps).
    A NaN or an infinity takes numpy's own clip, which passes a NaN through.
    """
    v0, v1, v2, v3, v4, v5 = twist_cmd
    p0, p1, p2, p3, p4, p5 = twist_prev
    if not math.isfinite(v0 + v1 + v2 + v3 + v4 + v5 + p0 + p1 + p2 + p3 + p4 + p5):
        prev = np.array(twist_prev, dtype=float)
        v = np.clip(np.array(twist_cmd, dtype=float), -limits.max_twist, limits.max_twist)
        step = limits.max_twist_rate * dt
        return np.clip(v, prev - step, prev + step).tolist()
    m0, m1, m2, m3, m4, m5 = limits._max_twist
    v0 = -m0 if v0 < -m0 else m0 if v0 > m0 else v0
    v1 = -m1 if v1 < -m1 else m1 if v1 > m1 else v1
    v2 = -m2 if v2 < -m2 else m2 if v2 > m2 else v2
    v3 = -m3 if v3 < -m3 else m3 if v3 > m3 else v3
    v4 = -m4 if v4 < -m4 else m4 if v4 > m4 else v4
    v5 = -m5 if v5 < -m5 else m5 if v5 > m5 else v5
    a0, a1, a2, a3, a4, a5 = limits._max_twist_rate
    s0, s1, s2, s3, s4, s5 = a0 * dt, a1 * dt, a2 * dt, a3 * dt, a4 * dt, a5 * dt
    return [
        p0 - s0 if v0 < p0 - s0 else p0 + s0 if v0 > p0 + s0 else v0,
        p1 - s1 if v1 < p1 - s1 else p1 + s1 if v1 > p1 + s1 else v1,
        p2 - s2 if v2 < p2 - s2 else p2 + s2 if v2 > p2 + s2 else v2,
        p3 - s3 if v3 < p3 - s3 else p3 + s3 if v3 > p3 + s3 else v3,
        p4 - s4 if v4 < p4 - s4 else p4 + s4 if v4 > p4 + s4 else v4,
        p5 - s5 if v5 < p5 - s5 else p5 + s5 if v5 > p5 + s5 else v5,
    ]


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
    current = np.asarray(travel, dtype=float)
    new, reason = _check_travel(limits, _floats(current, "travel"), _floats(twist, "twist"), dt)
    return (current, reason) if reason is not None else (np.array(new), None)


def _check_travel(
    limits: SafetyLimits, travel: Sequence[float], twist: Sequence[float], dt: float
) -> tuple[Sequence[float], StopReason | None]:
    """:func:`check_travel` on six floats each (the controller's kernel)."""
    x0, x1, x2, x3, x4, x5 = travel
    v0, v1, v2, v3, v4, v5 = twist
    x0, x1, x2, x3, x4, x5 = (
        x0 + v0 * dt,
        x1 + v1 * dt,
        x2 + v2 * dt,
        x3 + v3 * dt,
        x4 + v4 * dt,
        x5 + v5 * dt,
    )
    m0, m1, m2, m3, m4, m5 = limits._max_travel
    if abs(x0) > m0 or abs(x1) > m1 or abs(x2) > m2 or abs(x3) > m3 or abs(x4) > m4 or abs(x5) > m5:
        return travel, StopReason.TRAVEL_LIMIT
    return [x0, x1, x2, x3, x4, x5], None
