"""A sensor stream logged live: ``ftcomp stream`` as one library call.

:func:`stream` takes an entered robot and sensor and logs every reading the sensor delivers until
the duration is up, the recording ends (a replay) or a fault or Ctrl-C stops it, and returns a
:class:`StreamResult`. It commands nothing (a zero twist every cycle); every cycle it takes every
new reading (``sensor.read_new``), so the log has the sensor's rate whatever the loop's, one row
per reading (:func:`stream_columns`): the raw wrench and, with a pose, the sensor's orientation
and origin (a valid sample CSV); with a calibration the contact wrench; with ``online_load`` the
contact wrench with a grasped load weighed online and removed, and the load estimate; from a
sensor with extra channels (:class:`~ftcomp.hardware.protocols.ReportsExtraChannels`: its
temperature, an IMU) their values in each reading's frame, last. The loop's
cycle takes every reading and puts each through its one wrench pipeline
(:class:`~ftcomp.compensation.pipeline.WrenchPipeline`, as ``ftcomp run``'s cycle does with its
newest); the stream only logs what the cycle computed.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration_record import Calibration
from ftcomp.compensation.bias_tracking import BiasTracker, BiasTrackingConfig
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.compensation.online import LOAD_COLUMNS, LoadEvent
from ftcomp.compensation.pipeline import Compensated, WrenchPipeline
from ftcomp.config_fields import check_fields, param
from ftcomp.control.loop import ControlCycle, Reading, loop_clock, run_loop
from ftcomp.errors import FtcompError, ParameterError
from ftcomp.frames import quat_from_matrix
from ftcomp.hardware.pacing import TimingSummary
from ftcomp.hardware.protocols import (
    CountsLostPackets,
    Mount,
    ReportsExtraChannels,
    ReportsStreamHealth,
    Robot,
    StreamHealth,
    WrenchSensor,
)
from ftcomp.hardware.replay import EndOfReplayError
from ftcomp.model import GravityModel
from ftcomp.samples import WRENCH_COLUMNS
from ftcomp.session.interrupts import InterruptHold
from ftcomp.session.log import LogObserver, csv_log, save_timing
from ftcomp.session.online_load import require_tool_weight
from ftcomp.session.outcome import Outcome

__all__ = [
    "StreamConfig",
    "StreamLogger",
    "StreamProgress",
    "StreamResult",
    "stream",
    "stream_columns",
]

Row = Sequence[float]


def stream_columns(
    *,
    with_pose: bool,
    compensated: bool,
    online_load: bool = False,
    tracked: bool = False,
    extras: tuple[str, ...] = (),
) -> tuple[str, ...]:
    """Columns of ``ftcomp stream``'s log: ``t`` [s, session clock], the raw wrench, with a pose
    the sensor's orientation (``qx,qy,qz,qw``) and origin (``px,py,pz`` [m], base frame), when
    compensating the contact wrench ``cfx..ctz``, and with ``online_load`` (compensating) the
    load estimate (:data:`~ftcomp.compensation.online.LOAD_COLUMNS`), with the bias tracked
    ``bias_updated`` (1 in a row whose reading moved the tracked bias), then the sensor's
    ``extras`` (:attr:`~ftcomp.hardware.protocols.ReportsExtraChannels.extra_channels`,
    ``temperature_C``...). With a pose it is a valid sample CSV."""
    pose = ("qx", "qy", "qz", "qw", "px", "py", "pz") if with_pose else ()
    contact = tuple(f"c{c}" for c in WRENCH_COLUMNS) if compensated or online_load else ()
    load = LOAD_COLUMNS if online_load else ()
    tracking = ("bias_updated",) if tracked else ()
    return ("t", *WRENCH_COLUMNS, *pose, *contact, *load, *tracking, *extras)


class StreamLogger:
    """A stream's step: logs every reading its cycle hands on (:attr:`~ftcomp.control.loop.
    Reading.new`, each through the cycle's pipeline) stamped less than ``duration_s`` after the
    first cycle, on the session's clock (the cycle that finds the time over still logs those
    that came before it).

    Args:
        write_row: called with each row (see :func:`stream_columns`).
        duration_s: how long to log [s].
        with_pose: log the sensor's pose (the robot reports one).
        compensated: log the contact wrench.
        online: log the online load's columns.
        tracked: log whether each reading moved the tracked bias.
        extras: log each reading's extra channels (its sensor's, last).
    """

    def __init__(
        self,
        write_row: Callable[[Row], None],
        duration_s: float,
        *,
        with_pose: bool,
        compensated: bool = False,
        online: bool = False,
        tracked: bool = False,
        extras: bool = False,
    ) -> None:
        if not (math.isfinite(duration_s) and duration_s > 0.0):
            raise ParameterError(f"the duration must be > 0 s, got {duration_s}")
        self.write_row, self.with_pose = write_row, with_pose
        self.compensated, self.online, self.tracked = compensated or online, online, tracked
        self.extras = extras
        self.duration_ns = round(duration_s * 1e9)
        self.t0_ns: int | None = None
        self.count = 0
        #: Readings logged that moved the tracked bias.
        self.bias_updates = 0
        self.elapsed_s = 0.0
        self.contact_force_N = math.nan
        self._zero = np.zeros(6)
        self._pose_of: NDArray[np.float64] | None = None
        self._pose: list[float] = []

    def __call__(self, r: Reading) -> NDArray[np.float64] | None:
        """Log the readings that arrived since the previous cycle."""
        if self.t0_ns is None:
            self.t0_ns = r.now_ns
        self.elapsed_s = (r.now_ns - self.t0_ns) * 1e-9
        over = r.now_ns - self.t0_ns >= self.duration_ns
        self.log(r.new)
        return None if over else self._zero

    def log(self, readings: Sequence[Compensated]) -> None:
        """Log readings through the pipeline, those stamped before the end (however late the
        cycle that hands them on)."""
        end_ns = (self.t0_ns or 0) + self.duration_ns
        for c in readings:
            if c.t_ns >= end_ns:
                continue
            row = [c.t_ns * 1e-9, *c.wrench_raw_sensor.tolist()]
            if self.with_pose:
                if c.R_base_sensor is not self._pose_of:  # one pose per cycle
                    self._pose_of = c.R_base_sensor
                    self._pose = [*quat_from_matrix(c.R_base_sensor), *c.p_base_sensor.tolist()]
                row += self._pose
            if self.compensated:
                contact = c.wrench_contact_sensor
                row += contact.tolist()
                self.contact_force_N = float(np.linalg.norm(contact[:3]))
            if self.online:
                row += c.load
            if self.tracked:
                row.append(1.0 if c.bias_updated else 0.0)
                self.bias_updates += 1 if c.bias_updated else 0
            if self.extras:
                row += c.extras
            self.count += 1
            self.write_row(row)


@dataclass(frozen=True)
class StreamConfig:
    """A stream.

    Attributes:
        duration_s: how long to log [s], > 0.
        with_pose: log the sensor's pose (the robot must report one).
        online_load: weigh a grasped load online and compensate it too (needs a calibration).
        online_rate_hz: the readings' rate for the online estimate [Hz]; None: measured from
            the stamps of the first readings (held back, then logged).
        progress_period_s: how often ``on_progress`` is called [s].
        track_bias: let the bias follow the sensor while the arm is still and free
            (:class:`~ftcomp.compensation.bias_tracking.BiasTracker`; needs a calibration, not
            with ``online_load``); None: the calibration's bias.
        accelerometer: take the tool's (and a weighed load's) acceleration from the sensor's
            accelerometer (a sensor that reports ``accel_x_m_s2``...: an IMU's), so a moving
            tool's linear inertial force is compensated too
            (:class:`~ftcomp.compensation.pipeline.WrenchPipeline`).
    """

    duration_s: float = param(gt=0.0, unit="s", help="how long to log")
    with_pose: bool = True
    online_load: bool = False
    online_rate_hz: float | None = param(
        None,
        gt=0.0,
        le=100_000.0,
        optional=True,
        unit="Hz",
        help="the sensor's sample rate, which times the grasp detector's windows",
    )
    progress_period_s: float = param(0.25, gt=0.0, unit="s", help="how often to call on_progress")
    track_bias: BiasTrackingConfig | None = None
    accelerometer: bool = False

    def __post_init__(self) -> None:
        check_fields(self)
        if self.online_rate_hz is not None and not self.online_load:
            raise ParameterError(
                "online_rate_hz needs online_load", field=("online_rate_hz", "online_load")
            )
        if self.track_bias is not None and self.online_load:
            raise ParameterError(
                "track_bias and online_load: choose one", field=("track_bias", "online_load")
            )


@dataclass(frozen=True)
class StreamProgress:
    """Where a stream is (for a live status line).

    Attributes:
        readings: readings logged so far.
        elapsed_s: time since the start [s].
        duration_s: the planned duration [s].
        contact_force_N: the latest contact force's norm [N] (NaN: not compensating).
        lost_packets: packets the sensor lost so far (None: it cannot tell).
        load: the online load's state, one short text ("" without it).
    """

    readings: int
    elapsed_s: float
    duration_s: float
    contact_force_N: float
    lost_packets: int | None
    load: str


@dataclass(frozen=True)
class StreamResult:
    """How a stream went.

    Attributes:
        outcome: :class:`~ftcomp.session.outcome.Outcome` ``DURATION``, ``END_OF_REPLAY`` (a
            recording ran out), ``INTERRUPTED`` (Ctrl-C) or ``ERROR`` (a sensor or connection
            fault, see ``message``).
        message: what stopped it, one line ("" when it ended normally).
        readings: readings logged (the log's rows).
        elapsed_s: the session's duration [s].
        log: the log's path.
        health: the sensor's own account of its stream at the end (lost and received packets,
            ...), None when it gives none.
        online_rate_hz: the rate the online load estimate used [Hz] (NaN without it).
        online_rate_source: how that rate was found ("" without it).
        load_events: the online load's grasp, release and contact events.
        timing: how the loop kept time (its block is saved beside the log,
            :func:`~ftcomp.session.log.timing_path`).
        observer_dropped_rows: log rows the observers did not get (their queue was full).
        bias_correction: the tracked bias minus the calibration's at the end [N, N*m], (6,)
            (None: not tracking).
        bias_updates: readings logged that moved the tracked bias.
        temperature_outside: what a temperature bias model did with readings beyond its
            calibrated temperatures (held at the range's nearer end), one sentence; "" when
            there were none.
    """

    outcome: Outcome
    message: str
    readings: int
    elapsed_s: float
    log: Path
    health: StreamHealth | None = None
    online_rate_hz: float = math.nan
    online_rate_source: str = ""
    load_events: tuple[LoadEvent, ...] = ()
    timing: TimingSummary | None = None
    observer_dropped_rows: int = 0
    bias_correction: NDArray[np.float64] | None = field(default=None, repr=False)
    bias_updates: int = 0
    temperature_outside: str = ""

    @property
    def rate_hz(self) -> float:
        """Readings per second (NaN for no time)."""
        return self.readings / self.elapsed_s if self.elapsed_s > 0.0 else math.nan

    @property
    def faulted(self) -> bool:
        """Whether a fault or Ctrl-C ended it (:attr:`~ftcomp.session.outcome.Outcome.faulted`)."""
        return self.outcome.faulted


class _Progress:
    """Progress as one more log observer (:class:`~ftcomp.session.log.LogObserver`): the rows
    it is handed on the observers' worker thread are its clock, ``where()`` what it reports."""

    def __init__(
        self,
        on_progress: Callable[[StreamProgress], None],
        where: Callable[[], StreamProgress],
        period_s: float,
    ) -> None:
        self.on_progress, self.where, self.period_s = on_progress, where, period_s
        self._last = time.monotonic()

    def open(self, columns: Sequence[str]) -> None:
        """Nothing to prepare."""

    def row(self, t_ns: int, row: Sequence[float]) -> None:
        """Report, if ``period_s`` has passed since the last report."""
        now = time.monotonic()
        if now - self._last >= self.period_s:
            self._last = now
            self.on_progress(self.where())

    def event(self, t_ns: int, kind: str, text: str) -> None:
        """Events are not progress."""

    def close(self) -> None:
        """Nothing to finish."""


def stream(
    robot: Robot,
    sensor: WrenchSensor,
    config: StreamConfig,
    log_path: Path,
    *,
    calibration: Calibration | GravityModel | None = None,
    mount: Mount | None = None,
    on_progress: Callable[[StreamProgress], None] | None = None,
    source: str = "the calibration",
    observers: Sequence[LogObserver] = (),
) -> StreamResult:
    """Log the sensor's readings until the duration is up (see the module docstring).

    Args:
        robot: the arm or pose source (entered); the robot is stopped on any exit.
        sensor: the F/T sensor (entered).
        config: the stream.
        log_path: the CSV log, written atomically (the caller checks it may be written).
        calibration: compensate with it (needs the sensor's pose).
        mount: the sensor frame on the TCP (identity by default).
        on_progress: called at most every ``config.progress_period_s`` with where the stream
            is, as a log row is handed on, on the observers' worker thread (off the loop's).
        source: names the calibration in errors.
        observers: see every log row (stamped with the reading's ``t_ns``) and the events (the
            online load's, the end and why), on a worker thread (an MCAP log, a live view).

    Raises:
        ParameterError: compensation or a pose asked of a robot that reports none, an online
            load estimate with a weightless tool, a calibration whose bias follows the
            sensor's temperature with a sensor that reports none, or ``accelerometer`` without a
            calibration or with a sensor that reports no acceleration.
    """
    knows_pose = robot.pose_known
    if calibration is not None and not knows_pose:
        raise ParameterError("compensation needs the sensor's pose: the robot reports none")
    if config.online_load:
        if calibration is None:
            raise ParameterError("the online load estimate needs the tool's calibration")
        require_tool_weight(calibration, source)
    with_pose = config.with_pose and knows_pose
    if config.track_bias is not None and calibration is None:
        raise ParameterError("tracking the bias needs the tool's calibration")
    tracker = BiasTracker(config.track_bias) if config.track_bias is not None else None
    # the sensor's extra channels: a bias that follows the temperature reads it from them
    channels = sensor.extra_channels if isinstance(sensor, ReportsExtraChannels) else ()
    if config.online_load and calibration is not None:
        pipeline = WrenchPipeline.weighing(
            calibration,
            config.online_rate_hz,
            extra_channels=channels,
            accelerometer=config.accelerometer,
        )
    else:
        compensator = GravityCompensator(calibration) if calibration is not None else None
        pipeline = WrenchPipeline(
            compensator,
            bias_tracker=tracker,
            extra_channels=channels,
            accelerometer=config.accelerometer,
        )
    online = config.online_load
    columns = stream_columns(
        with_pose=with_pose,
        compensated=calibration is not None,
        online_load=online,
        tracked=tracker is not None,
        extras=channels,
    )
    lost = sensor if isinstance(sensor, CountsLostPackets) else None

    def where() -> StreamProgress:  # read on the observers' thread: figures for display
        if pipeline.measuring:
            load = "measuring the rate"
        else:
            load = pipeline.load.status_text() if pipeline.load is not None else ""
        return StreamProgress(
            logger.count,
            logger.elapsed_s,
            config.duration_s,
            logger.contact_force_N,
            lost.lost_packets if lost is not None else None,
            load,
        )

    if on_progress is not None:
        observers = (*observers, _Progress(on_progress, where, config.progress_period_s))
    outcome, message = Outcome.DURATION, ""
    with InterruptHold() as hold, csv_log(log_path, columns, observers=observers) as log:
        logger = StreamLogger(
            log.write_later,  # formatted after the command (run_loop's slack)
            config.duration_s,
            with_pose=with_pose,
            compensated=calibration is not None,
            online=online,
            tracked=tracker is not None,
            extras=bool(channels),
        )

        cycle = ControlCycle(robot, sensor, mount=mount, pipeline=pipeline, every_reading=True)
        # A logger reads every reading buffered since its last cycle (every_reading): its late
        # cycles lose nothing, so they are counted in the timing but not logged one by one.
        clock = loop_clock(robot, "ftcomp stream", log_late=False)
        try:
            run_loop(cycle, logger, clock=clock, in_slack=(log.flush,))
        except EndOfReplayError:
            outcome = Outcome.END_OF_REPLAY
        except KeyboardInterrupt:
            outcome, message = Outcome.INTERRUPTED, "interrupted (Ctrl-C)"
        except FtcompError as exc:
            outcome, message = Outcome.ERROR, str(exc)
        finally:
            hold.finishing(f"finishing the log {log_path}")
            if logger.t0_ns is not None:  # the readings held back while the rate was measured
                pipeline.finish(logger.t0_ns + logger.duration_ns)
            logger.log(pipeline.ready)
            pipeline.ready.clear()
            log.flush()
        t0_ns = logger.t0_ns if logger.t0_ns is not None else 0
        logged_until_ns = t0_ns + logger.duration_ns  # the pipeline saw the readings after
        events = [
            e
            for e in (pipeline.load.events if pipeline.load is not None else [])
            if round(e.confirmed_t_s * 1e9) < logged_until_ns
        ]
        for event in events:  # stamped like the rows
            log.event(round(event.confirmed_t_s * 1e9), event.kind, event.describe())
        end_ns = t0_ns + round(logger.elapsed_s * 1e9)
        log.event(end_ns, "fault" if message else "end", message or outcome)
        loop_timing = clock.summary()
        save_timing(log_path, loop_timing, log=log)
        dropped = log.dropped_rows
    # The rows in the file, not the logger's count: a Ctrl-C between the count and the row
    # being kept (Python raises it at a call) would make them differ by one.
    readings = log.rows
    health = sensor.stream_health() if isinstance(sensor, ReportsStreamHealth) else None
    return StreamResult(
        outcome=outcome,
        message=message,
        readings=readings,
        elapsed_s=logger.elapsed_s,
        log=log_path,
        health=health,
        online_rate_hz=pipeline.rate_Hz,
        online_rate_source=pipeline.rate_source,
        load_events=tuple(events),
        timing=loop_timing,
        observer_dropped_rows=dropped,
        bias_correction=tracker.correction.copy() if tracker is not None else None,
        bias_updates=logger.bias_updates,
        temperature_outside=pipeline.temperature_outside(),
    )
