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
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

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
    FORCE_LIMIT = "force_limit"
    TORQUE_LIMIT = "torque_limit"
    TRAVEL_LIMIT = "travel_limit"


def _frozen6(name: str, value: ArrayLike) -> NDArray[np.float64]:
    arr = np.array(value, dtype=float)
    if arr.shape == ():
        arr = np.full(6, float(arr))
    if arr.shape != (6,) or not np.all(arr > 0.0):
        raise ParameterError(
            f"{name} must be > 0 on all six axes, got {np.asarray(value).tolist()}"
        )
    arr.setflags(write=False)
    return arr


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
    """

    max_twist: NDArray[np.float64]
    max_twist_rate: NDArray[np.float64]
    max_travel: NDArray[np.float64]
    max_force_N: float
    max_torque_Nm: float
    stale_after_s: float
    max_repeated_samples: int = 0

    def __post_init__(self) -> None:
        for name in ("max_twist", "max_twist_rate", "max_travel"):
            object.__setattr__(self, name, _frozen6(name, getattr(self, name)))
        for name in ("max_force_N", "max_torque_Nm", "stale_after_s"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value > 0.0 and not math.isnan(value)):
                raise ParameterError(f"{name} must be > 0, got {value!r}")
        if not (isinstance(self.max_repeated_samples, int) and self.max_repeated_samples >= 0):
            raise ParameterError(
                f"max_repeated_samples must be an integer >= 0, got {self.max_repeated_samples!r}"
            )


class WatchdogState(NamedTuple):
    """Last accepted sample stamp [s] (``-inf`` before the first) and the current repeat count."""

    last_t: float = -math.inf
    repeats: int = 0


def check_sample(
    limits: SafetyLimits,
    state: WatchdogState,
    t_sample: float,
    wrench: ArrayLike,
    now: float,
) -> tuple[WatchdogState, StopReason | None]:
    """Judge one sample: non-finite values or stamp, a repeated or older stamp, or a stale one.

    Args:
        limits: the envelope.
        state: watchdog state from the previous sample.
        t_sample: the sample's stamp [s].
        wrench: the sample's wrench, shape (6,) (any frame).
        now: the robot's clock [s].

    Returns:
        ``(new_state, reason)``; ``reason`` is None when the sample may be used.
    """
    if not (math.isfinite(t_sample) and np.all(np.isfinite(wrench))):
        return state, StopReason.NON_FINITE_SAMPLE
    if t_sample <= state.last_t:
        repeats = state.repeats + 1
        new = WatchdogState(state.last_t, repeats)
        if repeats > limits.max_repeated_samples:
            return new, StopReason.REPEATED_SAMPLE
        if now - state.last_t > limits.stale_after_s:
            return new, StopReason.STALE_SAMPLE
        return new, None
    if now - t_sample > limits.stale_after_s:
        return state, StopReason.STALE_SAMPLE
    return WatchdogState(t_sample, 0), None


def check_wrench(limits: SafetyLimits, wrench: ArrayLike) -> StopReason | None:
    """FORCE_LIMIT or TORQUE_LIMIT when the contact wrench's force or torque norm is too large."""
    w = np.asarray(wrench, dtype=float)
    if float(np.linalg.norm(w[:3])) > limits.max_force_N:
        return StopReason.FORCE_LIMIT
    if float(np.linalg.norm(w[3:])) > limits.max_torque_Nm:
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
    prev = np.asarray(twist_prev, dtype=float)
    v = np.clip(np.asarray(twist_cmd, dtype=float), -limits.max_twist, limits.max_twist)
    step = limits.max_twist_rate * dt
    return np.clip(v, prev - step, prev + step)


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
    new = current + np.asarray(twist, dtype=float) * dt
    if np.any(np.abs(new) > limits.max_travel):
        return current, StopReason.TRAVEL_LIMIT
    return new, None
