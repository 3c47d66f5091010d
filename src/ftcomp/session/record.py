"""A calibration recording session on a live cell, written to a sample CSV as it goes.

:func:`record` runs one session with a robot and a sensor the caller has opened (and entered),
in one of two ways given by the :class:`RecordConfig`'s plan:

- :class:`RobotDriven`: the robot moves through a :class:`~ftcomp.samples.PoseList` (blocking
  moves at its speed limit, every pose checked before the first move when the robot can tell,
  see :func:`ftcomp.session.robot_driven.record_poses`), waits until arm and readings are still
  and records ``samples_per_pose`` readings at each;
- :class:`HandGuided`: the user jogs or free-drives the arm; each period held still is recorded
  (:class:`ftcomp.session.hand_guided.ManualRecorder` in :func:`ftcomp.control.loop.run_loop`),
  one too close in orientation to an earlier pose is ignored.

The sample file is rewritten (atomically) after every pose, so Ctrl-C, a lost connection or a
sensor fault leaves a valid file with every pose recorded so far. The session then stops the
robot and returns a :class:`RecordResult` saying how it ended (an
:class:`~ftcomp.session.outcome.Outcome`: ``COMPLETE``, ``INTERRUPTED`` or ``ERROR`` with the
reason) and what it recorded. A failure before the
first pose is recorded (an unreachable pose, a silent sensor) is raised instead: there is
nothing to keep.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import get_args

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.arrays import freeze_field
from ftcomp.config_fields import check_fields, param
from ftcomp.control.loop import ControlCycle, loop_clock, run_loop
from ftcomp.errors import FtcompError, ParameterError
from ftcomp.frames import OrientationEncoding, quat_from_matrix
from ftcomp.hardware.pacing import WORKER_PRIORITY, LoopClock, TimingSummary, realtime_loop
from ftcomp.hardware.protocols import Mount, ReportsExtraChannels, Robot, WrenchSensor
from ftcomp.io.atomic import check_writable
from ftcomp.io.samples_csv import write_samples
from ftcomp.samples import PoseList, Samples
from ftcomp.session.hand_guided import ManualRecorder, StillCriteria
from ftcomp.session.interrupts import InterruptHold
from ftcomp.session.log import LogObserver, ObserverThread, save_timing
from ftcomp.session.outcome import Outcome
from ftcomp.session.pose_record import (
    PoseEvent,
    PoseRecord,
    WrenchTolerance,
    nearest_pose,
    samples_from_records,
)
from ftcomp.session.robot_driven import record_poses
from ftcomp.session.stream import stream_columns

__all__ = [
    "MAX_SAMPLES_PER_POSE",
    "HandGuided",
    "RecordConfig",
    "RecordResult",
    "RobotDriven",
    "record",
]

#: Most readings per pose (about 80 s of a 1.2 kHz sensor; memory stays under 1 GB).
MAX_SAMPLES_PER_POSE = 100_000

#: How a recording may end.
ENDINGS = (Outcome.COMPLETE, Outcome.INTERRUPTED, Outcome.ERROR)


@dataclass(frozen=True)
class RobotDriven:
    """The robot drives through poses.

    Attributes:
        poses: sensor orientations (and optionally positions) to visit, in order.
        samples_per_pose: readings recorded at each pose, in [2, :data:`MAX_SAMPLES_PER_POSE`].
        position_base_m: the sensor origin for poses without a position [m], base frame, (3,);
            None: where the sensor is when the session starts.
        move_duration_s: about how long each move takes [s] (the robot caps the speed).
        settle_max_s: longest wait for the arm to come to rest at a pose [s].
        tolerance: how little the readings may drift to count as settled.
        max_tries: recordings at one pose before giving up on a drifting wrench, >= 1.
    """

    poses: PoseList
    samples_per_pose: int = param(
        500,
        integer=True,
        ge=2,
        le=MAX_SAMPLES_PER_POSE,
        help="readings recorded at each pose",
    )
    position_base_m: NDArray[np.float64] | None = field(default=None, repr=False)
    move_duration_s: float = param(2.0, gt=0.0, unit="s", help="about how long a move takes")
    settle_max_s: float = param(5.0, gt=0.0, unit="s", help="longest wait for the arm to rest")
    tolerance: WrenchTolerance = field(default_factory=WrenchTolerance)
    max_tries: int = 5

    def __post_init__(self) -> None:
        if not isinstance(self.poses, PoseList):
            raise ParameterError(f"poses must be a PoseList, got {type(self.poses).__name__}")
        check_fields(self)
        if self.position_base_m is not None:
            freeze_field(self, "position_base_m", (3,), finite=True)
        if not isinstance(self.tolerance, WrenchTolerance):
            raise ParameterError("tolerance must be a WrenchTolerance")
        if not (isinstance(self.max_tries, int) and self.max_tries >= 1):
            raise ParameterError(f"max_tries must be an integer >= 1, got {self.max_tries!r}")

    @property
    def n_poses(self) -> int:
        """Poses to record."""
        return len(self.poses)


@dataclass(frozen=True)
class HandGuided:
    """The user moves the arm; each still period at a new orientation is recorded.

    Attributes:
        n_poses: poses to record, >= 3 (fewer cannot separate bias from gravity).
        still: when the arm counts as held still, and when a pose is new.
        samples_per_pose: readings kept per pose (the still window's last ones), as
            ``RobotDriven``'s; None:
            the last three quarters of the window.
    """

    n_poses: int
    still: StillCriteria = field(default_factory=StillCriteria)
    samples_per_pose: int | None = param(
        None,
        integer=True,
        ge=2,
        le=MAX_SAMPLES_PER_POSE,
        optional=True,
        help="readings kept per pose (the still window's last ones)",
    )

    def __post_init__(self) -> None:
        if not (isinstance(self.n_poses, int) and not isinstance(self.n_poses, bool)):
            raise ParameterError(f"n_poses must be an integer, got {self.n_poses!r}")
        if self.n_poses < 3:
            raise ParameterError(
                f"n_poses must be >= 3 to separate bias from gravity, got {self.n_poses}"
            )
        if not isinstance(self.still, StillCriteria):
            raise ParameterError("still must be a StillCriteria")
        check_fields(self)


@dataclass(frozen=True)
class RecordConfig:
    """One recording session.

    Attributes:
        output: the sample CSV to write (rewritten after every pose).
        plan: robot-driven poses or hand-guided still periods.
        encoding: the orientation columns to write.
        overwrite: whether an existing ``output`` may be replaced.
    """

    output: Path
    plan: RobotDriven | HandGuided
    encoding: OrientationEncoding = "quaternion"
    overwrite: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "output", Path(self.output))
        if not isinstance(self.plan, RobotDriven | HandGuided):
            raise ParameterError(
                f"plan must be RobotDriven or HandGuided, got {type(self.plan).__name__}"
            )
        if self.encoding not in get_args(OrientationEncoding):
            raise ParameterError(
                f"encoding must be one of {', '.join(get_args(OrientationEncoding))}, "
                f"got {self.encoding!r}"
            )


@dataclass(frozen=True)
class RecordResult:
    """How a session went.

    Attributes:
        output: the sample CSV (written when at least one pose was recorded).
        ended: :class:`~ftcomp.session.outcome.Outcome` ``COMPLETE`` (every planned pose),
            ``INTERRUPTED`` (Ctrl-C) or ``ERROR`` (a fault: see ``reason``).
        reason: why it ended early, one line ("" when complete).
        records: the poses recorded, in order (all of them are in ``output``).
        samples: the same readings as one :class:`~ftcomp.samples.Samples` (None without any).
        poses_planned: poses the plan asked for.
        duration_s: wall-clock time of the session [s].
        timing: how the hand-guided session's loop kept time (saved beside the output,
            :func:`~ftcomp.session.log.timing_path`); None for a robot-driven session, which
            runs no periodic loop (it moves, settles and reads).
    """

    output: Path
    ended: Outcome
    reason: str
    records: tuple[PoseRecord, ...] = field(repr=False)
    samples: Samples | None = field(repr=False)
    poses_planned: int
    duration_s: float
    timing: TimingSummary | None = None

    def __post_init__(self) -> None:
        if self.ended not in ENDINGS:
            raise ParameterError(f"ended must be one of {', '.join(ENDINGS)}, got {self.ended!r}")
        object.__setattr__(self, "ended", Outcome(self.ended))
        if (self.ended is Outcome.COMPLETE) != (self.reason == ""):
            raise ParameterError("a reason is given exactly when the session did not complete")
        if (self.samples is None) != (not self.records):
            raise ParameterError("samples are given exactly when poses were recorded")
        if not self.duration_s >= 0.0:
            raise ParameterError(f"duration_s must be >= 0, got {self.duration_s}")

    @property
    def faulted(self) -> bool:
        """Whether a fault or Ctrl-C ended it (:attr:`~ftcomp.session.outcome.Outcome.faulted`)."""
        return self.ended.faulted

    @property
    def poses_recorded(self) -> int:
        """Poses in the file."""
        return len(self.records)

    @property
    def readings(self) -> int:
        """Readings in the file, over all poses."""
        return sum(len(r.wrench_sensor) for r in self.records)


class _SampleFile:
    """The session's records, written out whole (atomically) after every new one."""

    def __init__(self, path: Path, encoding: OrientationEncoding) -> None:
        self.path, self.encoding = path, encoding
        self.records: list[PoseRecord] = []
        self.samples: Samples | None = None

    def add(self, record: PoseRecord) -> None:
        self.records.append(record)
        self.samples = samples_from_records(self.records, str(self.path))
        write_samples(
            self.path,
            self.samples.wrench_sensor,
            Rotation.from_matrix(self.samples.R_base_sensor),
            encoding=self.encoding,
            pose=self.samples.pose,
            t=self.samples.t,
            extras=self.samples.extras,
        )


