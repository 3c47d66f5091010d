"""Grasp-aware compensation: weigh a grasped load online, detect grasp and release.

:class:`OnlineLoadCompensator` is a :class:`~ftcomp.compensation.compensator.GravityCompensator`
that watches its own output. Every single-sample :meth:`~OnlineLoadCompensator.compensate` call
(one per reading, in time order, as a live cycle's
:class:`~ftcomp.compensation.pipeline.WrenchPipeline` makes them) also

1. runs a **grasp/release detector** on the compensated wrench: a step of the windowed mean force
   away from a slowly tracked baseline, confirmed when it persists for ``confirm_s``. A step whose
   force points along gravity is a grasp (a surface pushing the tool cannot pull it down); in the
   holding state a step that brings the tool-only compensated force back to zero is a release;
   any other step is a contact and changes nothing;
2. after a grasp, **estimates the load** by recursive least squares with exponential forgetting
   (:class:`LoadRls`), restarted at every detection (from the sample after the confirmation
   window, which holds the grasp's transient);
3. once the estimate has **converged** (standard deviation of the predicted load wrench at the
   current orientation below ``converged_force_N`` / ``converged_torque_Nm``), subtracts the
   load's gravity wrench too, ramped in over ``ramp_s`` (bumpless: the output never jumps), and
   from then on refines the estimate only while the compensated force stays within the gate
   (no contact), so that contact forces stay right after a grasp.

Why recursive least squares: the load's wrench is *linear* in ``theta = (m, m c)`` (mass and
first moment), ``[F'; M'] = [g d, 0; 0, -g skew(d)] theta`` with ``d`` the unit gravity direction
in the sensor frame, so RLS is the exact recursive form of the batch least squares of
:func:`~ftcomp.compensation.load.estimate_load`; with rows weighted by the sensor's noise
variances its information matrix inverts to the parameters' covariance. A Kalman filter with a
random-walk model would add nothing but a process noise to tune; the forgetting factor plays that
role (time constant ``memory_s``). With an accelerometer in the sensor (``specific_force_mps2``)
``g d`` is the apparent gravity it reads, ``-f = g_s - a``: the load is weighed, and compensated,
while the arm moves as well as when it is still.

:class:`LoadTracker` follows a compensator call by call for a live log: the load columns of a
row (:data:`LOAD_COLUMNS`) and the grasp, release and contact events (:class:`LoadEvent`) with
their times and the mass each concerns.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace
from enum import Enum

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.calibration_record import Calibration
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import ParameterError
from ftcomp.model import GravityModel, skew

__all__ = [
    "LOAD_COLUMNS",
    "LOAD_STATE_CODES",
    "GraspEvent",
    "GraspState",
    "LoadEvent",
    "LoadRls",
    "LoadTracker",
    "OnlineLoadCompensator",
    "OnlineSettings",
    "estimate_columns",
]


class GraspState(Enum):
    """What the online compensator believes the gripper holds."""

    EMPTY = "empty"
    ESTIMATING = "estimating"
    HOLDING = "holding"


@dataclass(frozen=True)
class OnlineSettings:
    """Tuning of :class:`OnlineLoadCompensator` (defaults: the paper's sensor at 1 kHz).

    Attributes:
        rate_Hz: samples per second of the calls to ``compensate`` [Hz].
        force_noise_std_N, torque_noise_std_Nm: the sensor's per-sample noise (row weights).
        step_force_N: smallest force step taken as a grasp or release [N] (~100 g).
        confirm_s: a step must persist this long to count [s].
        baseline_s: time constant of the baseline the steps are measured from [s].
        memory_s: time constant of the estimator's forgetting [s].
        converged_force_N, converged_torque_Nm: standard deviations of the predicted load
            wrench below which the estimate counts as converged.
        ramp_s: the load wrench is ramped into the compensation over this time [s].
        grasp_cos: a grasp step's force must point along gravity within ``acos(grasp_cos)``.
    """

    rate_Hz: float = 1000.0
    force_noise_std_N: float = 0.125
    torque_noise_std_Nm: float = 0.003
    step_force_N: float = 1.0
    confirm_s: float = 0.05
    baseline_s: float = 0.5
    memory_s: float = 10.0
    converged_force_N: float = 0.01
    converged_torque_Nm: float = 0.0005
    ramp_s: float = 0.1
    grasp_cos: float = 0.9

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"OnlineSettings.{name} must be finite and > 0, got {value}")
        if self.grasp_cos >= 1.0:
            raise ParameterError(f"OnlineSettings.grasp_cos must be < 1, got {self.grasp_cos}")


class LoadRls:
    """Recursive least squares of a load's ``theta = (m [kg], m c [kg m])`` with forgetting.

    Each row's regressor is the gravity the load feels, ``gamma`` [m/s^2] in the sensor frame:
    gravity at the sensor's orientation, or, with an accelerometer in the sensor, its reading
    negated (the apparent gravity ``g_s - a``, so a moving load weighs what it weighs).

    Information form: ``A <- lam A + H' W H``, ``b <- lam b + H' W y``, ``theta = A^-1 b``,
    covariance ``A^-1`` (rows weighted by the inverse noise variances ``W``). A weak prior
    (``theta = 0`` with standard deviation 1 kg, 1 kg m) keeps ``A`` invertible while the centre
    of gravity along gravity is not yet observable (one orientation only).

    Args:
        weights: inverse noise variances of the six wrench rows, shape (6,).
        forgetting: ``lam`` in (0, 1].
    """

    def __init__(self, weights: NDArray[np.float64], forgetting: float):
        self.w = np.asarray(weights, dtype=float)
        self.lam = forgetting
        self.reset()

    def reset(self) -> None:
        """Forget everything: back to the prior."""
        self.A = np.eye(4)
        self.b = np.zeros(4)
        self.theta = np.zeros(4)
        self._cov: NDArray[np.float64] | None = None
        self.samples = 0

    @staticmethod
    def regressor(gamma_sensor: NDArray[np.float64]) -> NDArray[np.float64]:
        """``H`` (6, 4): the load wrench ``H @ theta`` under gravity ``gamma_sensor`` [m/s^2]."""
        H = np.zeros((6, 4))
        H[:3, 0] = gamma_sensor
        H[3:, 1:] = -skew(gamma_sensor)
        return H

    def update(self, gamma_sensor: NDArray[np.float64], wrench: NDArray[np.float64]) -> None:
        """Add one compensated wrench (tool removed) seen under gravity ``gamma_sensor``."""
        H = self.regressor(gamma_sensor)
        HtW = H.T * self.w
        self.A = self.lam * self.A + HtW @ H
        self.b = self.lam * self.b + HtW @ wrench
        self.theta = np.asarray(np.linalg.solve(self.A, self.b), dtype=float)
        self._cov = None
        self.samples += 1

    @property
    def covariance(self) -> NDArray[np.float64]:
        """Covariance of ``theta``, (4, 4)."""
        if self._cov is None:
            self._cov = np.asarray(np.linalg.inv(self.A))
        return self._cov

    @property
    def mass_kg(self) -> float:
        return float(self.theta[0])

    @property
    def mass_std_kg(self) -> float:
        return float(math.sqrt(self.covariance[0, 0]))

    @property
    def cog_m(self) -> NDArray[np.float64]:
        """Centre of gravity, sensor frame [m] (zeros before any mass is seen)."""
        m = self.theta[0]
        return self.theta[1:] / m if abs(m) > 1e-9 else np.zeros(3)

    @property
    def cog_covariance(self) -> NDArray[np.float64]:
        """Covariance of the centre of gravity (first order), (3, 3) [m^2]."""
        m = self.theta[0]
        if abs(m) <= 1e-9:
            return np.full((3, 3), np.inf)
        J = np.hstack([-self.cog_m[:, None] / m, np.eye(3) / m])
        return np.asarray(J @ self.covariance @ J.T)

    def predicted_std(self, gamma_sensor: NDArray[np.float64]) -> tuple[float, float]:
        """Largest standard deviation of the predicted load force [N] and torque [N m]."""
        H = self.regressor(gamma_sensor)
        C = H @ self.covariance @ H.T
        return float(math.sqrt(C[:3, :3].diagonal().max())), float(
            math.sqrt(C[3:, 3:].diagonal().max())
        )


@dataclass(frozen=True)
class GraspEvent:
    """A confirmed step of the compensated wrench.

    Attributes:
        kind: ``"grasp"``, ``"release"`` or ``"contact"``.
        sample: index of the ``compensate`` call that confirmed it (0-based).
        onset_sample: index of the call where the step began.
    """

    kind: str
    sample: int
    onset_sample: int


class OnlineLoadCompensator(GravityCompensator):
    """Tool compensation plus an online-weighed grasped load (see the module docstring).

    A single-sample :meth:`compensate` is *stateful*: it advances the detector and the
    estimator by one sample, so call it once per new reading, in time order. A batch call
    compensates with the current state and changes nothing.

    Args:
        calibration: the tool's static calibration (bias, tool weight and centre of gravity).
        settings: tuning; default :class:`OnlineSettings`.
    """

    def __init__(
        self, calibration: Calibration | GravityModel, settings: OnlineSettings | None = None
    ) -> None:
        super().__init__(calibration)
        if self.gravity_dir_base is None:
            raise ParameterError("online load estimation needs a calibration with a tool weight")
        self.settings = s = settings if settings is not None else OnlineSettings()
        self._u = np.asarray(self.gravity_dir_base, dtype=float)
        # With a mount the orientations given are the recorded frame's: R_base_sensor = R @ this.
        self._R_rec_sensor = None if self.mount is None else self.mount.R_rec_sensor
        weights = np.array([1 / s.force_noise_std_N**2] * 3 + [1 / s.torque_noise_std_Nm**2] * 3)
        self.rls = LoadRls(weights, math.exp(-1.0 / (s.memory_s * s.rate_Hz)))
        self._n_confirm = max(2, round(s.confirm_s * s.rate_Hz))
        self._alpha = 1.0 / (s.baseline_s * s.rate_Hz)
        self._ramp_step = 1.0 / max(1.0, s.ramp_s * s.rate_Hz)
        self.state = GraspState.EMPTY
        #: The load parameters in use, (m, m c), and how much of them is applied (0..1).
        self.theta_used = np.zeros(4)
        self.blend = 0.0
        self.events: list[GraspEvent] = []
        self._baseline: NDArray[np.float64] | None = None
        self._run = 0
        self._sum = np.zeros(6)
        self.samples = 0

    # ----------------------------------------------------------------- queries
    @property
    def converged(self) -> bool:
        """Whether a load is held and its estimate is in use."""
        return self.state is GraspState.HOLDING

    @property
    def confirm_samples(self) -> int:
        """Calls a step must persist to be confirmed (``confirm_s`` at ``rate_Hz``, at least
        2): an event's ``sample - onset_sample`` is this minus one."""
        return self._n_confirm

    def load_wrench(self, gamma_sensor: NDArray[np.float64]) -> NDArray[np.float64]:
        """The load wrench subtracted now, under gravity ``gamma_sensor`` [m/s^2], (6,)."""
        return self.blend * (self.rls.regressor(gamma_sensor) @ self.theta_used)

    def gravity_sensor(self, R_base_sensor: NDArray[np.float64]) -> NDArray[np.float64]:
        """Gravity in the sensor frame [m/s^2], (3,) (``R_base_sensor``: the sensor's own
        orientation, the mount already applied)."""
        return np.asarray(STANDARD_GRAVITY_MPS2 * (self._u @ R_base_sensor))

    # ----------------------------------------------------------------- the cycle
    def compensate(
        self,
        wrench_sensor: ArrayLike,
        R_base_sensor: ArrayLike,
        *,
        out: NDArray[np.float64] | None = None,
        t_s: ArrayLike | None = None,
        temperature_C: ArrayLike | None = None,
        specific_force_mps2: ArrayLike | None = None,
    ) -> NDArray[np.float64]:
        """Contact wrench with tool and (once converged) load removed [N, N*m], sensor frame.

        One sample, shape (6,) with (3, 3): advances the detector and estimator. A batch,
        (N, 6) with (N, 3, 3): compensates with the current state only. ``out``, ``t_s``,
        ``temperature_C`` and ``specific_force_mps2`` as in
        :meth:`GravityCompensator.compensate` (with an accelerometer the load too is weighed
        and compensated under the apparent gravity it reads).
        """
        tool_only = super().compensate(
            wrench_sensor,
            R_base_sensor,
            out=out,
            t_s=t_s,
            temperature_C=temperature_C,
            specific_force_mps2=specific_force_mps2,
        )
        R = np.asarray(R_base_sensor, dtype=float)
        if self._R_rec_sensor is not None:
            R = R @ self._R_rec_sensor
        if tool_only.ndim == 2:
            gammas = (
                STANDARD_GRAVITY_MPS2 * (R.transpose(0, 2, 1) @ self._u)
                if specific_force_mps2 is None
                else -np.asarray(specific_force_mps2, dtype=float)
            )
            H = np.array([self.rls.regressor(gamma) for gamma in gammas])
            tool_only -= self.blend * (H @ self.theta_used)
            return tool_only
        if not np.isfinite(tool_only).all():
            return tool_only  # garbage in: the loop's watchdog acts; the state is left alone
        gamma = (
            self.gravity_sensor(R)
            if specific_force_mps2 is None
            else -np.asarray(specific_force_mps2, dtype=float)
        )
        self._observe(gamma, tool_only)
        self.samples += 1
        return tool_only - self.load_wrench(gamma) if self.blend > 0.0 else tool_only

    def _observe(self, gamma: NDArray[np.float64], tool_only: NDArray[np.float64]) -> None:
        s = self.settings
        # The detector compares against the full load estimate (not the ramped one).
        residual = tool_only
        if self.state is GraspState.HOLDING:
            residual = tool_only - self.rls.regressor(gamma) @ self.theta_used
        if self._baseline is None:
            self._baseline = residual.copy()
        if self.state is GraspState.ESTIMATING:
            self.rls.update(gamma, tool_only)
            fs, ts = self.rls.predicted_std(gamma)
            if fs < s.converged_force_N and ts < s.converged_torque_Nm:
                self.state = GraspState.HOLDING
                self.theta_used = self.rls.theta.copy()
                self.blend = 0.0
                self._baseline = tool_only - self.rls.regressor(gamma) @ self.theta_used
                self._run = 0
                return
        elif self.state is GraspState.HOLDING:
            self.blend = min(1.0, self.blend + self._ramp_step)
            if self._run == 0 and abs(residual[:3]).max() < 4.0 * s.force_noise_std_N:
                self.rls.update(gamma, tool_only)  # refine while nothing touches the tool
                self.theta_used = self.rls.theta.copy()
        step = residual[:3] - self._baseline[:3]
        if float(np.linalg.norm(step)) > s.step_force_N:
            self._run += 1
            self._sum += residual
            if self._run >= self._n_confirm:
                mean = self._sum / self._run
                if float(np.linalg.norm(mean[:3] - self._baseline[:3])) > s.step_force_N:
                    self._confirmed(gamma, mean)
                self._run, self._sum = 0, np.zeros(6)
            return
        self._run, self._sum = 0, np.zeros(6)
        self._baseline += self._alpha * (residual - self._baseline)

    def _confirmed(self, gamma: NDArray[np.float64], mean: NDArray[np.float64]) -> None:
        """A step persisted for the confirmation window: grasp, release or contact."""
        s = self.settings
        onset = self.samples - self._n_confirm + 1
        assert self._baseline is not None
        jump = mean[:3] - self._baseline[:3]
        if self.state is GraspState.EMPTY or self.state is GraspState.ESTIMATING:
            level = mean[:3]  # nothing subtracted but the tool in these states
            d = gamma / max(float(np.linalg.norm(gamma)), 1e-9)  # gravity's direction
            along = float(level @ d)
            if along > s.step_force_N and along > s.grasp_cos * float(np.linalg.norm(level)):
                self._start_estimate("grasp", onset)
            elif self.state is GraspState.ESTIMATING and np.linalg.norm(level) < s.step_force_N:
                self._empty("release", onset)
            else:
                self.events.append(GraspEvent("contact", self.samples, onset))
            self._baseline = mean.copy()
            return
        tool_only_level = mean[:3] + self.rls.regressor(gamma)[:3] @ self.theta_used
        if float(np.linalg.norm(tool_only_level)) < max(
            s.step_force_N, 0.25 * float(np.linalg.norm(jump))
        ):
            load = self.rls.regressor(gamma) @ self.theta_used
            self._empty("release", onset)
            self._baseline = mean + load  # the level without the load subtracted
            return
        self.events.append(GraspEvent("contact", self.samples, onset))
        self._baseline = mean.copy()

    def _start_estimate(self, kind: str, onset: int) -> None:
        self.events.append(GraspEvent(kind, self.samples, onset))
        self.state = GraspState.ESTIMATING
        self.rls.reset()
        self.theta_used = np.zeros(4)
        self.blend = 0.0
        # The confirmation window is not fed: it holds the grasp's transient (the gripper
        # closing and the load swinging in), which would bias the centre of gravity.

    def _empty(self, kind: str, onset: int) -> None:
        self.events.append(GraspEvent(kind, self.samples, onset))
        self.state = GraspState.EMPTY
        self.rls.reset()
        self.theta_used = np.zeros(4)
        self.blend = 0.0


#: Columns a log gains with ``--online-load``: the state (:data:`LOAD_STATE_CODES`), the load's
#: mass and its standard deviation [kg], its centre of gravity (sensor frame) [m] and the largest
#: standard deviation of the centre's three components [m]. Empty: mass 0, the rest NaN.
LOAD_COLUMNS = (
    "load_state",
    "load_kg",
    "load_kg_std",
    "load_cx_m",
    "load_cy_m",
    "load_cz_m",
    "load_c_std_m",
)

#: ``load_state``: 0 empty (nothing held: only the tool is compensated), 1 estimating (a grasp
#: was detected, the load is being weighed, not yet compensated), 2 holding (the estimate has
#: converged and is compensated too).
LOAD_STATE_CODES = {GraspState.EMPTY: 0, GraspState.ESTIMATING: 1, GraspState.HOLDING: 2}

_EMPTY_COLUMNS = [0.0, 0.0] + [math.nan] * 5


@dataclass(frozen=True)
class LoadEvent:
    """A grasp, release or contact the online compensator confirmed.

    Attributes:
        kind: ``"grasp"``, ``"release"`` or ``"contact"``.
        t_s: when the step began [s] (the log's clock).
        confirmed_t_s: when it was confirmed, ``confirm_s`` later [s].
        mass_kg, mass_std_kg: the load concerned and its standard deviation: for a grasp the
            last estimate while it was held (or is, at the end), for a release the estimate of
            the load let go; NaN for a contact.
        converged: whether that estimate had converged (was compensated).
    """

    kind: str
    t_s: float
    confirmed_t_s: float
    mass_kg: float = math.nan
    mass_std_kg: float = math.nan
    converged: bool = False

    def describe(self) -> str:
        """One line, e.g. ``grasp    at 0.500 s (confirmed 0.549 s): 0.5002 ± 0.0004 kg``."""
        head = f"{self.kind:<8} at {self.t_s:.3f} s (confirmed {self.confirmed_t_s:.3f} s)"
        if self.kind == "contact":
            return head + ": a step that is neither (the load estimate is kept)"
        if not math.isfinite(self.mass_kg):
            return head
        note = "" if self.converged else " (not converged)"
        return f"{head}: {self.mass_kg:.4f} ± {self.mass_std_kg:.4f} kg{note}"


def estimate_columns(rls: LoadRls) -> list[float]:
    """``load_kg .. load_c_std_m`` of an estimate (the largest of the centre's three standard
    deviations; infinite before any mass is seen)."""
    c_std = math.sqrt(max(float(np.max(np.diag(rls.cog_covariance))), 0.0))
    return [rls.mass_kg, rls.mass_std_kg, *rls.cog_m.tolist(), c_std]


class LoadTracker:
    """The load columns and events of an online compensator, followed after each call.

    Args:
        compensator: the compensator, called by someone else (once per reading or cycle).
    """

    def __init__(self, compensator: OnlineLoadCompensator) -> None:
        self.compensator = compensator
        self._calls = compensator.samples
        self._seen = len(compensator.events)
        # (call index, time) of the latest calls: an event's onset is confirm_samples - 1 back.
        self._stamps: deque[tuple[int, float]] = deque(maxlen=compensator.confirm_samples + 1)
        self._events: list[LoadEvent] = []
        self._open: int | None = None  # the grasp whose load is weighed or held now
        self._estimate = (math.nan, math.nan, False)  # mass, std, converged of that load
        self.columns: list[float] = list(_EMPTY_COLUMNS)
        self._rls_samples, self._state = -1, GraspState.EMPTY  # what the columns are of

    @property
    def events(self) -> list[LoadEvent]:
        """Every event so far (an open grasp with the current estimate)."""
        out = list(self._events)
        if self._open is not None:
            mass, std, converged = self._estimate
            out[self._open] = replace(
                out[self._open], mass_kg=mass, mass_std_kg=std, converged=converged
            )
        return out

    def status_text(self) -> str:
        """For a live line: the load while holding, ``weighing`` while estimating."""
        state = self.compensator.state
        if state is GraspState.HOLDING:
            return f"load {self.columns[1]:.3f} ± {self.columns[2]:.3f} kg"
        return "weighing" if state is GraspState.ESTIMATING else ""

    def update(self, t_s: float) -> list[float]:
        """After the compensator's call(s) for a reading at ``t_s`` [s] (the log's clock): note
        new events, return the row's :data:`LOAD_COLUMNS`."""
        c = self.compensator
        if c.samples != self._calls:
            self._calls = c.samples
            self._stamps.append((c.samples - 1, t_s))
        while self._seen < len(c.events):
            self._record(c.events[self._seen], t_s)
            self._seen += 1
        if c.state is GraspState.EMPTY:
            self.columns, self._state = list(_EMPTY_COLUMNS), c.state
            return self.columns
        rls = c.rls
        if rls.samples != self._rls_samples or c.state is not self._state:
            self._rls_samples, self._state = rls.samples, c.state
            self.columns = [float(LOAD_STATE_CODES[c.state]), *estimate_columns(rls)]
        mass, std = self.columns[1], self.columns[2]
        converged = self._estimate[2] or c.state is GraspState.HOLDING
        self._estimate = (mass, std, converged)
        return self.columns

    def _time_of(self, sample: int, now_sample: int, now_s: float) -> float:
        for k, t in self._stamps:
            if k == sample:
                return t
        return now_s - (now_sample - sample) / self.compensator.settings.rate_Hz

    def _record(self, e: GraspEvent, now_s: float) -> None:
        onset_s = self._time_of(e.onset_sample, e.sample, now_s)
        confirmed_s = self._time_of(e.sample, e.sample, now_s)
        if e.kind == "contact":
            self._events.append(LoadEvent("contact", onset_s, confirmed_s))
            return
        mass, std, converged = self._estimate  # of the load held or weighed before this call
        if self._open is not None:  # a release or a new grasp ends it
            self._events[self._open] = replace(
                self._events[self._open], mass_kg=mass, mass_std_kg=std, converged=converged
            )
            self._open = None
        if e.kind == "release":
            self._events.append(LoadEvent("release", onset_s, confirmed_s, mass, std, converged))
        else:
            self._events.append(LoadEvent(e.kind, onset_s, confirmed_s))
            self._open = len(self._events) - 1
        self._estimate = (math.nan, math.nan, False)
