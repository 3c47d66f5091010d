"""One control loop for every command that runs one: a rate limiter and one cycle.

A cycle is ``read sensor and pose -> compensate -> step -> command -> log``:

- :class:`ControlCycle` does the I/O around the step: it reads the newest wrench and the robot's
  pose, turns the TCP pose into the sensor's through the :class:`~ftcomp.hardware.protocols.Mount`,
  compensates with the identified calibration (or passes the raw reading on), and sends a
  sensor-origin twist to the robot as a TCP twist.
- The *step* is any callable ``step(reading) -> twist | None``: the admittance controller of a
  placement, a recorder that commands nothing, an online estimator. ``None`` ends the loop.
- *Sinks* are callables ``sink(reading, twist)`` run after the step (logs, live displays).
- :func:`run_loop` runs cycles until the step says stop; on any exit (also an exception or
  Ctrl-C) it stops the robot first.

Timing stays apart from computing: the robot's ``wait_cycle`` paces the loop (the simulated cell
advances its physics by one period; a real robot's driver waits for its next period), and a
:class:`RateLimiter` on :func:`time.perf_counter` can hold a loop to wall-clock time where the
robot does not. The limiter reports its slack and logs overruns instead of raising; a loop that
falls too far behind is a fault for the caller to act on (:attr:`RateLimiter.periods_behind`).
"""

from __future__ import annotations

import gc
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ftcomp.compensation.bias_tracking import BiasTracker
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.control.timing import LoopTiming, TimingSummary
from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.pacing import RateLimiter, on_host_clock, realtime_loop
from ftcomp.hardware.protocols import Mount, ReportsLateness, Robot, WrenchSensor

__all__ = [
    "ControlCycle",
    "LoopOverrunError",
    "LoopStats",
    "LoopTiming",
    "RateLimiter",
    "Reading",
    "run_loop",
]

Step = Callable[["Reading"], "NDArray[np.float64] | None"]
Sink = Callable[["Reading", "NDArray[np.float64]"], None]


class LoopOverrunError(HardwareError):
    """The loop missed its period too many times in a row (the robot has been stopped)."""


@dataclass(frozen=True, slots=True)
class Reading:
    """What one cycle read, in the frames the controller works in.

    Attributes:
        t_sample_ns: the wrench sample's stamp [ns] (session clock).
        now_ns: the robot's clock when the cycle read [ns].
        wrench_raw_sensor: the reading [N, N*m], sensor frame, (6,).
        wrench_contact_sensor: the compensated wrench (the raw reading without a compensator)
            [N, N*m], sensor frame, (6,); may be non-finite when the sensor sent garbage.
        p_base_sensor: sensor origin [m], base frame, (3,).
        R_base_sensor: sensor orientation, (3, 3).
        R_base_tcp: TCP orientation, (3, 3) (for the mount's twist conversion).
    """

    t_sample_ns: int
    now_ns: int
    wrench_raw_sensor: NDArray[np.float64]
    wrench_contact_sensor: NDArray[np.float64]
    p_base_sensor: NDArray[np.float64]
    R_base_sensor: NDArray[np.float64]
    R_base_tcp: NDArray[np.float64]


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
        rate_limiter: holds the loop to wall-clock time after each ``robot.wait_cycle()``;
            None when the robot paces the loop (simulation, a driver that blocks per period).
        max_late_cycles: this many overruns in a row are a fault (:class:`LoopOverrunError`,
            and :func:`run_loop` stops the robot): a loop that cannot keep its period no longer
            controls the arm.
    """

    def __init__(
        self,
        robot: Robot,
        sensor: WrenchSensor,
        *,
        mount: Mount | None = None,
        compensator: GravityCompensator | None = None,
        bias_tracker: BiasTracker | None = None,
        rate_limiter: RateLimiter | None = None,
        max_late_cycles: int = 10,
    ) -> None:
        if not (isinstance(max_late_cycles, int) and max_late_cycles >= 1):
            raise ParameterError(f"max_late_cycles must be an integer >= 1, got {max_late_cycles}")
        self.max_late_cycles = max_late_cycles
        self.robot = robot
        self.sensor = sensor
        self.mount = mount if mount is not None else Mount()
        self.compensator = compensator
        self.bias_tracker = bias_tracker
        self.rate_limiter = rate_limiter
        self.period_s = robot.control_period_s

    def read(self) -> Reading:
        """Read the newest wrench and the pose, and compensate."""
        sample = self.sensor.read()
        pose = self.robot.pose()
        p, R = self.mount.sensor_pose(pose.p_base_tcp, pose.R_base_tcp)
        w = sample.wrench_sensor
        contact = w if self.compensator is None else self.compensator.compensate(w, R)
        if self.bias_tracker is not None:  # the bias followed while still and free
            contact = self.bias_tracker.correct(sample.t_ns * 1e-9, contact, R)
        return Reading(sample.t_ns, pose.t_ns, w, contact, p, R, pose.R_base_tcp)

    def command(self, twist_sensor_base: NDArray[np.float64], reading: Reading) -> None:
        """Send the sensor origin's twist (base frame) to the robot as its TCP's twist."""
        self.robot.command_twist(self.mount.tcp_twist(twist_sensor_base, reading.R_base_tcp))

    def advance(self) -> None:
        """Wait for (or simulate) the next period."""
        self.robot.wait_cycle()
        limiter = self.rate_limiter
        if limiter is not None:
            limiter.sleep()
            if limiter.periods_behind >= self.max_late_cycles:
                raise LoopOverrunError(
                    f"the control loop fell {limiter.periods_behind} of its "
                    f"{limiter.period_s * 1e3:g} ms periods behind (worst: late by "
                    f"{-limiter.worst_slack_s * 1e3:.1f} ms); motion stopped"
                )


@dataclass(frozen=True)
class LoopStats:
    """How a loop ran: cycles run, the rate limiter's overruns (0 without one), and its timing
    (:class:`~ftcomp.control.timing.TimingSummary`)."""

    cycles: int
    overruns: int
    worst_slack_s: float
    timing: TimingSummary


#: A paced loop's pause between its set-up and its first cycle [s].
_AFTER_SETUP_S = 0.01


def _collect_in_slack() -> None:
    """The collection the interpreter would have started by itself (its thresholds), run after
    the cycle's command has been sent instead of in the middle of a cycle."""
    young, middle, old = gc.get_count()
    threshold0, threshold1, threshold2 = gc.get_threshold()
    if young < threshold0:
        return
    gc.collect(2 if old >= threshold2 else 1 if middle >= threshold1 else 0)


