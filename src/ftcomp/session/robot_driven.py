"""Robot-driven calibration readings, pose by pose, so nothing is lost when it stops.

:func:`record_poses` drives the robot through a :class:`~ftcomp.samples.PoseList` with
:func:`ftcomp.calibration.collect.record_static`, one pose at a time: it checks every pose is
reachable before the first move (when the robot can tell, see
:class:`~ftcomp.hardware.protocols.ChecksReachability`) and leaves out, with a line naming it and
why, each one the robot cannot reach; it moves (a robot that moves in joint space,
:class:`~ftcomp.hardware.protocols.MovesInJointSpace`, by a joint move to the inverse kinematics
nearest its joints, as ``poses design --robot`` planned the visit; a pose it finds no solution
for from there is left out the same way), waits for the arm to come to rest,
records ``samples_per_pose`` readings and re-records while the readings still drift (the
wrench has not settled). Each finished pose goes to ``on_pose`` as a
:class:`~ftcomp.session.pose_record.PoseRecord` at once, so a caller can write it out before
the next move: a fault, a lost connection or Ctrl-C later loses nothing already recorded.

The hand-guided variant (the user moves the arm, ftcomp notices each still period) is
:mod:`ftcomp.session.hand_guided`; :func:`ftcomp.session.record.record` runs either as a whole
session that writes the sample file.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.calibration.collect import record_static
from ftcomp.errors import HardwareError, ParameterError, UnreachablePoseError
from ftcomp.hardware.protocols import (
    ChecksReachability,
    Mount,
    MovesInJointSpace,
    Robot,
    WrenchSensor,
)
from ftcomp.samples import PoseList
from ftcomp.session.pose_record import PoseRecord, WrenchTolerance, is_settled, wrench_drift

__all__ = ["check_reachable", "record_poses"]


def check_reachable(
    robot: Robot, poses: PoseList, mount: Mount, position_base_m: NDArray[np.float64]
) -> list[str]:
    """Before any move: the labels of the poses the robot reports unreachable (none for robots
    that cannot tell: their own move checks, before it starts).

    Raises:
        UnreachablePoseError: the robot reaches none of them (nothing was moved).
    """
    if not isinstance(robot, ChecksReachability):
        return []
    unreachable = []
    for i, (label, rotation) in enumerate(zip(poses.ids, poses.rotations, strict=True)):
        p = poses.positions_base_m[i] if poses.positions_base_m is not None else position_base_m
        if not robot.is_reachable(*mount.tcp_pose(p, rotation.as_matrix())):
            unreachable.append(label)
    if unreachable and len(unreachable) == len(poses.ids):
        raise UnreachablePoseError(
            f"no pose of {poses.source} is reachable (inverse kinematics or safety limits); "
            "nothing was moved"
        )
    return unreachable


def record_poses(
    robot: Robot,
    sensor: WrenchSensor,
    poses: PoseList,
    samples_per_pose: int,
    on_pose: Callable[[PoseRecord], None],
    *,
    mount: Mount | None = None,
    position_base_m: ArrayLike | None = None,
    move_duration_s: float = 2.0,
    settle_max_s: float = 5.0,
    tolerance: WrenchTolerance | None = None,
    max_tries: int = 5,
    on_skip: Callable[[str], None] | None = None,
) -> None:
    """Visit every pose and hand each one's readings to ``on_pose`` as soon as they are in.

    Args:
        robot: the arm (entered).
        sensor: the F/T sensor (entered), on the robot's clock.
        poses: sensor orientations (and optionally positions) to visit.
        samples_per_pose: readings averaged at each pose, >= 2.
        on_pose: called with each :class:`~ftcomp.session.pose_record.PoseRecord`, in order.
        mount: the sensor frame on the TCP (identity by default).
        position_base_m: the sensor origin for poses without a position [m], base frame;
            None: where the sensor is when recording starts.
        move_duration_s: about how long each move takes [s] (the robot caps the speed).
        settle_max_s: longest wait for the arm to come to rest [s].
        tolerance: how still the readings must be (see
            :class:`~ftcomp.session.pose_record.WrenchTolerance`).
        max_tries: recordings at one pose before giving up on a drifting wrench.
        on_skip: called with one line for each pose left out (it names the pose and why).

    Raises:
        UnreachablePoseError: no pose can be reached (checked before the first move when the
            robot can tell).
        HardwareError: the wrench keeps drifting at a pose, the sensor goes silent, the
            connection is lost.
    """
    if not (isinstance(samples_per_pose, int) and samples_per_pose >= 2):
        raise ParameterError(f"samples_per_pose must be an integer >= 2, got {samples_per_pose}")
    mount = mount if mount is not None else Mount()
    tolerance = tolerance if tolerance is not None else WrenchTolerance()
    if position_base_m is None:
        here = robot.pose()
        p_default = mount.sensor_pose(here.p_base_tcp, here.R_base_tcp)[0]
    else:
        p_default = np.asarray(position_base_m, dtype=float)
        if p_default.shape != (3,) or not np.all(np.isfinite(p_default)):
            raise ParameterError(f"position_base_m must be 3 finite numbers [m], got {p_default}")
    skipped = set(check_reachable(robot, poses, mount, p_default))

    def skip(line: str) -> None:
        if on_skip is not None:
            on_skip(line)

    for label in poses.ids:
        if label in skipped:
            skip(
                f"pose {label} of {poses.source} skipped: the robot does not reach it (inverse "
                "kinematics or safety limits)"
            )
    for i, label in enumerate(poses.ids):
        if label in skipped:
            continue
        p_i = poses.positions_base_m[i] if poses.positions_base_m is not None else p_default
        if isinstance(robot, MovesInJointSpace):
            try:
                robot.move_pose_joints(
                    *mount.tcp_pose(p_i, poses.rotations[i].as_matrix()), move_duration_s
                )
            except UnreachablePoseError as exc:
                skip(f"pose {label} of {poses.source} skipped: {exc}")
                continue
        one = PoseList(
            (label,),
            poses.rotations[i : i + 1],
            poses.source,
            poses.positions_base_m[i : i + 1] if poses.positions_base_m is not None else None,
        )
        for _ in range(max_tries):
            samples = record_static(
                robot,
                sensor,
                one,
                samples_per_pose,
                mount=mount,
                position_base_m=p_default,
                move_duration_s=move_duration_s,
                settle_max_s=settle_max_s,
            )
            if is_settled(samples.wrench_sensor, tolerance):
                break
        else:
            drift = wrench_drift(samples.wrench_sensor)
            raise HardwareError(
                f"pose {label} of {poses.source}: the readings kept drifting over {max_tries} "
                f"recordings (force {drift[:3].max():.3f} N, torque {drift[3:].max():.4f} N*m "
                f"between halves; tolerance {tolerance.force_N:g} N, {tolerance.torque_Nm:g} N*m)"
            )
        at = robot.pose()
        assert samples.t is not None  # record_static stamps every reading
        on_pose(
            PoseRecord(
                label,
                samples.R_base_sensor[0],
                mount.sensor_pose(at.p_base_tcp, at.R_base_tcp)[0],
                samples.wrench_sensor,
                np.round(samples.t * 1e9).astype(np.int64),
                samples.extras,
            )
        )