#: The rows an observer of a recording sees: one per reading, as a stream with a pose logs it
#: (and the sensor's extra channels after them, :func:`~ftcomp.session.stream.stream_columns`).
OBSERVED_COLUMNS = stream_columns(with_pose=True, compensated=False)


def _observe(
    thread: ObserverThread,
    record: PoseRecord,
    number: int,
    planned: int,
    channels: tuple[str, ...],
) -> None:
    """Hand a recorded pose's readings to the observers, then the event."""
    pose = [*quat_from_matrix(record.R_base_sensor), *record.p_base_sensor.tolist()]
    extras = np.array([record.extras[name] for name in channels]).T.reshape(
        len(record.t_ns), len(channels)
    )
    rows = zip(record.t_ns.tolist(), record.wrench_sensor.tolist(), extras.tolist(), strict=True)
    for t_ns, w, e in rows:
        thread.row(t_ns, [t_ns * 1e-9, *w, *pose, *e])
    text = f"pose {number} of {planned} recorded ({record.pose_id})"
    thread.event(int(record.t_ns[-1]), "pose", text)


def _stop(robot: Robot) -> str:
    """Stop the robot; what went wrong doing so, or "" (after a fault the link may be gone)."""
    try:
        robot.stop()
    except FtcompError as exc:
        return f"stopping the robot failed: {exc}"
    return ""