def run_loop(
    cycle: ControlCycle,
    step: Step,
    *,
    sinks: Sequence[Sink] = (),
    max_cycles: int | None = None,
    timing: LoopTiming | None = None,
    in_slack: Sequence[Callable[[], None]] = (),
) -> LoopStats:
    """Run cycles until ``step`` returns None (or ``max_cycles``); stop the robot on any exit.

    Each cycle: ``reading = cycle.read()``, ``twist = step(reading)``, every sink
    ``sink(reading, twist)``, ``cycle.command(twist)``, every ``in_slack()``,
    ``cycle.advance()``. When the step returns None the sinks do not run and nothing is
    commanded. ``in_slack`` is work the cycle owes but the command need not wait for (a log
    row's formatting, :meth:`~ftcomp.session.log.CsvLog.write_later`): it runs after the
    command has been sent, in the period's slack.

    Every cycle is timed (``timing``, or a :class:`~ftcomp.control.timing.LoopTiming` of the
    robot's period, paced when the robot is on the host's clock): pass one to keep its figures
    when the loop ends by an exception.

    A paced loop (on the host's clock) keeps the garbage collector out of its cycles: what
    exists before the loop is collected once and frozen (:func:`gc.freeze`), so the collections
    the loop's own garbage triggers scan only that (a few objects) instead of every object of
    the process (tens of milliseconds with numpy, scipy and a client library loaded), and they
    run between cycles, after the command has been sent (automatic collection is off while the
    loop runs); both are undone on exit. It also runs in
    :func:`~ftcomp.hardware.pacing.realtime_loop` (real-time scheduling where the OS allows it).
    """
    if timing is None:
        timing = LoopTiming(cycle.period_s, paced=on_host_clock(cycle.robot))
    robot = cycle.robot
    n = 0
    # A loop on the wall clock keeps the collector out of its cycles (a simulated one needs not).
    paced = timing.paced
    automatic = gc.isenabled()
    frozen_before = gc.get_freeze_count()
    if paced:
        gc.collect()
        gc.freeze()
        gc.disable()  # collected in the slack instead (_collect_in_slack)
    try:
        with realtime_loop(realtime=timing.paced) as timing.realtime:
            if paced:
                # The device clients' readers deliver what arrived while the set-up (the
                # collection above: 50-80 ms) held the interpreter's lock: the first cycle's
                # reading was once older than the stale limit, a healthy stream stopped.
                time.sleep(_AFTER_SETUP_S)
            # The schedules start with the loop: what came before it (the set-up, an earlier
            # loop on the same robot) is no stall.
            if isinstance(robot, ReportsLateness):
                robot.restart_schedule()
            if cycle.rate_limiter is not None:
                cycle.rate_limiter.restart()
            while max_cycles is None or n < max_cycles:
                timing.start()
                reading = cycle.read()
                twist = step(reading)
                if twist is None:
                    break
                for sink in sinks:
                    sink(reading, twist)
                cycle.command(twist, reading)
                timing.sent(robot.now_ns() - reading.t_sample_ns)
                for later in in_slack:
                    later()
                if paced:
                    _collect_in_slack()
                cycle.advance()
                n += 1
    finally:
        robot.stop()
        if paced:
            if automatic:
                gc.enable()
            if not frozen_before:  # a caller's own freeze stays
                gc.unfreeze()
    limiter = cycle.rate_limiter
    return LoopStats(
        n,
        limiter.overruns if limiter is not None else 0,
        limiter.worst_slack_s if limiter is not None else 0.0,
        timing.summary(),
    )
