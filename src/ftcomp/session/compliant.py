"""The one compliant step: the admittance controller in a live loop, and when a run is done.

Every loop that moves an arm under force control runs this step, whatever it is for: ``ftcomp
run`` (:func:`ftcomp.session.run.run_compliant`), ``ftcomp sim place`` and the demo's placements
(:func:`ftcomp.session.placement.run_placement`). Per cycle, for a
:class:`~ftcomp.control.loop.Reading`:

1. the first reading starts the controller bumpless at its wrench
   (:meth:`~ftcomp.control.controller.AdmittanceController.initial_state`);
2. the controller steps once (watchdog, limits, filter, law, envelope): the wrench error it
   acted on is part of the state it returns, and that error, computed once, is what the cycle
   record carries, what the log writes and what the settle rule judges;
3. :class:`Settling` low-passes that error and says when the selected axes have stayed within
   the band long enough (:class:`SettleRule`);
4. ``on_cycle`` gets a :class:`CycleRecord` (the caller logs it);
5. the run ends (``None``) on its duration, a protective stop of the controller, a robot that
   keeps missing its period, or once settled (after ``SettleRule.then_hold_s`` more).

A dry run computes and records every command and sends a zero twist instead.

Because the step starts from the first reading it is given and is a pure function of the
readings after it, a run's log (every reading's stamps, wrenches and orientation) replays through
a new step to the same commands (``tests/session/test_run.py``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ftcomp.config_fields import check_fields, param
from ftcomp.control.controller import AdmittanceController, ControllerState
from ftcomp.control.filters import LowPassFilter
from ftcomp.control.loop import Reading
from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import ReportsLateness, Robot
from ftcomp.session.outcome import Outcome

__all__ = [
    "DEFAULT_HOLD_S",
    "DEFAULT_THEN_HOLD_S",
    "CompliantStep",
    "CycleRecord",
    "SettleRule",
    "Settling",
]

#: How long the force error must stay in the band by default [s]; also the window a run's
#: final error is averaged over without a settle rule.
DEFAULT_HOLD_S = 0.3
#: How long a run stays under control once settled by default [s]. The error enters the band
#: from one side and the rule judges it at once, so a run that ended there would leave up to
#: the band's width uncorrected; on a soft surface (the twin's sponge: 1 / (K2 * stiffness) =
#: 0.4 s with the paper's gains) a second more takes the rest down tenfold: placements of the
#: twin's Net F/T pair (5 Hz wrench filter, the truth's calibration) ended 0.015-0.030 N short
#: with 0 s, 0.004-0.012 N with 1 s (six runs each).
DEFAULT_THEN_HOLD_S = 1.0

#: Twist [m/s, rad/s] a caller adds to the law's (a planned motion), from the reading; None: none.
Nominal = Callable[[Reading], "NDArray[np.float64] | None"]


@dataclass(frozen=True)
class SettleRule:
    """When a compliant run is done: every selected force error, low-passed at ``cutoff_hz``,
    within ``band_N`` [N] of zero for ``hold_s`` [s]; then the run goes on under control for
    ``then_hold_s`` [s] (0: it ends at once; by default :data:`DEFAULT_THEN_HOLD_S`).

    The error judged is the one the controller acted on (control frame, after its own filter);
    the rule's slower filter only keeps sensor noise out of the decision.
    """

    band_N: float = param(
        gt=0.0, unit="N", help="end once the selected force error stays this small"
    )
    hold_s: float = param(DEFAULT_HOLD_S, gt=0.0, unit="s", help="... for this long")
    cutoff_hz: float = param(2.0, gt=0.0, unit="Hz", help="low-pass of the error judged")
    then_hold_s: float = param(
        DEFAULT_THEN_HOLD_S, ge=0.0, unit="s", help="control kept on after settling"
    )

    def __post_init__(self) -> None:
        check_fields(self)


class Settling:
    """:class:`SettleRule` applied to a run's wrench errors, one call per cycle.

    Args:
        rule: the rule.
        period_s: the control period [s] (the filter's sample time).
        selected: which of the six error axes count (the law's selection), shape (6,) bool.
        error0: the first error [N, N*m] (the filter starts there, bumpless).
    """

    def __init__(
        self,
        rule: SettleRule,
        period_s: float,
        selected: NDArray[np.bool_],
        error0: NDArray[np.float64],
    ) -> None:
        self.rule = rule
        self.selected = np.asarray(selected, dtype=bool)
        self.filter = LowPassFilter(rule.cutoff_hz, period_s, order=1, channels=6)
        self.state = self.filter.initial_state(error0)
        self.filtered = np.array(error0, dtype=float)
        self.hold_ns = round(rule.hold_s * 1e9)
        self.in_band_since_ns: int | None = None
        self.settled_at_ns: int | None = None

    def update(self, now_ns: int, error: NDArray[np.float64]) -> bool:
        """Filter this cycle's error; True from the cycle the rule is met on (it latches)."""
        if self.settled_at_ns is not None:
            return True
        if not np.all(np.isfinite(error)):
            return False
        self.state, self.filtered = self.filter.step(self.state, error)
        if np.all(np.abs(self.filtered[self.selected]) <= self.rule.band_N):
            if self.in_band_since_ns is None:
                self.in_band_since_ns = now_ns
            if now_ns - self.in_band_since_ns >= self.hold_ns:
                self.settled_at_ns = now_ns
                return True
            return False
        self.in_band_since_ns = None
        return False


@dataclass(frozen=True, slots=True)
class CycleRecord:
    """What one compliant cycle did.

    Attributes:
        reading: the cycle's reading.
        state: the controller's state after the step (its ``wrench_error`` is :attr:`error`).
        error: the wrench error the controller acted on [N, N*m], control frame, (6,).
        settle_error: that error low-passed by the settle rule (None without a rule).
        twist_base: the command the controller computed [m/s, rad/s], base frame, (6,).
        sent: whether it was sent (False in a dry run).
        settled: whether the settle rule has been met (at this cycle or before).
    """

    reading: Reading
    state: ControllerState
    error: NDArray[np.float64]
    settle_error: NDArray[np.float64] | None
    twist_base: NDArray[np.float64]
    sent: bool
    settled: bool


class CompliantStep:
    """The compliant loop's step (see the module docstring); a ``run_loop`` step.

    Args:
        controller: the admittance controller.
        robot: the arm (its control period; if it reports lateness, a loop too far behind ends the
            run).
        duration_s: the run ends after this long [s] on the robot's clock.
        on_cycle: called with every cycle's :class:`CycleRecord`.
        settle: when the run is done (None: it runs for the whole duration).
        nominal: a planned twist added to the law's (e.g. a position-only descent).
        dry_run: compute and record every command but send zero.
        max_late_cycles: the run ends (``"loop_late"``) once the loop has fallen this many periods
            behind the robot's schedule (``ReportsLateness.periods_behind``).
    """

    def __init__(
        self,
        controller: AdmittanceController,
        robot: Robot,
        duration_s: float,
        on_cycle: Callable[[CycleRecord], None],
        *,
        settle: SettleRule | None = None,
        nominal: Nominal | None = None,
        dry_run: bool = False,
        max_late_cycles: int = 10,
    ) -> None:
        if not (math.isfinite(duration_s) and duration_s > 0.0):
            raise ParameterError(f"the duration must be > 0 s, got {duration_s}")
        if not (isinstance(max_late_cycles, int) and max_late_cycles >= 1):
            raise ParameterError(f"max_late_cycles must be an integer >= 1, got {max_late_cycles}")
        self.controller, self.on_cycle = controller, on_cycle
        self.settle, self.nominal, self.dry_run = settle, nominal, dry_run
        self.lateness = robot if isinstance(robot, ReportsLateness) else None
        self.max_late = max_late_cycles
        self.period_s = robot.control_period_s
        self.duration_ns = round(duration_s * 1e9)
        self.selected = np.diag(controller.law.selection) > 0.0
        self.state: ControllerState | None = None
        self.settling: Settling | None = None
        self.t0_ns = 0
        self.cycles = 0
        #: Why the run ended: :attr:`~ftcomp.session.outcome.Outcome.DURATION`,
        #: ``SETTLED``, ``LOOP_LATE`` (the loop fell too far behind the robot's periods) or a
        #: protective stop of the controller.
        self.outcome = Outcome.DURATION
        self._zero = np.zeros(6)

    @property
    def faulted(self) -> bool:
        """Whether the run ended by a protective stop or a late loop
        (:attr:`~ftcomp.session.outcome.Outcome.faulted`)."""
        return self.outcome.faulted

    @property
    def settled_at_ns(self) -> int | None:
        """When the settle rule was met [ns, robot clock], None if it was not."""
        return self.settling.settled_at_ns if self.settling is not None else None

    def _start(self, r: Reading) -> ControllerState:
        w0 = r.wrench_contact_sensor
        if not np.all(np.isfinite(w0)):
            w0 = np.zeros(6)  # the watchdog stops at this cycle's step
        state = self.controller.initial_state(w0, r.R_base_sensor)
        if self.settle is not None:
            e0 = self.controller.wrench_error(w0, r.R_base_sensor)
            self.settling = Settling(self.settle, self.period_s, self.selected, e0)
        self.t0_ns = r.now_ns
        return state

    def __call__(self, r: Reading) -> NDArray[np.float64] | None:
        """One cycle: controller step, record, and whether to go on."""
        state = self._start(r) if self.state is None else self.state
        if r.now_ns - self.t0_ns >= self.duration_ns:
            self.outcome = Outcome.DURATION
            return None
        if self.lateness is not None and self.lateness.periods_behind >= self.max_late:
            self.outcome = Outcome.LOOP_LATE
            return None
        nominal = self.nominal(r) if self.nominal is not None else None
        state, twist = self.controller.step(
            state,
            r.t_sample_ns * 1e-9,
            r.wrench_contact_sensor,
            r.R_base_sensor,
            r.now_ns * 1e-9,
            self.period_s,
            nominal,
            wrench_raw_sensor=r.wrench_raw_sensor,
        )
        self.state = state
        self.cycles += 1
        error = state.law.wrench_error
        settling = self.settling
        settled = settling is not None and settling.update(r.now_ns, error)
        self.on_cycle(
            CycleRecord(
                r,
                state,
                error,
                settling.filtered if settling is not None else None,
                twist,
                not self.dry_run,
                settled,
            )
        )
        if state.stop_reason is not None:
            self.outcome = Outcome.stopped_by(state.stop_reason)
            return None
        if settled and settling is not None and settling.settled_at_ns is not None:
            self.outcome = Outcome.SETTLED
            if r.now_ns - settling.settled_at_ns >= round(settling.rule.then_hold_s * 1e9):
                return None
        return self._zero if self.dry_run else twist
