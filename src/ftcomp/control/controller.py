"""An admittance controller: watchdog, filter, law and safety envelope in one pure step.

Per control period, given the *contact* wrench (the compensated reading, sensor frame, see
:mod:`ftcomp.compensation`) and the sensor's orientation::

    watchdog(sample) -> force/torque limit (raw) -> low-pass (sensor frame)
    -> rotate to the control frame -> ΔF = wrench - wrench_desired -> law -> twist
    -> twist to the base frame -> velocity/acceleration limits -> travel limit -> twist_base

``frame`` (required, no default) names the control frame: ``"base"`` (gains and selection act on
base-frame axes, e.g. S = z for gravity) or ``"sensor"`` (tool axes). Wrenches are rotated with
``R_base_sensor`` (torques stay about the sensor origin); twists are of the sensor origin.

The step is a pure function of ``(state, inputs)``: it neither reads a clock nor talks to the
robot, so it replays a recorded log exactly. A stop latches: every later step returns a zero twist
and the same ``stop_reason``.

The step is the 1 kHz path of every loop, so it is lean: the constants (gains with S folded in,
limits, filter coefficients, ``wrench_desired``) are prepared as floats in ``__post_init__``; a
step converts its inputs to Python floats once, computes on floats written out per axis (a numpy
operation on six numbers costs about a microsecond, a float operation a few tens of nanoseconds)
and puts the arrays of the new state in one new buffer. It never writes into the state it was
given. ``bench/bench_control.py`` times it against the straightforward numpy version.
"""

from __future__ import annotations

import functools
import math
import struct
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.arrays import frozen_array
from ftcomp.control.filters import LowPassFilter
from ftcomp.control.laws import (
    AdmittanceLaw,
    LawState,
    _rate_gains_of,
    _rate_step,
    _RateGains,
)
from ftcomp.control.safety import (
    SafetyLimits,
    StopReason,
    WatchdogState,
    _check_sample,
    _check_travel,
    _check_wrench,
    _limit_twist,
    _saturated,
)
from ftcomp.errors import ParameterError

__all__ = ["AdmittanceController", "ControlFrame", "ControllerState"]

ControlFrame = Literal["base", "sensor"]


class ControllerState(NamedTuple):
    """Everything the controller carries from one period to the next.

    Attributes:
        law: the law's state (offset, twist and wrench error in the control frame).
        filter: the low-pass filter's state.
        watchdog: last sample stamp and repeat count.
        wrench_filtered_sensor: last filtered contact wrench [N, N*m], sensor frame, (6,).
        twist_base: last twist commanded [m/s, rad/s], base frame, (6,).
        travel_base: displacement commanded since the start [m, rad], base frame, (6,).
        stop_reason: None while running; why it stopped otherwise (latched).
    """

    law: LawState
    filter: NDArray[np.float64]
    watchdog: WatchdogState
    wrench_filtered_sensor: NDArray[np.float64]
    twist_base: NDArray[np.float64]
    travel_base: NDArray[np.float64]
    stop_reason: StopReason | None


def _floats(value: ArrayLike, shape: tuple[int, ...], name: str) -> list[Any]:
    """``value`` as (nested) lists of Python floats, after checking its shape."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape:
        raise ParameterError(f"{name} must have shape {shape}, got {arr.shape}")
    return arr.tolist()


@functools.cache
def _packer(n_floats: int) -> Callable[..., bytes]:
    """``pack(*floats) -> bytes`` of ``n_floats`` doubles (kept here: a Struct does not pickle)."""
    return struct.Struct(f"{n_floats}d").pack


def _rotate6(R: Sequence[Sequence[float]], v: Sequence[float]) -> list[float]:
    """``[R @ v[:3], R @ v[3:]]`` on floats, R as three rows."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R
    f0, f1, f2, m0, m1, m2 = v
    return [
        r00 * f0 + r01 * f1 + r02 * f2,
        r10 * f0 + r11 * f1 + r12 * f2,
        r20 * f0 + r21 * f1 + r22 * f2,
        r00 * m0 + r01 * m1 + r02 * m2,
        r10 * m0 + r11 * m1 + r12 * m2,
        r20 * m0 + r21 * m1 + r22 * m2,
    ]