def record(
    robot: Robot,
    sensor: WrenchSensor,
    config: RecordConfig,
    *,
    mount: Mount | None = None,
    on_event: Callable[[PoseEvent], None] | None = None,
    observers: Sequence[LogObserver] = (),
    on_skip: Callable[[str], None] | None = None,
) -> RecordResult:
    """Run a recording session (module docstring) and write its sample file as it goes.

    Args:
        robot: the arm (entered).
        sensor: the F/T sensor (entered), on the robot's clock.
        config: what to record and where.
        mount: the sensor frame on the TCP (identity by default).
        on_event: called with every :class:`~ftcomp.session.pose_record.PoseEvent` (a pose
            recorded, once it is in the file; a hand-guided still period ignored), e.g. to
            announce it.
        observers: see every recorded reading as a row (:data:`OBSERVED_COLUMNS`, then the
            sensor's extra channels; once its pose is in the file) and the events (each pose,
            the end), on a worker thread.
        on_skip: called with a line for each pose of a robot-driven plan left out because the
            robot cannot reach it (:func:`~ftcomp.session.robot_driven.record_poses`); the
            session goes on.

    Returns:
        The :class:`RecordResult`; on Ctrl-C or a fault after the first pose, with ``ended``
        saying so (the robot stopped, the file holding every pose recorded).

    Raises:
        ParameterError: ``config.output`` may not or cannot be written.
        FtcompError: the session failed before its first pose was recorded (an unreachable
            pose, nothing moved; a silent sensor; a lost connection).
    """
    output = check_writable(config.output, overwrite=config.overwrite)
    mount = mount if mount is not None else Mount()
    channels = sensor.extra_channels if isinstance(sensor, ReportsExtraChannels) else ()
    file = _SampleFile(output, config.encoding)
    plan = config.plan

    thread = ObserverThread(observers) if observers else None
    if thread is not None:
        thread.open((*OBSERVED_COLUMNS, *channels))

    def recorded(event: PoseEvent) -> None:
        if event.record is not None:
            file.add(event.record)
            if thread is not None:
                _observe(thread, event.record, len(file.records), plan.n_poses, channels)
        if on_event is not None:
            on_event(event)

    def driven(record: PoseRecord) -> None:
        _, angle = nearest_pose(file.records, record.R_base_sensor)
        recorded(PoseEvent("recorded", len(file.records) + 1, angle, record))

    start = time.monotonic()
    ended = Outcome.ERROR
    reason = "the session failed before its first pose"  # unless _run_plan returns
    clock = loop_clock(robot, "ftcomp record") if isinstance(plan, HandGuided) else None
    with InterruptHold() as hold:
        try:
            ended, reason = _run_plan(
                robot, sensor, plan, mount, driven, recorded, file, clock, on_skip
            )
        finally:
            hold.finishing(f"finishing {output}")
            if thread is not None:
                last_ns = int(file.records[-1].t_ns[-1]) if file.records else 0
                thread.event(last_ns, "fault" if ended.faulted else "end", reason or ended)
                thread.close()
        summary = clock.summary() if clock is not None and clock.timing.cycles else None
        if summary is not None and file.records:
            save_timing(output, summary)
    return RecordResult(
        output=output,
        ended=ended,
        reason=reason,
        records=tuple(file.records),
        samples=file.samples,
        poses_planned=plan.n_poses,
        duration_s=time.monotonic() - start,
        timing=summary,
    )


