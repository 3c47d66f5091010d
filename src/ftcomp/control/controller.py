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

**The error the law acted on is part of the state.** After ``state, twist = controller.step(...)``,
``state.law.wrench_error`` is the filtered wrench error ΔF in the control frame that the law turned
into ``twist`` (for every law). A log that records it needs no second computation of the error,
and replaying the log through the step reproduces the commands.

The step is the 1 kHz path of every loop, written plainly: each law, filter and safety check is
called through its one public implementation (:mod:`ftcomp.control.laws`,
:mod:`ftcomp.control.filters`, :mod:`ftcomp.control.safety`) on (6,) arrays; it never writes into
the state it was given. ``bench/bench_cycle.py`` shows what it costs within a whole cycle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.arrays import frozen_array
from ftcomp.control.filters import LowPassFilter
from ftcomp.control.laws import AdmittanceLaw, LawState
from ftcomp.control.safety import (
    SafetyLimits,
    StopReason,
    WatchdogState,
    check_range,
    check_sample,
    check_travel,
    check_wrench,
    limit_twist,
)
from ftcomp.errors import ParameterError

__all__ = ["CONTROL_FRAMES", "AdmittanceController", "ControlFrame", "ControllerState"]

ControlFrame = Literal["base", "sensor"]
#: The control frames a controller can act in.
CONTROL_FRAMES: tuple[ControlFrame, ...] = ("base", "sensor")


class ControllerState(NamedTuple):
    """Everything the controller carries from one period to the next.

    Attributes:
        law: the law's state in the control frame: ``law.wrench_error`` is the filtered wrench
            error [N, N*m] the law acted on, the one that produced the twist returned with this
            state (see the module docstring; a period that stops returns a zero twist whatever
            it holds); also ``law.offset`` and ``law.twist``.
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


def _array(value: ArrayLike, shape: tuple[int, ...], name: str) -> NDArray[np.float64]:
    """``value`` as a float array (not copied if it is one), after checking its shape."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape:
        raise ParameterError(f"{name} must have shape {shape}, got {arr.shape}")
    return arr


def _all_finite(arr: NDArray[np.float64]) -> bool:
    """Whether every value is finite (on a few values, cheaper than ``np.isfinite().all()``)."""
    return all(map(math.isfinite, arr.ravel().tolist()))


def _rotate6(R: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    """``[R @ v[:3], R @ v[3:]]``: a wrench or twist rotated by R, shape (6,)."""
    return (v.reshape(2, 3) @ R.T).ravel()


@dataclass(frozen=True)
class AdmittanceController:
    """Admittance law + wrench filter + safety envelope.

    Attributes:
        law: any :class:`~ftcomp.control.laws.AdmittanceLaw`, stepped through its ``step``.
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

    def __post_init__(self) -> None:
        if self.frame not in CONTROL_FRAMES:
            raise ParameterError(f"frame must be 'base' or 'sensor', got {self.frame!r}")
        w = np.array(self.wrench_desired, dtype=float)
        if w.shape != (6,) or not np.all(np.isfinite(w)):
            raise ParameterError(f"wrench_desired must be 6 finite values, got {w.tolist()}")
        object.__setattr__(self, "wrench_desired", frozen_array(w, (6,), name="wrench_desired"))
        if self.wrench_filter is not None and self.wrench_filter.channels != 6:
            raise ParameterError("wrench_filter must filter 6 channels")

    def wrench_error(
        self, wrench_sensor: ArrayLike, R_base_sensor: ArrayLike
    ) -> NDArray[np.float64]:
        """ΔF = wrench (rotated to the control frame) - wrench_desired, shape (6,).

        Args:
            wrench_sensor: a wrench [N, N*m], sensor frame, shape (6,).
            R_base_sensor: the sensor's orientation, shape (3, 3).

        Returns:
            ΔF [N, N*m], control frame. The step computes the error it acts on with this method
            (on the filtered wrench) and keeps it in ``state.law.wrench_error``.
        """
        w = _array(wrench_sensor, (6,), "wrench_sensor")
        return self._error(w, _array(R_base_sensor, (3, 3), "R_base_sensor"))

    def _error(self, w: NDArray[np.float64], R: NDArray[np.float64]) -> NDArray[np.float64]:
        """:meth:`wrench_error` of arrays whose shapes are checked."""
        return (_rotate6(R, w) if self.frame == "base" else w) - self.wrench_desired

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
        w = _array(wrench_contact_sensor, (6,), "wrench_contact_sensor")
        raw = None if wrench_raw_sensor is None else _array(wrench_raw_sensor, (6,), "raw")
        watched = w if raw is None else raw
        watchdog, reason = check_sample(limits, state.watchdog, float(t_sample), watched, now)
        if reason is None and raw is not None:
            # The watchdog saw the raw reading, not the compensated one.
            reason = check_range(limits, raw) if _all_finite(w) else StopReason.NON_FINITE_SAMPLE
        if reason is None:
            reason = check_wrench(limits, w)
        if reason is None and not (dt > 0.0 and math.isfinite(dt)):
            reason = StopReason.INVALID_INPUT
        if reason is not None:
            return self._stopped(state, watchdog, reason), np.zeros(6)
        R = _array(R_base_sensor, (3, 3), "R_base_sensor")
        nominal = (
            None
            if twist_nominal_base is None
            else _array(twist_nominal_base, (6,), "twist_nominal_base")
        )
        if not _all_finite(R) or (nominal is not None and not _all_finite(nominal)):
            return self._stopped(state, watchdog, StopReason.NON_FINITE_POSE), np.zeros(6)
        if watchdog.repeats > 0:  # tolerated repeat: nothing new to filter, hold the command
            return state._replace(watchdog=watchdog), state.twist_base
        if self.wrench_filter is not None:
            zi, w_filt = self.wrench_filter.step(state.filter, w)
        else:
            zi, w_filt = state.filter, w.copy()  # the state keeps no array of the caller's
        e = self._error(w_filt, R)
        law_state, twist = self.law.step(state.law, e, dt)
        twist_base = twist if self.frame == "base" else _rotate6(R, twist)
        if nominal is not None:
            twist_base = twist_base + nominal
        twist_base = limit_twist(limits, twist_base, state.twist_base, dt)
        if not _all_finite(twist_base):  # the last guard: never command a NaN
            return self._stopped(state, watchdog, StopReason.NON_FINITE_COMMAND), np.zeros(6)
        travel, reason = check_travel(limits, state.travel_base, twist_base, dt)
        if reason is not None:
            stopped = ControllerState(
                law_state, zi, watchdog, w_filt, np.zeros(6), state.travel_base, reason
            )
            return stopped, np.zeros(6)
        return ControllerState(
            law_state, zi, watchdog, w_filt, twist_base, travel, None
        ), twist_base

    @staticmethod
    def _stopped(
        state: ControllerState, watchdog: WatchdogState, reason: StopReason
    ) -> ControllerState:
        return state._replace(watchdog=watchdog, twist_base=np.zeros(6), stop_reason=reason)
