"""Static calibration readings from any robot and sensor: drive to each pose, wait, record.

:func:`record_static` works through the hardware protocols (:mod:`ftcomp.hardware.protocols`),
so the same code collects from the simulated cell (``sim://``) and from a real arm. At each pose
of a :class:`~ftcomp.samples.PoseList` it moves the sensor there (blocking, through the mount),
waits until the arm is at rest, and records the next ``samples_per_pose`` sensor readings with
the sensor's measured orientation (and a sensor's extra channels, its temperature or IMU, each
reading's own: :class:`~ftcomp.hardware.protocols.ReportsExtraChannels`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from ftcomp.errors import FtcompError, HardwareError, ParameterError
from ftcomp.hardware.protocols import (
    Mount,
    ReportsExtraChannels,
    Robot,
    WrenchSample,
    WrenchSensor,
)
from ftcomp.samples import PoseList, Samples

__all__ = ["record_static"]

#: Control cycles without a new reading after which a sensor counts as silent.
_SILENT_CYCLES = 1000

PoseCallback = Callable[[int, str], None]


def _readings(robot: Robot, sensor: WrenchSensor, n: int, label: str) -> list[WrenchSample]:
    """The next ``n`` readings, advancing the robot's cycle while waiting."""
    sensor.read_new()  # only readings from now on
    kept: list[WrenchSample] = []
    silent = 0
    while len(kept) < n:
        robot.wait_cycle()
        new = sensor.read_new()
        silent = 0 if new else silent + 1
        if silent >= _SILENT_CYCLES:
            raise HardwareError(f"{label}: the sensor sent nothing for {silent} control cycles")
        kept.extend(new)
    return kept[:n]


def record_static(
    robot: Robot,
    sensor: WrenchSensor,
    poses: PoseList,
    samples_per_pose: int,
    *,
    mount: Mount | None = None,
    position_base_m: ArrayLike | None = None,
    move_duration_s: float = 1.0,
    settle_max_s: float = 3.0,
    on_pose: PoseCallback | None = None,
) -> Samples:
    """Readings at every pose, labelled by the pose ids.

    Args:
        robot: the arm (entered).
        sensor: the F/T sensor (entered), on the same clock.
        poses: sensor orientations (and optionally positions) to visit.
        samples_per_pose: readings recorded at each pose, >= 1.
        mount: the sensor frame on the TCP (identity by default).
        position_base_m: the sensor origin for poses without a position [m], base frame;
            None: where the sensor is when recording starts.
        move_duration_s: duration of each move [s].
        settle_max_s: longest wait for the arm to come to rest [s].
        on_pose: called as ``on_pose(index, pose_id)`` after each pose's readings (e.g. to
            note the simulator's truth there).

    Returns:
        :class:`~ftcomp.samples.Samples` in the ``paper_euler`` encoding, with ``pose``, ``t``
        (seconds on the session's clock) and a sensor's extra channels in ``extras``.

    Raises:
        UnreachablePoseError: a pose cannot be reached (the error names it).
        FtcompError: the arm does not come to rest, or the sensor goes silent.
    """
    if not (isinstance(samples_per_pose, int) and samples_per_pose >= 1):
        raise ParameterError(f"samples_per_pose must be an integer >= 1, got {samples_per_pose}")
    mount = mount if mount is not None else Mount()
    here = robot.pose()
    if position_base_m is None:
        p_default = mount.sensor_pose(here.p_base_tcp, here.R_base_tcp)[0]
    else:
        p_default = np.asarray(position_base_m, dtype=float)
        if p_default.shape != (3,) or not np.isfinite(p_default).all():
            raise ParameterError(f"position_base_m must be 3 finite numbers [m], got {p_default}")
    channels = sensor.extra_channels if isinstance(sensor, ReportsExtraChannels) else ()
    wrenches, rotations, pose_ids, times, extras = [], [], [], [], []
    for i, (label, rotation) in enumerate(zip(poses.ids, poses.rotations, strict=True)):
        name = f"pose {label} of {poses.source}"
        p = poses.positions_base_m[i] if poses.positions_base_m is not None else p_default
        try:
            robot.move_pose(*mount.tcp_pose(p, rotation.as_matrix()), move_duration_s)
            robot.settle(settle_max_s)
        except FtcompError as exc:
            raise type(exc)(f"{name}: {exc}") from None
        readings = _readings(robot, sensor, samples_per_pose, name)
        at = robot.pose()
        R_base_sensor = mount.sensor_pose(at.p_base_tcp, at.R_base_tcp)[1]
        wrenches.append(np.array([r.wrench_sensor for r in readings]))
        times.append(np.array([r.t_ns for r in readings], dtype=np.int64))
        if channels:
            extras.append(np.array([r.extras for r in readings], dtype=float))
        rotations.append(np.broadcast_to(R_base_sensor, (samples_per_pose, 3, 3)))
        pose_ids.extend([label] * samples_per_pose)
        if on_pose is not None:
            on_pose(i, label)
    t_ns = np.concatenate(times)
    extra = np.concatenate(extras).reshape(len(t_ns), len(channels)) if channels else None
    return Samples(
        wrench_sensor=np.concatenate(wrenches),
        R_base_sensor=np.concatenate(rotations),
        encoding="paper_euler",
        pose=np.array(pose_ids),
        t=t_ns.astype(np.float64) * 1e-9,
        source=f"recording at {len(poses)} poses of {poses.source}",
        extras={} if extra is None else dict(zip(channels, extra.T, strict=True)),
    )
