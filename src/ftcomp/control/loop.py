"""One control loop for every command that runs one: a cycle, a step and the loop's clock.

A cycle is ``read sensor and pose -> compensate -> step -> command -> log``:

- :class:`ControlCycle` does the I/O around the step: it reads the newest wrench (or every
  reading since the last cycle) and the robot's pose, turns the TCP pose into the sensor's
  through the :class:`~ftcomp.hardware.protocols.Mount`, puts the reading through the cycle's one
  :class:`~ftcomp.compensation.pipeline.WrenchPipeline` (bias and gravity or a load weighed
  online, then bias tracking: computed once, here, and only read after), and sends a
  sensor-origin twist to the robot as a TCP twist.
- The *step* is any callable ``step(reading) -> twist | None``: the admittance controller of a
  placement, a recorder that commands nothing, an online estimator. ``None`` ends the loop.
- *Sinks* are callables ``sink(reading, twist)`` run after the step, on the loop's thread (a
  ROS 2 publisher). Logs, MCAP, live views and progress are not sinks: a session hands its log
  rows to its observers on their worker thread (:class:`~ftcomp.session.log.ObserverThread`).
- :func:`run_loop` runs cycles until the step says stop; on any exit (also an exception or
  Ctrl-C) it stops the robot first.

Timing stays apart from computing: the robot's ``wait_cycle`` paces the loop (the simulated cell
advances its physics by one period; a hardware robot waits on its pacer, which keeps how far the
loop has fallen behind: :class:`~ftcomp.hardware.protocols.ReportsLateness`), and the loop's
:class:`~ftcomp.hardware.pacing.LoopClock` times every cycle and, on the host's clock, keeps the
collector out of the cycles and asks for real-time scheduling (time is kept in one place,
:mod:`ftcomp.hardware.pacing`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ftcomp.compensation.bias_tracking import BiasTracker
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.compensation.pipeline import Compensated, WrenchPipeline
from ftcomp.errors import ParameterError
from ftcomp.hardware.pacing import LoopClock, TimingSummary, on_host_clock
from ftcomp.hardware.protocols import (
    Mount,
    ReportsExtraChannels,
    ReportsLateness,
    Robot,
    WrenchSensor,
)

__all__ = ["ControlCycle", "LoopStats", "Reading", "loop_clock", "run_loop"]

Step = Callable[["Reading"], "NDArray[np.float64] | None"]
Sink = Callable[["Reading", "NDArray[np.float64]"], None]


@dataclass(frozen=True, slots=True)
class Reading:
    """What one cycle read, in the frames the controller works in.

    A cycle that takes every reading (``ControlCycle(every_reading=True)``) hands them on in
    :attr:`new`, each compensated once; its own wrench fields are then the newest of them (with
    none new this cycle, the last cycle's; before the first, the raw reading and a NaN contact).

    Attributes:
        t_sample_ns: the wrench sample's stamp [ns] (session clock).
        now_ns: the robot's clock when the cycle read [ns].
        wrench_raw_sensor: the reading [N, N*m], sensor frame, (6,).
        wrench_contact_sensor: the compensated wrench (the raw reading without a compensator)
            [N, N*m], sensor frame, (6,); may be non-finite when the sensor sent garbage.
        p_base_sensor: sensor origin [m], base frame, (3,).
        R_base_sensor: sensor orientation, (3, 3).
        R_base_tcp: TCP orientation, (3, 3) (for the mount's twist conversion).
        new: every reading since the last cycle, through the pipeline, in time order (empty
            unless the cycle takes every reading).
        extras: the sensor's extra channels in the frame of this wrench
            (:attr:`~ftcomp.hardware.protocols.WrenchSample.extras`; empty without them).
    """

    t_sample_ns: int
    now_ns: int
    wrench_raw_sensor: NDArray[np.float64]
    wrench_contact_sensor: NDArray[np.float64]
    p_base_sensor: NDArray[np.float64]
    R_base_sensor: NDArray[np.float64]
    R_base_tcp: NDArray[np.float64]
    new: tuple[Compensated, ...] = ()
    extras: tuple[float, ...] = ()


class ControlCycle:
    """The I/O of one control cycle around a step (see the module docstring).

    Args:
        robot: the arm (entered).
        sensor: the F/T sensor (entered), on the robot's clock.
        mount: the sensor frame on the TCP (identity by default).
        compensator: removes bias and tool gravity with the identified calibration; None passes
            the raw reading on (the paper's uncompensated comparison).
        bias_tracker: follows the bias while the arm is still and free, after the compensator
            (None: the calibration's bias).
        pipeline: the wrench pipeline itself, instead of ``compensator`` and ``bias_tracker``
            (:meth:`~ftcomp.compensation.pipeline.WrenchPipeline.weighing`: a load weighed
            online at a rate measured from the readings).
        every_reading: take every reading the sensor delivered since the last cycle
            (``sensor.read_new()``, those from before the first cycle dropped), each through the
            pipeline, into :attr:`Reading.new` (a stream or a recorder at the sensor's rate);
            False: the newest reading only, once per cycle (a control loop).

    Attributes:
        pipeline: the cycle's :class:`~ftcomp.compensation.pipeline.WrenchPipeline`.
    """

    def __init__(
        self,
        robot: Robot,
        sensor: WrenchSensor,
        *,
        mount: Mount | None = None,
        compensator: GravityCompensator | None = None,
        bias_tracker: BiasTracker | None = None,
        pipeline: WrenchPipeline | None = None,
        every_reading: bool = False,
    ) -> None:
        if pipeline is not None and (compensator is not None or bias_tracker is not None):
            raise ParameterError("give a pipeline or its compensator and bias tracker, not both")
        self.robot = robot
        self.sensor = sensor
        self.mount = mount if mount is not None else Mount()
        channels = sensor.extra_channels if isinstance(sensor, ReportsExtraChannels) else ()
        self.pipeline = (
            pipeline
            if pipeline is not None
            else WrenchPipeline(compensator, bias_tracker=bias_tracker, extra_channels=channels)
        )
        self.every_reading = every_reading
        self.period_s = robot.control_period_s
        self._newest: Compensated | None = None
        self._started = False

    def read(self) -> Reading:
        """Read the newest wrench (or every new one) and the pose, through the pipeline."""
        if self.every_reading:
            return self._read_every()
        sample = self.sensor.read()
        pose = self.robot.pose()
        p, R = self.mount.sensor_pose(pose.p_base_tcp, pose.R_base_tcp)
        w = sample.wrench_sensor
        contact = self.pipeline.contact(sample.t_ns, w, R, sample.extras)
        return Reading(sample.t_ns, pose.t_ns, w, contact, p, R, pose.R_base_tcp, (), sample.extras)

    def _read_every(self) -> Reading:
        sensor = self.sensor
        sample = sensor.read()
        pose = self.robot.pose()
        p, R = self.mount.sensor_pose(pose.p_base_tcp, pose.R_base_tcp)
        if not self._started:  # the readings from the loop's start on
            sensor.read_new()
            self._started = True
        pipeline = self.pipeline
        for s in sensor.read_new():
            pipeline.push(s.t_ns, s.wrench_sensor, R, p, s.extras)
        new = tuple(pipeline.ready)
        pipeline.ready.clear()
        if new:
            self._newest = new[-1]
        last = self._newest
        if last is None:
            raw, contact, t_ns = sample.wrench_sensor, np.full(6, np.nan), sample.t_ns
            extras = sample.extras
        else:
            raw, contact, t_ns = last.wrench_raw_sensor, last.wrench_contact_sensor, last.t_ns
            extras = last.extras
        return Reading(t_ns, pose.t_ns, raw, contact, p, R, pose.R_base_tcp, new, extras)

    def command(self, twist_sensor_base: NDArray[np.float64], reading: Reading) -> None:
        """Send the sensor origin's twist (base frame) to the robot as its TCP's twist."""
        self.robot.command_twist(self.mount.tcp_twist(twist_sensor_base, reading.R_base_tcp))

    def advance(self) -> None:
        """Wait for (or simulate) the next period: the robot's ``wait_cycle``."""
        self.robot.wait_cycle()


@dataclass(frozen=True)
class LoopStats:
    """How a loop ran: the cycles run and how it kept time
    (:class:`~ftcomp.hardware.pacing.TimingSummary`)."""

    cycles: int
    timing: TimingSummary


def loop_clock(robot: Robot, name: str = "control loop", *, log_late: bool = True) -> LoopClock:
    """The clock of a loop on ``robot``: its control period, paced when the robot is on the
    host's clock (a simulated cell's loop is only timed); ``log_late``: as
    :class:`~ftcomp.hardware.pacing.LoopTiming`."""
    return LoopClock(
        robot.control_period_s, paced=on_host_clock(robot), name=name, log_late=log_late
    )


def run_loop(
    cycle: ControlCycle,
    step: Step,
    *,
    sinks: Sequence[Sink] = (),
    max_cycles: int | None = None,
    clock: LoopClock | None = None,
    in_slack: Sequence[Callable[[], None]] = (),
) -> LoopStats:
    """Run cycles until ``step`` returns None (or ``max_cycles``); stop the robot on any exit.

    Each cycle: ``reading = cycle.read()``, ``twist = step(reading)``, every sink
    ``sink(reading, twist)``, ``cycle.command(twist)``, every ``in_slack()``,
    ``cycle.advance()``. When the step returns None the sinks do not run and nothing is
    commanded. ``in_slack`` is work the cycle owes but the command need not wait for (a log
    row's formatting, :meth:`~ftcomp.session.log.CsvLog.write_later`): it runs after the
    command has been sent, in the period's slack, before the collection the clock runs there.

    The loop runs inside its ``clock`` (:class:`~ftcomp.hardware.pacing.LoopClock`; default
    :func:`loop_clock` of the robot): every cycle timed, and on the host's clock the collector
    kept out of the cycles and real-time scheduling asked for. Pass one to keep its figures
    when the loop ends by an exception. The robot's schedule
    (:class:`~ftcomp.hardware.protocols.ReportsLateness`) starts with the loop.
    """
    if clock is None:
        clock = loop_clock(cycle.robot)
    robot = cycle.robot
    n = 0
    with clock:
        try:
            # The schedules start with the loop: what came before it (the set-up, an earlier
            # loop on the same robot) is no stall.
            if isinstance(robot, ReportsLateness):
                robot.restart_schedule()
            while max_cycles is None or n < max_cycles:
                clock.start()
                reading = cycle.read()
                twist = step(reading)
                if twist is None:
                    break
                for sink in sinks:
                    sink(reading, twist)
                cycle.command(twist, reading)
                clock.sent(robot.now_ns() - reading.t_sample_ns)
                for later in in_slack:
                    later()
                clock.collect()
                cycle.advance()
                n += 1
        finally:
            robot.stop()  # first, before the clock gives the collector back
    return LoopStats(n, clock.summary())