@dataclass(frozen=True)
class AdmittanceController:
    """Admittance law + wrench filter + safety envelope.

    Attributes:
        law: any :class:`~ftcomp.control.laws.AdmittanceLaw`. :class:`CombinedLaw`,
            :class:`PositionLaw` and :class:`VelocityLaw` are stepped on floats, any other law
            through its own ``step``.
        wrench_filter: low-pass on the contact wrench (its ``period_s`` should be the control
            period), or None for no filtering.
        limits: the safety envelope (base-frame axes).
        frame: the control frame of the law's gains, selection and ``wrench_desired``.
        wrench_desired: F0 [N, N*m] in the control frame, shape (6,); zeros by default.
    """

    law: AdmittanceLaw
    wrench_filter: LowPassFilter | None
    limits: SafetyLimits
    frame: ControlFrame
    wrench_desired: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    # Prepared in __post_init__ for the step: (S K1, S K2) as floats or None, F0 as floats,
    # and the size of the new state's buffer (see ``step``).
    _rate_gains: _RateGains | None = field(init=False, repr=False, compare=False)
    _wrench_desired: tuple[float, ...] = field(init=False, repr=False, compare=False)
    _n_floats: int = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.frame not in ("base", "sensor"):
            raise ParameterError(f"frame must be 'base' or 'sensor', got {self.frame!r}")
        w = np.array(self.wrench_desired, dtype=float)
        if w.shape != (6,) or not np.all(np.isfinite(w)):
            raise ParameterError(f"wrench_desired must be 6 finite values, got {w.tolist()}")
        w = frozen_array(w, (6,), name="wrench_desired")
        object.__setattr__(self, "wrench_desired", w)
        object.__setattr__(self, "_wrench_desired", tuple(w.tolist()))
        if self.wrench_filter is not None and self.wrench_filter.channels != 6:
            raise ParameterError("wrench_filter must filter 6 channels")
        gains = _rate_gains_of(self.law)
        object.__setattr__(self, "_rate_gains", gains)
        n_floats = 18 + (18 if gains is not None else 0)
        if self.wrench_filter is not None:
            n_floats += 12 * len(self.wrench_filter.sos)
        object.__setattr__(self, "_n_floats", n_floats)

    def _wrench_error(self, w_sensor: Sequence[float], R: Sequence[Sequence[float]]) -> list[float]:
        """ΔF on floats: ``w_sensor`` rotated to the control frame minus ``wrench_desired``."""
        w0, w1, w2, w3, w4, w5 = _rotate6(R, w_sensor) if self.frame == "base" else w_sensor
        d0, d1, d2, d3, d4, d5 = self._wrench_desired
        return [w0 - d0, w1 - d1, w2 - d2, w3 - d3, w4 - d4, w5 - d5]

    def wrench_error(
        self, wrench_sensor: ArrayLike, R_base_sensor: ArrayLike
    ) -> NDArray[np.float64]:
        """ΔF = wrench (rotated to the control frame) - wrench_desired, shape (6,)."""
        w = _floats(wrench_sensor, (6,), "wrench_sensor")
        R = _floats(R_base_sensor, (3, 3), "R_base_sensor")
        return np.array(self._wrench_error(w, R))

    def initial_state(
        self, wrench_contact_sensor: ArrayLike, R_base_sensor: ArrayLike
    ) -> ControllerState:
        """Start at rest, bumpless: the filter and the law's derivative begin at this wrench.

        Args:
            wrench_contact_sensor: the contact wrench now [N, N*m], sensor frame, shape (6,),
                finite.
            R_base_sensor: the sensor's orientation now, shape (3, 3).
        """
        w = np.array(wrench_contact_sensor, dtype=float)
        if w.shape != (6,) or not np.all(np.isfinite(w)):
            raise ParameterError(
                f"the initial contact wrench must be 6 finite values, got {w.tolist()}"
            )
        zi = (
            self.wrench_filter.initial_state(w)
            if self.wrench_filter is not None
            else np.zeros((0, 2, 6))
        )
        return ControllerState(
            law=self.law.initial_state(self.wrench_error(w, R_base_sensor)),
            filter=zi,
            watchdog=WatchdogState(),
            wrench_filtered_sensor=w,
            twist_base=np.zeros(6),
            travel_base=np.zeros(6),
            stop_reason=None,
        )

    def step(
        self,
        state: ControllerState,
        t_sample: float,
        wrench_contact_sensor: ArrayLike,
        R_base_sensor: ArrayLike,
        now: float,
        dt: float,
        twist_nominal_base: ArrayLike | None = None,
        *,
        wrench_raw_sensor: ArrayLike | None = None,
    ) -> tuple[ControllerState, NDArray[np.float64]]:
        """One control period; never raises and never returns a non-finite twist.

        Args:
            state: from :meth:`initial_state` or the previous step; not modified.
            t_sample: the sample's stamp [s].
            wrench_contact_sensor: compensated wrench [N, N*m], sensor frame, shape (6,); may be
                non-finite (the watchdog stops).
            R_base_sensor: the sensor's orientation now, shape (3, 3).
            now: the robot's clock [s].
            dt: control period [s], > 0.
            twist_nominal_base: planned motion [m/s, rad/s], base frame, shape (6,), that the
                law's ΔV is added to (the paper's ΔV is an offset); None: standing still.
            wrench_raw_sensor: the uncompensated reading, shape (6,), if the caller has it: the
                frozen-value check then looks at it, and it is checked against the sensor's
                range (``limits.sensor_range``).

        Returns:
            ``(new_state, twist_base)`` [m/s, rad/s], base frame, shape (6,); zeros once
            ``new_state.stop_reason`` is set. Any bad input stops in this period: a wrench of
            the wrong shape, a non-positive or non-finite ``dt`` (INVALID_INPUT), a non-finite
            orientation or nominal twist (NON_FINITE_POSE), a robot clock that is NaN or runs
            backwards (CLOCK_FAULT); see the fault table in ``docs/control.md``.
        """
        if state.stop_reason is not None:
            return state, np.zeros(6)
        try:
            return self._step(
                state,
                t_sample,
                wrench_contact_sensor,
                R_base_sensor,
                now,
                dt,
                twist_nominal_base,
                wrench_raw_sensor,
            )
        except Exception:  # an input no check foresaw: stop rather than raise or move
            return self._stopped(state, state.watchdog, StopReason.INVALID_INPUT), np.zeros(6)

    def _step(
        self,
        state: ControllerState,
        t_sample: float,
        wrench_contact_sensor: ArrayLike,
        R_base_sensor: ArrayLike,
        now: float,
        dt: float,
        twist_nominal_base: ArrayLike | None,
        wrench_raw_sensor: ArrayLike | None,
    ) -> tuple[ControllerState, NDArray[np.float64]]:
        """:meth:`step` once the latch is checked; may raise on inputs of the wrong type."""
        limits = self.limits
        w = _floats(wrench_contact_sensor, (6,), "wrench_contact_sensor")
        raw = None if wrench_raw_sensor is None else _floats(wrench_raw_sensor, (6,), "raw")
        watched = w if raw is None else raw
        watchdog, reason = _check_sample(limits, state.watchdog, float(t_sample), watched, now)
        if reason is None and raw is not None and not all(map(math.isfinite, w)):
            reason = StopReason.NON_FINITE_SAMPLE
        if reason is None and raw is not None and _saturated(limits, raw):
            reason = StopReason.SENSOR_SATURATED
        if reason is None:
            reason = _check_wrench(limits, w)
        if reason is None and not (dt > 0.0 and math.isfinite(dt)):
            reason = StopReason.INVALID_INPUT
        if reason is not None:
            return self._stopped(state, watchdog, reason), np.zeros(6)
        R = _floats(R_base_sensor, (3, 3), "R_base_sensor")
        nominal = (
            None
            if twist_nominal_base is None
            else _floats(twist_nominal_base, (6,), "twist_nominal_base")
        )
        if not math.isfinite(sum(R[0]) + sum(R[1]) + sum(R[2])) or (
            nominal is not None and not math.isfinite(sum(nominal))
        ):
            return self._stopped(state, watchdog, StopReason.NON_FINITE_POSE), np.zeros(6)
        if watchdog.repeats > 0:  # tolerated repeat: nothing new to filter, hold the command
            return state._replace(watchdog=watchdog), state.twist_base
        if self.wrench_filter is not None:
            zi, w_filt = self.wrench_filter._step6(state.filter.tolist(), w)
        else:
            zi, w_filt = [], w
        e = self._wrench_error(w_filt, R)
        law_state: LawState | None = None
        if self._rate_gains is not None:
            law = state.law
            offset, twist = _rate_step(
                self._rate_gains, law.offset.tolist(), law.wrench_error.tolist(), e, dt
            )
            law_rows = [*offset, *twist, *e]
        else:  # another law: its own step, on arrays
            law_state, twist_array = self.law.step(state.law, np.array(e), dt)
            twist, law_rows = twist_array.tolist(), []
        twist_base = twist if self.frame == "base" else _rotate6(R, twist)
        if nominal is not None:
            v0, v1, v2, v3, v4, v5 = twist_base
            n0, n1, n2, n3, n4, n5 = nominal
            twist_base = [v0 + n0, v1 + n1, v2 + n2, v3 + n3, v4 + n4, v5 + n5]
        twist_base = _limit_twist(limits, twist_base, state.twist_base.tolist(), dt)
        if not math.isfinite(sum(twist_base)):  # the last guard: never command a NaN
            return self._stopped(state, watchdog, StopReason.NON_FINITE_COMMAND), np.zeros(6)
        travel, reason = _check_travel(limits, state.travel_base.tolist(), twist_base, dt)
        # The new state's arrays are slices of one new buffer: one allocation instead of seven
        # (np.array on six floats costs about as much as packing them all). The layout:
        # w_filt, twist_base, travel, [the law's offset, twist, e], [the filter's state].
        pack = _packer(self._n_floats)
        buf = np.frombuffer(bytearray(pack(*w_filt, *twist_base, *travel, *law_rows, *zi)))
        if law_state is None:
            law_state = LawState(buf[18:24], buf[24:30], buf[30:36])
        zi_new = buf[len(buf) - len(zi) :].reshape(state.filter.shape)
        if reason is not None:
            stopped = ControllerState(
                law_state, zi_new, watchdog, buf[0:6], np.zeros(6), state.travel_base, reason
            )
            return stopped, np.zeros(6)
        twist_out = buf[6:12]
        new = ControllerState(law_state, zi_new, watchdog, buf[0:6], twist_out, buf[12:18], None)
        return new, twist_out

    @staticmethod
    def _stopped(
        state: ControllerState, watchdog: WatchdogState, reason: StopReason
    ) -> ControllerState:
        return state._replace(watchdog=watchdog, twist_base=np.zeros(6), stop_reason=reason)