def _run_plan(
    robot: Robot,
    sensor: WrenchSensor,
    plan: RobotDriven | HandGuided,
    mount: Mount,
    driven: Callable[[PoseRecord], None],
    recorded: Callable[[PoseEvent], None],
    file: _SampleFile,
    clock: LoopClock | None,
    on_skip: Callable[[str], None] | None = None,
) -> tuple[Outcome, str]:
    """Record the plan; how it ended and why (see :func:`record`), the robot stopped."""
    ended = Outcome.COMPLETE
    reason = ""
    try:
        if isinstance(plan, RobotDriven):
            # No periodic loop, but the sensor's readers keep the device's pace: real-time
            # scheduling as a live loop's (realtime_loop), or a busy machine holds them off
            # until a serial sensor's bytes overflow its port's buffer (4 KB, 0.1 s of a Bota
            # Gen0 stream: a cut frame, a CRC fault) or a Net F/T is silent past its limit;
            # with two busy processes at nice 19 beside it, a Bota and an FT 300 RTU
            # recording broke in every try. Raising the readers alone was not enough (the
            # thread that holds the interpreter's lock must run too), and this thread waits in
            # a client library's blocking calls, so it runs at the workers' priority, not a
            # loop's: below the twin's threads, which answer those calls (at the loop's
            # priority, a UR twin's inverse kinematics once came too late beside another
            # worker's tests: a designed pose taken for unreachable).
            with realtime_loop(WORKER_PRIORITY):
                record_poses(
                    robot,
                    sensor,
                    plan.poses,
                    plan.samples_per_pose,
                    driven,
                    mount=mount,
                    position_base_m=plan.position_base_m,
                    move_duration_s=plan.move_duration_s,
                    settle_max_s=plan.settle_max_s,
                    tolerance=plan.tolerance,
                    max_tries=plan.max_tries,
                    on_skip=on_skip,
                )
        else:
            recorder = ManualRecorder(
                plan.n_poses,
                plan.still,
                recorded,
                samples_per_pose=plan.samples_per_pose,
                extra_channels=(
                    sensor.extra_channels if isinstance(sensor, ReportsExtraChannels) else ()
                ),
            )
            cycle = ControlCycle(robot, sensor, mount=mount, every_reading=True)
            run_loop(cycle, recorder, clock=clock)
    except KeyboardInterrupt:
        ended, reason = Outcome.INTERRUPTED, "interrupted (Ctrl-C)"
    except FtcompError as exc:
        if not file.records:
            _stop(robot)  # nothing to keep: the error is the answer
            raise
        ended, reason = Outcome.ERROR, str(exc)
    except BaseException:
        _stop(robot)  # anything else (a failed write, a bug): stop the arm, then let it through
        raise
    stopped = _stop(robot)
    if stopped:
        ended, reason = (
            (Outcome.ERROR, stopped)
            if ended is Outcome.COMPLETE
            else (ended, f"{reason}; {stopped}")
        )
    return ended, reason
