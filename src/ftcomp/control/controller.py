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
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.control.filters import LowPassFilter
from ftcomp.control.laws import AdmittanceLaw, LawState
from ftcomp.control.safety import (
    SafetyLimits,
    StopReason,
    WatchdogState,
    check_sample,
    check_travel,
    check_wrench,
    limit_twist,
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


def _rotate6(R: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.concatenate([R @ v[:3], R @ v[3:]])


def _rotate6_inv(R: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.concatenate([R.T @ v[:3], R.T @ v[3:]])


@dataclass(frozen=True)
class AdmittanceController:
    """Admittance law + wrench filter + safety envelope.

    Attributes:
        law: any :class:`~ftcomp.control.laws.AdmittanceLaw`.
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
        if self.frame not in ("base", "sensor"):
            raise ParameterError(f"frame must be 'base' or 'sensor', got {self.frame!r}")
        w = np.array(self.wrench_desired, dtype=float)
        if w.shape != (6,) or not np.all(np.isfinite(w)):
            raise ParameterError(f"wrench_desired must be 6 finite values, got {w.tolist()}")
        w.setflags(write=False)
        object.__setattr__(self, "wrench_desired", w)
        if self.wrench_filter is not None and self.wrench_filter.channels != 6:
            raise ParameterError("wrench_filter must filter 6 channels")

    def _to_control(
        self, w_sensor: NDArray[np.float64], R: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        return _rotate6(R, w_sensor) if self.frame == "base" else w_sensor

    def _twist_to_base(
        self, twist: NDArray[np.float64], R: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        return twist if self.frame == "base" else _rotate6(R, twist)

    def wrench_error(
        self, wrench_sensor: ArrayLike, R_base_sensor: ArrayLike
    ) -> NDArray[np.float64]:
        """ΔF = wrench (rotated to the control frame) - wrench_desired, shape (6,)."""
        w = np.asarray(wrench_sensor, dtype=float)
        R = np.asarray(R_base_sensor, dtype=float)
        return self._to_control(w, R) - self.wrench_desired

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
    ) -> tuple[ControllerState, NDArray[np.float64]]:
        """One control period.

        Args:
            state: from :meth:`initial_state` or the previous step.
            t_sample: the sample's stamp [s].
            wrench_contact_sensor: compensated wrench [N, N*m], sensor frame, shape (6,); may be
                non-finite (the watchdog stops).
            R_base_sensor: the sensor's orientation now, shape (3, 3).
            now: the robot's clock [s].
            dt: control period [s], > 0.
            twist_nominal_base: planned motion [m/s, rad/s], base frame, shape (6,), that the
                law's ΔV is added to (the paper's ΔV is an offset); None: standing still.

        Returns:
            ``(new_state, twist_base)`` [m/s, rad/s], base frame, shape (6,); zeros once
            ``new_state.stop_reason`` is set. Never raises on bad sensor data.
        """
        if state.stop_reason is not None:
            return state, np.zeros(6)
        w = np.asarray(wrench_contact_sensor, dtype=float)
        watchdog, reason = check_sample(self.limits, state.watchdog, t_sample, w, now)
        if reason is None:
            reason = check_wrench(self.limits, w)
        if reason is not None:
            return self._stopped(state, watchdog, reason), np.zeros(6)
        if watchdog.repeats > 0:  # tolerated repeat: nothing new to filter, hold the command
            return state._replace(watchdog=watchdog), state.twist_base
        R = np.asarray(R_base_sensor, dtype=float)
        if self.wrench_filter is not None:
            zi, w_filt = self.wrench_filter.step(state.filter, w)
        else:
            zi, w_filt = state.filter, w
        law_state, twist = self.law.step(
            state.law, self._to_control(w_filt, R) - self.wrench_desired, dt
        )
        twist_base = self._twist_to_base(twist, R)
        if twist_nominal_base is not None:
            twist_base = twist_base + np.asarray(twist_nominal_base, dtype=float)
        twist_base = limit_twist(self.limits, twist_base, state.twist_base, dt)
        travel, reason = check_travel(self.limits, state.travel_base, twist_base, dt)
        new = ControllerState(law_state, zi, watchdog, w_filt, twist_base, travel, None)
        if reason is not None:
            return self._stopped(new, watchdog, reason), np.zeros(6)
        return new, twist_base

    @staticmethod
    def _stopped(
        state: ControllerState, watchdog: WatchdogState, reason: StopReason
    ) -> ControllerState:
        return state._replace(watchdog=watchdog, twist_base=np.zeros(6), stop_reason=reason)
