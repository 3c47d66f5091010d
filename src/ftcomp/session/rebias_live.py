"""Re-bias at the start of a live session: the bias from a few seconds of still readings, the
tool model kept (``ftcomp stream/run --rebias-s SECONDS``).

A calibration's bias is the bias of its session. Used later, the bias has moved (a sensor
warming up moves it by a newton in minutes, docs/calibration.md), and live tracking
(:class:`~ftcomp.compensation.bias_tracking.BiasTracker`) cannot catch up from there: a
compensated force beyond its contact threshold is taken for a touch. With the user's word that
nothing touches the tool, :func:`rebias_still` reads the sensor with the arm still, before the
loop starts, and re-estimates the bias alone (:func:`~ftcomp.calibration.rebias.rebias`:
``reading - tool gravity wrench``, gravity-aware where a vendor's tare is not). The loop then
starts from the bias now, and tracking, if on, follows it from there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Final

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.rebias import bias_of, rebias
from ftcomp.calibration_record import Calibration
from ftcomp.config_fields import FieldSpec, check_value
from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.protocols import Mount, Robot, WrenchSensor
from ftcomp.samples import Samples

__all__ = ["MOVED_M", "REBIAS_DURATION", "TURNED_RAD", "Rebiased", "rebias_still"]

#: The rule of a re-bias's duration [s]: any time to average the noise over, up to a minute (a
#: bias read over longer has drifted while it was read).
REBIAS_DURATION: Final = FieldSpec(
    help="how long to read with the arm still and nothing touching the tool",
    unit="s",
    gt=0.0,
    le=60.0,
)

#: How far the sensor may move [m] and turn [rad] while the bias is read: further, and the
#: arm was not still.
MOVED_M: Final = 1e-3
TURNED_RAD: Final = 0.005
_SILENT_CYCLES: Final = 1000  # robot cycles without a reading: the sensor is silent


@dataclass(frozen=True)
class Rebiased:
    """A calibration re-biased at the start of a live session.

    Attributes:
        calibration: the calibration with the bias now (its drift model dropped).
        shift: the new bias minus the calibration's [N, N*m], (6,).
        std_errors: the new bias's standard errors [N, N*m], (6,).
        readings: the readings it came from.
    """

    calibration: Calibration
    shift: NDArray[np.float64] = field(repr=False)
    std_errors: NDArray[np.float64] = field(repr=False)
    readings: int

    def line(self) -> str:
        """One line for a command's output."""
        s, e = self.shift, self.std_errors
        return (
            f"re-biased from {self.readings} still readings: the bias moved by [{s[0]:+.3f} "
            f"{s[1]:+.3f} {s[2]:+.3f}] N [{s[3]:+.4f} {s[4]:+.4f} {s[5]:+.4f}] N·m from the "
            f"calibration's (standard error {e[:3].max():.3f} N, {e[3:].max():.4f} N·m)"
        )


def rebias_still(
    robot: Robot,
    sensor: WrenchSensor,
    calibration: Calibration,
    duration_s: float,
    *,
    mount: Mount | None = None,
) -> Rebiased:
    """The calibration re-biased from ``duration_s`` of readings, the arm still and nothing
    touching the tool (the caller's word: a touch cannot be told from a bias here).

    Args:
        robot: the arm (entered), still; it is not moved.
        sensor: the F/T sensor (entered), on the robot's clock.
        calibration: the calibration to re-bias (its tool model, tilt and mount are kept).
        duration_s: how long to read [s], in (0, 60] (:data:`REBIAS_DURATION`; on the robot's
            clock).
        mount: the sensor frame on the TCP (identity by default), as the loop's.

    Returns:
        The re-biased calibration and what changed.

    Raises:
        ParameterError: a duration out of its range, a robot that reports no pose.
        HardwareError: the arm moved more than :data:`MOVED_M` or turned more than
            :data:`TURNED_RAD` while reading, or the sensor is silent.
    """
    check_value("duration_s", REBIAS_DURATION, duration_s)
    if not robot.pose_known:
        raise ParameterError("re-biasing needs the sensor's pose: the robot reports none")
    mount = mount if mount is not None else Mount()
    first = robot.pose()
    p0, R0 = mount.sensor_pose(first.p_base_tcp, first.R_base_tcp)
    end_ns = first.t_ns + round(duration_s * 1e9)
    sensor.read_new()  # the readings from now on
    wrenches: list[NDArray[np.float64]] = []
    rotations: list[NDArray[np.float64]] = []
    silent = 0
    while True:
        robot.wait_cycle()
        new = sensor.read_new()
        pose = robot.pose()
        p, R = mount.sensor_pose(pose.p_base_tcp, pose.R_base_tcp)
        moved = float(np.linalg.norm(p - p0))
        turned = math.acos(min(1.0, max(-1.0, (float(np.trace(R0.T @ R)) - 1.0) / 2.0)))
        if moved > MOVED_M or turned > TURNED_RAD:
            raise HardwareError(
                f"the arm moved while the bias was read ({moved * 1e3:.1f} mm, "
                f"{math.degrees(turned):.2f} deg; still means under {MOVED_M * 1e3:g} mm and "
                f"{math.degrees(TURNED_RAD):.2f} deg): re-bias with the arm still"
            )
        silent = 0 if new else silent + 1
        if silent >= _SILENT_CYCLES:
            raise HardwareError(f"the sensor sent nothing for {silent} control cycles")
        wrenches.extend(sample.wrench_sensor for sample in new)
        rotations.extend([R] * len(new))
        if pose.t_ns >= end_ns and len(wrenches) >= 2:
            break
    wrench = np.array(wrenches)
    if not np.all(np.isfinite(wrench)):
        raise HardwareError("the sensor sent non-finite readings while the bias was read")
    samples = Samples(wrench, np.array(rotations), "quaternion", source="the still readings")
    new_calibration = rebias(calibration, samples)
    (old, _), (now, std_errors) = bias_of(calibration), bias_of(new_calibration)
    return Rebiased(new_calibration, now - old, std_errors, len(wrenches))
