"""The online load estimate in the live loops (``ftcomp stream`` and ``ftcomp run``
with ``--online-load``).

:class:`LoadTracker` follows an :class:`~ftcomp.compensation.online.OnlineLoadCompensator` call
by call: the load columns of a log row (:data:`LOAD_COLUMNS`) and the grasp, release and contact
events with their times on the log's clock and the mass each concerns.

:class:`StreamLoad` is a stream's compensation with it: one ``compensate`` call per reading, in
time order, so the compensator's rate must be the readings' rate. Given, it is used as is;
otherwise it is measured from the stamps of the first readings (:data:`MEASURE_RATE_S`), which
are held back until then and compensated in order once the rate is known, so none is lost.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration_record import Calibration
from ftcomp.compensation.online import (
    GraspEvent,
    GraspState,
    LoadRls,
    OnlineLoadCompensator,
    OnlineSettings,
)
from ftcomp.errors import ParameterError
from ftcomp.model import GravityModel

__all__ = [
    "LOAD_COLUMNS",
    "LOAD_STATE_CODES",
    "MEASURE_RATE_S",
    "LoadEvent",
    "LoadTracker",
    "StreamLoad",
    "estimate_columns",
    "event_lines",
    "require_tool_weight",
]

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

#: How long the readings' stamps are watched to measure their rate when none is given [s].
MEASURE_RATE_S = 0.5
#: ... and at least this many readings.
MIN_RATE_READINGS = 20

_EMPTY_COLUMNS = [0.0, 0.0] + [math.nan] * 5


def require_tool_weight(calibration: Calibration | GravityModel, source: str) -> None:
    """Refuse a calibration the online estimator cannot use (a weightless tool gives no gravity
    direction to weigh a load along).

    Raises:
        ParameterError: the tool weight is 0, naming ``source`` (the calibration file).
    """
    model = calibration.model if isinstance(calibration, Calibration) else calibration
    if not model.weight_N:
        raise ParameterError(
            f"{source}: the tool weight is 0 N: online load estimation needs a calibration "
            "with the tool's weight (its direction is gravity's)"
        )


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


def event_lines(events: list[LoadEvent], *, limit: int = 20) -> list[str]:
    """The events as lines to print (the first ``limit``, then how many more)."""
    if not events:
        return ["online load: no grasp or release detected"]
    lines = ["online load events (t on the log's clock; mass ± 1 standard deviation):"]
    lines += [f"  {e.describe()}" for e in events[:limit]]
    if len(events) > limit:
        lines.append(f"  ... and {len(events) - limit} more")
    return lines


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


Row = list[float]


class StreamLoad:
    """A stream's online load compensation: one ``compensate`` call per reading, in order.

    Args:
        calibration: the tool's calibration (with its weight).
        rate_Hz: the readings' rate [Hz]; None: measured from the stamps of the first
            ``measure_s`` of readings (at least :data:`MIN_RATE_READINGS`), held back until then.
        settings: the compensator's tuning; its ``rate_Hz`` is replaced by the rate
            (default :class:`~ftcomp.compensation.online.OnlineSettings`).
        measure_s: how long to measure the rate [s].

    Raises:
        ParameterError: a weightless tool, or a rate that is not > 0.
    """

    def __init__(
        self,
        calibration: Calibration | GravityModel,
        rate_Hz: float | None = None,
        *,
        settings: OnlineSettings | None = None,
        measure_s: float = MEASURE_RATE_S,
    ) -> None:
        require_tool_weight(calibration, "the calibration")
        if rate_Hz is not None and not (math.isfinite(rate_Hz) and rate_Hz > 0.0):
            raise ParameterError(f"the readings' rate must be > 0 Hz, got {rate_Hz:g}")
        self.calibration = calibration
        self.settings = settings if settings is not None else OnlineSettings()
        self.measure_ns = round(measure_s * 1e9)
        self.compensator: OnlineLoadCompensator | None = None
        self.tracker: LoadTracker | None = None
        #: How the rate was found (for the report).
        self.rate_source = ""
        self.contact_force_N = math.nan
        self._pending: list[tuple[int, NDArray[np.float64], NDArray[np.float64], Row]] = []
        if rate_Hz is not None:
            self._start(rate_Hz, "given")

    @property
    def rate_Hz(self) -> float:
        """The rate in use [Hz] (NaN while it is being measured)."""
        return self.compensator.settings.rate_Hz if self.compensator is not None else math.nan

    def status_text(self) -> str:
        """For a live line (see :meth:`LoadTracker.status_text`)."""
        if self.tracker is None:
            return "measuring the rate"
        return self.tracker.status_text()

    @property
    def events(self) -> list[LoadEvent]:
        """The events so far."""
        return self.tracker.events if self.tracker is not None else []

    def push(
        self,
        t_ns: int,
        wrench_sensor: NDArray[np.float64],
        R_base_sensor: NDArray[np.float64],
        head: Row,
    ) -> list[Row]:
        """One reading (stamp [ns], raw wrench, the sensor's orientation, the row's first
        columns): the rows ready to log, each ``head + contact wrench + LOAD_COLUMNS``."""
        if self.compensator is None:
            self._pending.append((t_ns, wrench_sensor, R_base_sensor, head))
            first = self._pending[0][0]
            if t_ns - first >= self.measure_ns and len(self._pending) >= MIN_RATE_READINGS:
                self._start_measured()
                return self._drain()
            return []
        return [self._row(t_ns, wrench_sensor, R_base_sensor, head)]

    def finish(self) -> list[Row]:
        """At the end of the stream: the rows still held back (the rate measured from them)."""
        if self.compensator is None and self._pending:
            self._start_measured()
        return self._drain()

    def _start_measured(self) -> None:
        stamps = [p[0] for p in self._pending]
        span_s = (stamps[-1] - stamps[0]) * 1e-9
        if len(stamps) >= 2 and span_s > 0.0:
            rate = (len(stamps) - 1) / span_s
            self._start(rate, f"measured from {len(stamps)} readings over {span_s:.2f} s")
        else:  # one stamp: no step can be confirmed (two calls at least), the rate is moot
            self._start(self.settings.rate_Hz, "too few readings to measure: the default")

    def _start(self, rate_Hz: float, source: str) -> None:
        settings = replace(self.settings, rate_Hz=rate_Hz)
        self.compensator = OnlineLoadCompensator(self.calibration, settings)
        self.tracker = LoadTracker(self.compensator)
        self.rate_source = source

    def _drain(self) -> list[Row]:
        pending, self._pending = self._pending, []
        return [self._row(*p) for p in pending]

    def _row(
        self, t_ns: int, wrench: NDArray[np.float64], R: NDArray[np.float64], head: Row
    ) -> Row:
        assert self.compensator is not None and self.tracker is not None
        contact = self.compensator.compensate(wrench, R)
        self.contact_force_N = float(np.linalg.norm(contact[:3]))
        return [*head, *contact.tolist(), *self.tracker.update(t_ns * 1e-9)]
