"""Live sessions on any cell: log a sensor stream, run the compliant loop. Steps for ``run_loop``.

:class:`StreamLogger` (``ftcomp stream``) commands nothing; every cycle it takes every new
reading (``sensor.read_new``), so the log has the sensor's rate whatever the loop's, and writes
one row per reading: the raw wrench and, with a compensator and a pose, the contact wrench; with
a :class:`~ftcomp.experiments.live_load.StreamLoad` (``--online-load``) the contact wrench with
a grasped load weighed online and removed, and the load estimate.

:class:`CompliantStep` (``ftcomp run``) is the live compliant loop: the controller's step
(:class:`~ftcomp.control.controller.AdmittanceController`: watchdog, limits, filter, law,
envelope) on the compensated wrench, one log row per cycle (with a
:class:`~ftcomp.experiments.live_load.LoadTracker`, the online load estimate too), and the end
of the run: its duration, a settled contact (the selected axes' filtered force error within a
band for a while), a protective stop of the controller, or a loop that keeps missing its
period. With ``dry_run`` it computes and logs every command and sends a zero twist instead.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.control.controller import AdmittanceController, ControllerState
from ftcomp.control.filters import LowPassFilter
from ftcomp.control.loop import Reading
from ftcomp.errors import ParameterError
from ftcomp.experiments.live_load import LOAD_COLUMNS, LoadTracker, StreamLoad
from ftcomp.frames import quat_from_matrix
from ftcomp.hardware.protocols import Robot, WrenchSensor
from ftcomp.samples import WRENCH_COLUMNS

__all__ = ["RUN_COLUMNS", "CompliantStep", "SettleRule", "StreamLogger", "stream_columns"]

Row = Sequence[float]

#: Columns of ``ftcomp run``'s log: time since the start [s], raw and contact wrench (sensor
#: frame), the force error (contact minus desired) in the control frame, the commanded
#: sensor-origin twist (base frame), the sensor origin (base frame), and whether the twist was
#: sent (0 in a dry run).
RUN_COLUMNS = (
    "t_s",
    *WRENCH_COLUMNS,
    *(f"c{c}" for c in WRENCH_COLUMNS),
    "ex",
    "ey",
    "ez",
    "vx",
    "vy",
    "vz",
    "wx",
    "wy",
    "wz",
    "px",
    "py",
    "pz",
    "sent",
)


def stream_columns(
    *, with_pose: bool, compensated: bool, online_load: bool = False
) -> tuple[str, ...]:
    """Columns of ``ftcomp stream``'s log: ``t`` [s, session clock], the raw wrench, with a pose
    the sensor's orientation (``qx,qy,qz,qw``) and origin (``px,py,pz`` [m], base frame), when
    compensating the contact wrench ``cfx..ctz``, and with ``online_load`` (compensating) the
    load estimate (:data:`~ftcomp.experiments.live_load.LOAD_COLUMNS`). With a pose it is a
    valid sample CSV."""
    pose = ("qx", "qy", "qz", "qw", "px", "py", "pz") if with_pose else ()
    contact = tuple(f"c{c}" for c in WRENCH_COLUMNS) if compensated or online_load else ()
    load = LOAD_COLUMNS if online_load else ()
    return ("t", *WRENCH_COLUMNS, *pose, *contact, *load)


class StreamLogger:
    """Logs every reading until ``duration_s`` has passed on the session's clock.

    Args:
        sensor: the loop's sensor.
        write_row: called with each row (see :func:`stream_columns`).
        duration_s: how long to log [s].
        with_pose: log the sensor's pose (the robot reports one).
        compensator: also log the contact wrench.
        online: instead of ``compensator``, compensate with a grasped load weighed online, and
            log its estimate (rows may be held back while it measures the readings' rate:
            call :meth:`finish` at the end).
    """

    def __init__(
        self,
        sensor: WrenchSensor,
        write_row: Callable[[Row], None],
        duration_s: float,
        *,
        with_pose: bool,
        compensator: GravityCompensator | None = None,
        online: StreamLoad | None = None,
    ) -> None:
        if not (math.isfinite(duration_s) and duration_s > 0.0):
            raise ParameterError(f"the duration must be > 0 s, got {duration_s}")
        if compensator is not None and online is not None:
            raise ParameterError("give a compensator or an online load estimate, not both")
        self.sensor, self.write_row, self.with_pose = sensor, write_row, with_pose
        self.compensator, self.online = compensator, online
        self.duration_ns = round(duration_s * 1e9)
        self.t0_ns: int | None = None
        self.count = 0
        self.elapsed_s = 0.0
        self.contact_force_N = math.nan
        self._zero = np.zeros(6)

    def __call__(self, r: Reading) -> NDArray[np.float64] | None:
        """Log the readings that arrived since the previous cycle."""
        if self.t0_ns is None:
            self.t0_ns = r.now_ns
            self.sensor.read_new()  # start with the readings from now on
        self.elapsed_s = (r.now_ns - self.t0_ns) * 1e-9
        if r.now_ns - self.t0_ns >= self.duration_ns:
            return None
        pose: list[float] = []
        if self.with_pose:
            pose = [*quat_from_matrix(r.R_base_sensor), *r.p_base_sensor.tolist()]
        online = self.online
        for sample in self.sensor.read_new():
            w = sample.wrench_sensor
            row = [sample.t_ns * 1e-9, *w.tolist(), *pose]
            self.count += 1
            if online is not None:
                for ready in online.push(sample.t_ns, w, r.R_base_sensor, row):
                    self.write_row(ready)
                self.contact_force_N = online.contact_force_N
                continue
            if self.compensator is not None:
                contact = self.compensator.compensate(w, r.R_base_sensor)
                row += contact.tolist()
                self.contact_force_N = float(np.linalg.norm(contact[:3]))
            self.write_row(row)
        return self._zero

    def finish(self) -> None:
        """Log the rows still held back (the online estimate measuring the rate)."""
        if self.online is not None:
            for row in self.online.finish():
                self.write_row(row)


@dataclass(frozen=True)
class SettleRule:
    """When a run is done: every selected force error (filtered at ``cutoff_hz``) within
    ``band_N`` [N] of zero for ``hold_s`` [s]."""

    band_N: float
    hold_s: float = 0.3
    cutoff_hz: float = 2.0

    def __post_init__(self) -> None:
        for name in ("band_N", "hold_s", "cutoff_hz"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"settle {name} must be > 0, got {value}")


class CompliantStep:
    """The compliant loop's step (see the module docstring).

    Args:
        controller: the admittance controller.
        robot: the arm (for its period and, if it paces itself, its missed periods).
        first: the first reading (the controller starts bumpless at its wrench).
        duration_s: the run ends after this long [s].
        write_row: called with one row of :data:`RUN_COLUMNS` per cycle (with ``load``, then
            :data:`~ftcomp.experiments.live_load.LOAD_COLUMNS`).
        settle: end when the contact has settled (None: run for the whole duration).
        dry_run: compute and log every command but send zero.
        max_late_cycles: this many missed periods in a row end the run (``"overrun"``).
        load: follows the cycle's online load compensator (its estimate is logged).
    """

    def __init__(
        self,
        controller: AdmittanceController,
        robot: Robot,
        first: Reading,
        duration_s: float,
        write_row: Callable[[Row], None],
        *,
        settle: SettleRule | None = None,
        dry_run: bool = False,
        max_late_cycles: int = 10,
        load: LoadTracker | None = None,
    ) -> None:
        if not (math.isfinite(duration_s) and duration_s > 0.0):
            raise ParameterError(f"the duration must be > 0 s, got {duration_s}")
        w0 = first.wrench_contact_sensor
        if not np.all(np.isfinite(w0)):
            raise ParameterError("the first contact wrench is not finite: check the sensor")
        self.controller, self.robot, self.write_row = controller, robot, write_row
        self.dt = robot.control_period_s
        self.duration_ns = round(duration_s * 1e9)
        self.settle, self.dry_run, self.max_late = settle, dry_run, max_late_cycles
        self.load = load
        self.state: ControllerState = controller.initial_state(w0, first.R_base_sensor)
        self.t0_ns = first.now_ns
        self.outcome = "duration"
        self.cycles = 0
        self.contact_error = np.zeros(6)
        self._selected = np.diag(controller.law.selection)[:3] > 0.0
        self._in_band_since: int | None = None
        self._filter: LowPassFilter | None = None
        self._filter_state: NDArray[np.float64] | None = None
        if settle is not None:
            self._filter = LowPassFilter(settle.cutoff_hz, self.dt, order=1, channels=6)
            e0 = controller.wrench_error(w0, first.R_base_sensor)
            self._filter_state = self._filter.initial_state(e0)
        self._zero = np.zeros(6)

    @property
    def faulted(self) -> bool:
        """Whether the run ended by a protective stop or an overrun."""
        return self.outcome not in ("duration", "settled")

    def _settled(self, r: Reading) -> bool:
        rule, filt = self.settle, self._filter
        if rule is None or filt is None or self._filter_state is None:
            return False
        e = self.controller.wrench_error(r.wrench_contact_sensor, r.R_base_sensor)
        self._filter_state, e_filtered = filt.step(self._filter_state, e)
        self.contact_error = e_filtered
        if np.all(np.abs(e_filtered[:3][self._selected]) <= rule.band_N):
            if self._in_band_since is None:
                self._in_band_since = r.now_ns
            return r.now_ns - self._in_band_since >= round(rule.hold_s * 1e9)
        self._in_band_since = None
        return False

    def __call__(self, r: Reading) -> NDArray[np.float64] | None:
        """One cycle: controller step, log, and the decision whether to go on."""
        if r.now_ns - self.t0_ns >= self.duration_ns:
            self.outcome = "duration"
            return None
        if getattr(self.robot, "late_in_a_row", 0) >= self.max_late:
            self.outcome = "overrun"
            return None
        contact_finite = bool(np.all(np.isfinite(r.wrench_contact_sensor)))
        error = [math.nan] * 3
        if contact_finite:
            e = self.controller.wrench_error(r.wrench_contact_sensor, r.R_base_sensor)
            error = e[:3].tolist()
        self.state, twist = self.controller.step(
            self.state,
            r.t_sample_ns * 1e-9,
            r.wrench_contact_sensor,
            r.R_base_sensor,
            r.now_ns * 1e-9,
            self.dt,
        )
        self.cycles += 1
        t_s = (r.now_ns - self.t0_ns) * 1e-9
        row = [
            t_s,
            *r.wrench_raw_sensor.tolist(),
            *r.wrench_contact_sensor.tolist(),
            *error,
            *twist.tolist(),
            *r.p_base_sensor.tolist(),
            0.0 if self.dry_run else 1.0,
        ]
        if self.load is not None:
            row += self.load.update(t_s)
        self.write_row(row)
        if self.state.stop_reason is not None:
            self.outcome = self.state.stop_reason.value
            return None
        if contact_finite and self._settled(r):
            self.outcome = "settled"
            return None
        return self._zero if self.dry_run else twist
