"""A compliant run on a live cell: ``ftcomp run`` as one library call.

:func:`run_compliant` opens nothing: it takes an entered robot and sensor, the calibration, a
:class:`RunConfig` and the log's path, runs :class:`~ftcomp.session.compliant.CompliantStep` in
the package's one loop (:func:`~ftcomp.control.loop.run_loop`: on any exit the robot is stopped
first) and returns a :class:`RunResult`: why it ended, the cycles, the travel, the force error at
the end, the online load's events.

Each cycle: read, compensate (bias and tool gravity of the calibration; with ``online_load`` a
grasped load weighed online too), the admittance controller on the selected axes (its law, the
safety envelope, the sample watchdog), then the twist to the robot; one log row per cycle
(:data:`RUN_COLUMNS`). The log carries every input of the controller's step (the sample's stamp,
the contact and raw wrench, the orientation) at full precision and the error it acted on, so it
replays through the step to the same commands.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration_record import Calibration
from ftcomp.compensation.bias_tracking import BiasTracker, BiasTrackingConfig
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.compensation.online import LOAD_COLUMNS, LoadEvent, LoadTracker
from ftcomp.compensation.pipeline import WrenchPipeline
from ftcomp.config_fields import check_fields, param
from ftcomp.control.controller import CONTROL_FRAMES, AdmittanceController, ControlFrame
from ftcomp.control.filters import LowPassFilter
from ftcomp.control.laws import (
    AdmittanceLaw,
    CombinedLaw,
    MassDamperSpringLaw,
    PositionLaw,
    VelocityLaw,
    selection_matrix,
)
from ftcomp.control.loop import ControlCycle, loop_clock, run_loop
from ftcomp.control.safety import SafetyLimits
from ftcomp.errors import FtcompError, ParameterError
from ftcomp.frames import quat_from_matrix
from ftcomp.hardware.pacing import TimingSummary
from ftcomp.hardware.protocols import (
    Mount,
    ReportsExtraChannels,
    ReportsRate,
    Robot,
    TakesControl,
    WrenchSensor,
)
from ftcomp.model import GravityModel
from ftcomp.samples import WRENCH_COLUMNS
from ftcomp.session.compliant import DEFAULT_HOLD_S, CompliantStep, CycleRecord, SettleRule
from ftcomp.session.interrupts import InterruptHold
from ftcomp.session.log import CsvLog, LogObserver, csv_log, save_timing
from ftcomp.session.online_load import require_tool_weight
from ftcomp.session.outcome import Outcome

__all__ = [
    "FILTER_HZ",
    "FILTER_SHARE_OF_RATE",
    "INTEGRAL_FILTER_HZ",
    "LAWS",
    "RUN_COLUMNS",
    "STALE_SENSOR_PERIODS",
    "AdmittanceConfig",
    "LawName",
    "RunConfig",
    "RunResult",
    "cycle_row",
    "filter_hz_for",
    "run_compliant",
    "sensor_rate_hz",
    "stale_after_s_for",
]

LawName = Literal["combined", "position", "velocity", "mass-damper-spring"]

#: The admittance laws a run can use.
LAWS: tuple[LawName, ...] = ("combined", "position", "velocity", "mass-damper-spring")

#: Columns of a run's log: the cycle's time and the sample's stamp since the start [s], the raw
#: and contact wrench (sensor frame), the sensor's orientation (``qx,qy,qz,qw``) and origin
#: (base frame, [m]), the wrench error the controller acted on (control frame, after its
#: filter), the commanded sensor-origin twist (base frame) and whether it was sent (0 in a dry
#: run). Numbers are written with 17 significant digits (exact).
RUN_COLUMNS = (
    "t_s",
    "t_sample_s",
    *WRENCH_COLUMNS,
    *(f"c{c}" for c in WRENCH_COLUMNS),
    "qx",
    "qy",
    "qz",
    "qw",
    "px",
    "py",
    "pz",
    "ex",
    "ey",
    "ez",
    "etx",
    "ety",
    "etz",
    "vx",
    "vy",
    "vz",
    "wx",
    "wy",
    "wz",
    "sent",
)


def cycle_row(record: CycleRecord, t0_ns: int) -> list[float]:
    """A compliant cycle as a row of :data:`RUN_COLUMNS`, its times from ``t0_ns`` [ns] (the
    first cycle's ``now_ns``): what ``ftcomp run`` logs, and what a placement hands its
    observers."""
    r = record.reading
    return [
        (r.now_ns - t0_ns) * 1e-9,
        (r.t_sample_ns - t0_ns) * 1e-9,
        *r.wrench_raw_sensor.tolist(),
        *r.wrench_contact_sensor.tolist(),
        *quat_from_matrix(r.R_base_sensor),
        *r.p_base_sensor.tolist(),
        *record.error.tolist(),
        *record.twist_base.tolist(),
        1.0 if record.sent else 0.0,
    ]


#: The contact wrench's low-pass by default [Hz] ... The combined law's derivative (K1) turns
#: the sensor's noise into velocity, more the wider the filter (its spread grows as the cutoff
#: to the power 3/2), and a soft surface under the load feels each jolt; a narrow filter's lag
#: makes a stiff contact ring instead. On the twin's Net F/T (0.125 N of noise at 500 Hz) the
#: sponge placements (the paper's gains, the truth's calibration, a second under control after
#: settling) ended 0.002-0.015 N short at 10 Hz and 0.004-0.012 N at 5 Hz, never pressing
#: beyond the weight; at 20 Hz, stopping at settle, 0.004-0.043 N off, pressing up to 0.38 N.
#: On the book the FR3 twin pressed 1.85 N beyond the weight at 5 Hz (45 ms of lag in a loop
#: of 71 ms: 1 / (K2 * 1.4e5 N/m) at K2 = 0.1 mm/(s*N)), within 0.3 N at 10 Hz and 20 Hz.
FILTER_HZ = 10.0
#: ... and this with a law that does not differentiate the force (no K1 on an axis that
#: yields: the velocity and mass-damper-spring laws, the combined law with K1 = 0), where only
#: the lag counts. A delayed first-order loop rings once its delay passes 1/e of its time
#: constant: the 10 Hz filter's 22 ms with the twin's 3-4 cycles of round trip is about 0.4 of
#: the book's 71 ms, so a host's late reading tips it. The UR5e twin's book placement (K1 0,
#: K2 0.1 mm/(s*N), the true calibration), five runs each: at 10 Hz 0.04-0.55 N beyond the
#: weight (0.55 N with a reading 27 ms old), at 20 Hz 0.05-0.07 N (one run with readings up to
#: 39 ms old and 6.5 % missed periods).
INTEGRAL_FILTER_HZ = 20.0
#: ... and, with K1's derivative, at most this share of the sensor's sample rate: the filter's
#: time constant then spans three of the sensor's samples (1 / (2 pi rate / 20) = 3.2 sample
#: periods). A sensor slower than the loop (an FT 300's 100 Hz under a UR's 500 Hz) holds each
#: reading for several cycles, steps the filter must not pass to K1's derivative (a law without
#: one only integrates them).
FILTER_SHARE_OF_RATE = 1.0 / 20.0
#: How long ``run`` waits for a sensor to have measured its rate [s].
RATE_WAIT_S = 1.0
#: A reading stops the run as stale only when it is also older than this many of its sensor's
#: sample periods: a 100 Hz sensor's newest reading is up to 10 ms old before any transport,
#: and a USB serial adapter's latency timer (16 ms on FTDI's) adds to that; the twin's 100 Hz
#: FT 300 read 18.6 ms old at the 99th percentile on an idle host, against the default 20 ms.
STALE_SENSOR_PERIODS = 4


def filter_hz_for(sensor_rate_hz: float | None, *, differentiates: bool = True) -> float:
    """The contact wrench's low-pass for a sensor sampling at ``sensor_rate_hz`` [Hz] (None:
    not known) under a law that ``differentiates`` the force (a K1 term): :data:`FILTER_HZ`,
    or :data:`FILTER_SHARE_OF_RATE` of a slower sensor's rate; without one
    :data:`INTEGRAL_FILTER_HZ`."""
    if not differentiates:
        return INTEGRAL_FILTER_HZ
    if sensor_rate_hz is None:
        return FILTER_HZ
    return min(FILTER_HZ, FILTER_SHARE_OF_RATE * sensor_rate_hz)


def stale_after_s_for(limit_s: float, sensor_rate_hz: float | None) -> float:
    """The age at which a reading of a sensor sampling at ``sensor_rate_hz`` [Hz] (None: not
    known) is stale: ``limit_s`` [s], or :data:`STALE_SENSOR_PERIODS` of its periods if longer."""
    if sensor_rate_hz is None:
        return limit_s
    return max(limit_s, STALE_SENSOR_PERIODS / sensor_rate_hz)


def sensor_rate_hz(sensor: WrenchSensor, wait_s: float = RATE_WAIT_S) -> float | None:
    """The rate a sensor's samples come at [Hz], if it tells one
    (:class:`~ftcomp.hardware.protocols.ReportsRate`): takes its readings (``read_new``) for up
    to ``wait_s`` until it has seen enough to tell; None when it does not tell one or has not
    seen enough. Call it before a loop: the readings it takes are gone.

    Raises:
        HardwareError: the sensor faulted meanwhile.
    """
    if not isinstance(sensor, ReportsRate):
        return None
    deadline = time.monotonic() + wait_s
    while True:
        sensor.read_new()
        rate = sensor.sample_rate_hz
        if math.isfinite(rate) and rate > 0.0:
            return rate
        if time.monotonic() >= deadline:
            return None
        time.sleep(0.01)


@dataclass(frozen=True)
class AdmittanceConfig:
    """The admittance controller of a run, in SI units (see :mod:`ftcomp.control.laws`).

    Each field's unit and range are declared with it (:func:`~ftcomp.config_fields.param`);
    vectors are per axis ``[x, y, z, rx, ry, rz]``.

    Attributes:
        limits: the safety envelope (base-frame axes).
        law: which law (:data:`LAWS`).
        axes: the axes that yield to force (``"z"``, ``"x,y,z,rz"``).
        frame: the frame of ``axes``, the gains and ``wrench_desired``: ``"base"`` or
            ``"sensor"``.
        k1: K1 per axis [m/N on x, y, z; rad/(N*m) on rx, ry, rz], >= 0.
        k2: K2 per axis [m/(s*N); rad/(s*N*m)], >= 0.
        mass: the mass-damper-spring M per axis [kg; kg*m^2], > 0.
        damping: its D [N*s/m; N*m*s/rad], >= 0.
        stiffness: its K [N/m; N*m/rad], >= 0 (0: free).
        wrench_desired: F0 [N, N*m] in the control frame.
        filter_hz: the low-pass on the contact wrench [Hz], > 0; None: :func:`filter_hz_for`
            the sensor's sample rate and the law.
    """

    limits: SafetyLimits
    law: LawName = param("combined", choices=LAWS, help="admittance law")
    axes: str = param("z", help="axes that yield to force, e.g. z or x,y,z,rz")
    frame: ControlFrame = param(
        "base", choices=CONTROL_FRAMES, help="frame of the axes, gains and desired wrench"
    )
    k1: tuple[float, ...] = param(
        (1e-4, 1e-4, 1e-4, 0.0, 0.0, 0.0), ge=0.0, length=6, unit="m/N, rad/(N*m)", help="K1"
    )
    k2: tuple[float, ...] = param(
        (1e-3, 1e-3, 1e-3, 0.0, 0.0, 0.0),
        ge=0.0,
        length=6,
        unit="m/(s*N), rad/(s*N*m)",
        help="K2",
    )
    mass: tuple[float, ...] = param(
        (2.0,) * 6, gt=0.0, length=6, unit="kg, kg*m^2", help="mass-damper-spring M"
    )
    damping: tuple[float, ...] = param(
        (200.0,) * 6, ge=0.0, length=6, unit="N*s/m, N*m*s/rad", help="mass-damper-spring D"
    )
    stiffness: tuple[float, ...] = param(
        (0.0,) * 6, ge=0.0, length=6, unit="N/m, N*m/rad", help="mass-damper-spring K (0: free)"
    )
    wrench_desired: tuple[float, ...] = param(
        (0.0,) * 6, length=6, unit="N, N*m", help="desired contact wrench in the control frame"
    )
    filter_hz: float | None = param(
        None, gt=0.0, optional=True, unit="Hz", help="low-pass on the contact wrench"
    )

    def __post_init__(self) -> None:
        check_fields(self)
        try:
            selection_matrix(self.axes)  # names the bad axis
        except ParameterError as exc:
            raise ParameterError(f"axes: {exc}", field="axes") from None

    def differentiates_force(self) -> bool:
        """Whether the law turns the force's rate into velocity: a K1 on an axis that yields
        (the combined and position laws)."""
        if self.law not in ("combined", "position"):
            return False
        selected = np.diag(selection_matrix(self.axes)) > 0.0
        return bool(np.any(np.array(self.k1)[selected] > 0.0))

    def law_for(self) -> AdmittanceLaw:
        """The law with these gains and selection."""
        S = selection_matrix(self.axes)
        if self.law == "combined":
            return CombinedLaw(np.array(self.k1), np.array(self.k2), S)
        if self.law == "position":
            return PositionLaw(np.array(self.k1), S)
        if self.law == "velocity":
            return VelocityLaw(np.array(self.k2), S)
        return MassDamperSpringLaw(
            np.array(self.mass), np.array(self.damping), np.array(self.stiffness), S
        )

    def controller(
        self, period_s: float, sensor_rate_hz: float | None = None
    ) -> AdmittanceController:
        """The controller for a loop of period ``period_s`` [s] (the filter's sample time) on a
        sensor sampling at ``sensor_rate_hz`` [Hz] (None: not known): its wrench filter
        :attr:`filter_hz` or :func:`filter_hz_for` the rate and the law, its stale limit
        :func:`stale_after_s_for` the rate."""
        cutoff_hz = (
            self.filter_hz
            if self.filter_hz is not None
            else filter_hz_for(sensor_rate_hz, differentiates=self.differentiates_force())
        )
        stale_s = stale_after_s_for(self.limits.stale_after_s, sensor_rate_hz)
        return AdmittanceController(
            law=self.law_for(),
            wrench_filter=LowPassFilter(cutoff_hz, period_s),
            limits=dataclasses.replace(self.limits, stale_after_s=stale_s),
            frame=self.frame,
            wrench_desired=np.array(self.wrench_desired),
        )


@dataclass(frozen=True)
class RunConfig:
    """A compliant run.

    Attributes:
        admittance: the controller.
        duration_s: the longest run [s], > 0.
        settle: end once the selected force error has settled (None: run ``duration_s``).
        dry_run: compute and log every command, send none.
        max_late_cycles: periods the loop may fall behind the robot's schedule (stalls, net of the
            slack since) before the run stops, >= 1.
        online_load: weigh a grasped load online (rate: 1 / the robot's control period) and
            compensate it too once weighed; start with the gripper empty.
        track_bias: let the bias follow the sensor while the arm is still and free
            (:class:`~ftcomp.compensation.bias_tracking.BiasTracker`; not with
            ``online_load``). A steady contact lighter than its contact thresholds cannot be
            told from a bias change: keep it off for a run that presses less than that.
        accelerometer: take the tool's (and a weighed load's) acceleration from the sensor's
            accelerometer (a sensor that reports ``accel_x_m_s2``...: an IMU's), so a moving
            tool's linear inertial force is compensated too
            (:class:`~ftcomp.compensation.pipeline.WrenchPipeline`).
    """

    admittance: AdmittanceConfig
    duration_s: float = param(30.0, gt=0.0, unit="s", help="longest run")
    settle: SettleRule | None = None
    dry_run: bool = False
    max_late_cycles: int = param(
        10,
        ge=1,
        integer=True,
        help="periods the loop may fall behind the robot's schedule before it stops: stalls, "
        "net of the slack since",
    )
    online_load: bool = False
    track_bias: BiasTrackingConfig | None = None
    accelerometer: bool = False

    def __post_init__(self) -> None:
        if self.track_bias is not None and self.online_load:
            raise ParameterError(
                "track_bias and online_load: choose one", field=("track_bias", "online_load")
            )
        check_fields(self)

    @property
    def final_error_window_s(self) -> float:
        """How long the force error at the end is averaged over [s]: the settle rule's hold,
        or its default hold without a rule."""
        return self.settle.hold_s if self.settle is not None else DEFAULT_HOLD_S


@dataclass(frozen=True)
class RunResult:
    """How a run went.

    Attributes:
        outcome: :class:`~ftcomp.session.outcome.Outcome` ``DURATION``, ``SETTLED``,
            ``LOOP_LATE``, a protective stop of the controller, ``INTERRUPTED`` (Ctrl-C) or
            ``ERROR`` (a hardware or loop fault, see ``message``).
        message: what stopped it, one line ("" when it ended normally).
        cycles: control cycles run.
        duration_s: time from the first to the last logged cycle [s].
        period_s: the control period [s].
        travel_m: the sensor origin's displacement from start to end [m], base frame, (3,).
        final_error: the mean force error the controller acted on over the last
            :attr:`RunConfig.final_error_window_s` [N], control frame, (3,) (NaN: no cycle).
        log: the log's path.
        load_events: the online load's grasp, release and contact events (empty without it).
        timing: how the loop kept time (:class:`~ftcomp.hardware.pacing.TimingSummary`; its
            block is saved beside the log, :func:`~ftcomp.session.log.timing_path`).
        observer_dropped_rows: log rows the observers (MCAP, view) did not get: their queue
            was full.
        bias_correction: the tracked bias minus the calibration's at the end [N, N*m], (6,)
            (None: not tracking).
        bias_updates: cycles that moved the tracked bias.
        filter_hz: the contact wrench's low-pass the controller ran with [Hz].
        stale_after_s: the age at which a reading stopped the run [s] (:func:`stale_after_s_for`).
        temperature_outside: what a temperature bias model did with readings beyond its
            calibrated temperatures (held at the range's nearer end), one sentence; "" when
            there were none.
    """

    outcome: Outcome
    message: str
    cycles: int
    duration_s: float
    period_s: float
    travel_m: NDArray[np.float64] = field(repr=False)
    final_error: NDArray[np.float64] = field(repr=False)
    log: Path
    load_events: tuple[LoadEvent, ...] = ()
    timing: TimingSummary | None = None
    observer_dropped_rows: int = 0
    bias_correction: NDArray[np.float64] | None = field(default=None, repr=False)
    bias_updates: int = 0
    filter_hz: float = math.nan
    stale_after_s: float = math.nan
    temperature_outside: str = ""

    @property
    def faulted(self) -> bool:
        """Whether the run ended on a fault (the robot was stopped): not by its duration or a
        settled contact (:attr:`~ftcomp.session.outcome.Outcome.faulted`)."""
        return self.outcome.faulted


class _Summary:
    """Start and end figures of a run, kept as the rows go by (no copy of the log)."""

    def __init__(self, window_s: float) -> None:
        self.window_ns = round(window_s * 1e9)
        self.p0: NDArray[np.float64] | None = None
        self.p = np.full(3, math.nan)
        self.recent: deque[tuple[int, NDArray[np.float64]]] = deque()
        self.t0_ns: int | None = None
        self.t_ns = 0

    def add(self, record: CycleRecord) -> None:
        r = record.reading
        if self.t0_ns is None:
            self.t0_ns, self.p0 = r.now_ns, r.p_base_sensor
        self.t_ns, self.p = r.now_ns, r.p_base_sensor
        self.recent.append((r.now_ns, record.error[:3]))
        while self.recent and self.recent[0][0] < r.now_ns - self.window_ns:
            self.recent.popleft()

    def figures(self) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
        if self.p0 is None or self.t0_ns is None:
            return 0.0, np.zeros(3), np.full(3, math.nan)
        errors = np.array([e for _, e in self.recent])
        with np.errstate(invalid="ignore"):
            final = np.nanmean(np.where(np.isfinite(errors), errors, np.nan), axis=0)
        return (self.t_ns - self.t0_ns) * 1e-9, self.p - self.p0, final


def _tell_end(
    log: CsvLog,
    t0_ns: int,
    end_ns: int,
    load: LoadTracker | None,
    outcome: Outcome,
    message: str,
) -> None:
    """The run's events for its observers: the online load's, then how it ended."""
    for event in load.events if load is not None else []:
        log.event(t0_ns + round(event.confirmed_t_s * 1e9), event.kind, event.describe())
    kind = "fault" if outcome.faulted else "end"
    log.event(end_ns, kind, f"{outcome}: {message}" if message else outcome)


def run_compliant(
    robot: Robot,
    sensor: WrenchSensor,
    calibration: Calibration | GravityModel,
    config: RunConfig,
    log_path: Path,
    *,
    mount: Mount | None = None,
    source: str = "the calibration",
    observers: Sequence[LogObserver] = (),
) -> RunResult:
    """Run the compliant loop until the run ends; the robot is stopped on any exit.

    Args:
        robot: the arm (entered). A robot whose control must be taken first
            (:class:`~ftcomp.hardware.protocols.TakesControl`, a UR uploading its script) is
            taken before the loop, unless ``config.dry_run``.
        sensor: the F/T sensor (entered), on the robot's clock.
        calibration: the identified calibration (bias, tool, tilt, and a mount or drift if it
            has them) to compensate with, or a bare gravity model.
        config: the run.
        log_path: the CSV log (:data:`RUN_COLUMNS`, with ``online_load`` then
            :data:`~ftcomp.compensation.online.LOAD_COLUMNS`, with the bias tracked
            ``bias_updated``, from a sensor with extra channels
            (:class:`~ftcomp.hardware.protocols.ReportsExtraChannels`) their values in the frame
            of the cycle's wrench), written atomically; the caller checks it may be written.
        mount: the sensor frame on the TCP (identity by default).
        source: names the calibration in errors.
        observers: see every log row (stamped with the cycle's ``now_ns``) and the events (the
            online load's, the end and why), on a worker thread (an MCAP log, a live view).

    Returns:
        The result; a fault, a lost connection or Ctrl-C end the run with the robot stopped
        and the log kept (``outcome`` and ``message`` say what happened).

    Raises:
        ParameterError: a calibration the online load estimate cannot use; one whose bias
            follows the sensor's temperature with a sensor that reports none.
    """
    if config.online_load:
        require_tool_weight(calibration, source)
    period_s = robot.control_period_s
    tracker = BiasTracker(config.track_bias) if config.track_bias is not None else None
    # the sensor's extra channels: a bias that follows the temperature reads it from them
    # (a sensor without them is refused here, before the robot is taken)
    channels = sensor.extra_channels if isinstance(sensor, ReportsExtraChannels) else ()
    pipeline = (  # weighing: one call per cycle
        WrenchPipeline.weighing(
            calibration,
            1.0 / period_s,
            extra_channels=channels,
            accelerometer=config.accelerometer,
        )
        if config.online_load
        else WrenchPipeline(
            GravityCompensator(calibration),
            bias_tracker=tracker,
            extra_channels=channels,
            accelerometer=config.accelerometer,
        )
    )
    if isinstance(robot, TakesControl) and not config.dry_run:
        robot.connect_control()  # before the loop: it takes a while (a UR uploads its script)
    controller = config.admittance.controller(period_s, sensor_rate_hz(sensor))
    wrench_filter = controller.wrench_filter
    load = pipeline.load
    cycle = ControlCycle(robot, sensor, mount=mount, pipeline=pipeline)
    columns = (*RUN_COLUMNS, *LOAD_COLUMNS) if load is not None else RUN_COLUMNS
    if tracker is not None:
        columns = (*columns, "bias_updated")
    columns = (*columns, *channels)
    summary = _Summary(config.final_error_window_s)
    outcome, message = Outcome.DURATION, ""
    with (
        InterruptHold() as hold,
        csv_log(log_path, columns, digits=17, observers=observers) as log,
    ):
        t0_ns: list[int] = []
        # The cycles' records wait for the period's slack: their rows are built and written
        # after the command has been sent (run_loop's in_slack), not on the command's path.
        pending: deque[CycleRecord] = deque()

        def log_pending() -> None:
            while pending:
                record = pending.popleft()
                r = record.reading
                if not t0_ns:
                    t0_ns.append(r.now_ns)
                row = cycle_row(record, t0_ns[0])
                t_s = row[0]
                if load is not None:
                    row += load.update(t_s)
                if tracker is not None:  # the same cycle's: the next read has not run yet
                    row.append(1.0 if tracker.updated else 0.0)
                if channels:
                    row += r.extras
                log.write(row, r.now_ns)
                summary.add(record)

        step = CompliantStep(
            controller,
            robot,
            config.duration_s,
            pending.append,
            settle=config.settle,
            dry_run=config.dry_run,
            max_late_cycles=config.max_late_cycles,
        )
        clock = loop_clock(robot, "ftcomp run")
        try:
            run_loop(cycle, step, clock=clock, in_slack=(log_pending,))
            outcome = step.outcome
        except KeyboardInterrupt:
            outcome, message = Outcome.INTERRUPTED, "interrupted (Ctrl-C)"
        except FtcompError as exc:
            outcome, message = Outcome.ERROR, str(exc)
        hold.finishing(f"finishing the log {log_path}")
        if not message and outcome is Outcome.LOOP_LATE:
            message = (
                f"loop late: the loop fell {config.max_late_cycles} periods behind the robot's "
                f"schedule "
                f"(worst start {clock.summary().lateness_max_s * 1e3:.1f} ms late)"
            )
        elif not message and step.faulted:
            message = f"protective stop: {outcome}"
        log_pending()  # the last cycle's row, and one kept when the loop ended by an exception
        if observers:
            _tell_end(log, t0_ns[0] if t0_ns else 0, summary.t_ns, load, outcome, message)
        loop_timing = clock.summary()
        save_timing(log_path, loop_timing, log=log)
        dropped = log.dropped_rows
    duration_s, travel_m, final_error = summary.figures()
    return RunResult(
        outcome=outcome,
        message=message,
        cycles=step.cycles,
        duration_s=duration_s,
        period_s=period_s,
        travel_m=travel_m,
        final_error=final_error,
        log=log_path,
        load_events=tuple(load.events) if load is not None else (),
        timing=loop_timing,
        observer_dropped_rows=dropped,
        bias_correction=tracker.correction.copy() if tracker is not None else None,
        bias_updates=tracker.updates if tracker is not None else 0,
        temperature_outside=pipeline.temperature_outside(),
        filter_hz=wrench_filter.cutoff_hz if wrench_filter is not None else math.nan,
        stale_after_s=controller.limits.stale_after_s,
    )
