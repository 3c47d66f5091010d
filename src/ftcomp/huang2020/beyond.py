"""Beyond the paper, moving: a load grasped and released during a slow move, weighed online.

:func:`run_grasp_during_move` calibrates the tool in the simulated cell (the paper's nine poses,
:func:`ftcomp.calibration.identify.calibrate`), then makes a slow wrist move during which the
gripper grasps a 500 g load and later releases it. Every control cycle goes through
:class:`~ftcomp.compensation.online.OnlineLoadCompensator` exactly as in a live loop; the
simulator's truth (the load's mass and its centre of gravity in the sensor frame) only scores.
:func:`run_motion_without_grasp` moves for a while with the empty gripper and counts the grasps
the detector (wrongly) reports.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ftcomp import paper
from ftcomp.calibration.identify import calibrate
from ftcomp.calibration_record import Calibration
from ftcomp.compensation.online import OnlineLoadCompensator
from ftcomp.huang2020.gravity import collect_paper_poses
from ftcomp.sim.cell import HOME_Q_RAD, SimCell
from ftcomp.sim.scene import SceneConfig
from ftcomp.sim.sensor import SensorSpec
from ftcomp.sim.tool import LoadSpec

__all__ = ["GraspRun", "NoGraspRun", "run_grasp_during_move", "run_motion_without_grasp"]

#: The slow move's joint change [rad] (wrist only: the tool turns ~50 deg, the sensor origin
#: barely moves) and its duration [s].
_SLOW_MOVE_RAD = (0.0, 0.0, 0.0, 0.8, 0.9, 0.8)
#: Joint targets of the motion without grasping, offsets from HOME [rad]; visited in turn.
_WANDER_RAD = (
    (0.3, 0.2, -0.2, 0.5, 0.4, 0.6),
    (-0.3, -0.1, 0.2, -0.4, 0.6, -0.5),
    (0.0, 0.25, 0.1, 0.6, -0.3, 0.9),
    (0.2, -0.15, -0.1, -0.6, 0.2, -0.8),
)


def _cell(seed: int, load: LoadSpec | None) -> SimCell:
    config = SceneConfig(
        tilt_U_rad=float(np.radians(paper.TILT_DEG[0])),
        tilt_V_rad=float(np.radians(paper.TILT_DEG[1])),
        load=load,
    )
    return SimCell(config, SensorSpec(), seed=seed)


def _calibrated(cell: SimCell, samples_per_pose: int) -> Calibration:
    samples, _ = collect_paper_poses(cell, samples_per_pose)
    calibration = calibrate(samples, method="joint", leave_one_out=False)
    cell.move_joints(np.array(HOME_Q_RAD), 1.0)
    cell.settle(label="start of the move")
    return calibration


@dataclass(frozen=True)
class GraspRun:
    """A load grasped and released during a slow move.

    Attributes:
        t: time since the move started [s], (N,).
        mass_kg, mass_std_kg: the online estimate and its standard deviation, (N,).
        cog_m: the estimated centre of gravity, sensor frame [m], (N, 3).
        cog_std_m: standard deviations of its components [m], (N, 3).
        state: the compensator's state per cycle (``"empty"``, ``"estimating"``, ``"holding"``).
        contact_force_N: the online-compensated force, sensor frame [N], (N, 3).
        grasp_s, release_s: when the gripper grasped and released [s].
        detected_grasp_s, detected_release_s: when the detector confirmed them [s] (nan: never).
        true_mass_kg, true_cog_m: the load's truth.
        events: every confirmed step, ``(kind, time [s])``.
    """

    t: NDArray[np.float64] = field(repr=False)
    mass_kg: NDArray[np.float64] = field(repr=False)
    mass_std_kg: NDArray[np.float64] = field(repr=False)
    cog_m: NDArray[np.float64] = field(repr=False)
    cog_std_m: NDArray[np.float64] = field(repr=False)
    state: list[str] = field(repr=False)
    contact_force_N: NDArray[np.float64] = field(repr=False)
    grasp_s: float
    release_s: float
    detected_grasp_s: float
    detected_release_s: float
    true_mass_kg: float
    true_cog_m: NDArray[np.float64]
    events: list[tuple[str, float]]

    def at(self, t_s: float) -> int:
        """Index of the first cycle at or after ``t_s``."""
        return min(int(np.searchsorted(self.t, t_s - 1e-9)), len(self.t) - 1)


def run_grasp_during_move(
    *,
    seed: int,
    samples_per_pose: int = 200,
    load_kg: float = 0.5,
    move_s: float = 10.0,
    grasp_fraction: float = 0.45,
    release_fraction: float = 0.75,
) -> GraspRun:
    """Grasp ``load_kg`` at ``grasp_fraction`` of a slow ``move_s`` move, release it later.

    The grasp falls near the middle of the minimum-jerk move, where the tool turns fastest
    (~0.15 rad/s) and accelerates least; the estimator never learns when it happens.
    """
    load = LoadSpec(load_kg, name=f"{load_kg * 1000:.0f} g")
    cell = _cell(seed, load)
    online = OnlineLoadCompensator(_calibrated(cell, samples_per_pose))
    t0 = cell.time()
    grasp_s, release_s = grasp_fraction * move_s, release_fraction * move_s
    n = max(1, round(move_s / cell.control_period_s))
    data = np.full((n, 12), np.nan)
    states: list[str] = []
    truth: list[NDArray[np.float64]] = []
    load_id = cell.model.body("load").id
    site_id = cell.model.site("ft_site").id

    def cycle(c: SimCell) -> None:
        t = c.time() - t0
        if not c.holding and grasp_s <= t < release_s:
            c.grasp()
        elif c.holding and t >= release_s:
            c.release()
        if c.holding:
            d = c.data
            R_world_sensor = d.site_xmat[site_id].reshape(3, 3)
            truth.append(R_world_sensor.T @ (d.xipos[load_id] - d.site_xpos[site_id]))
        sample = c.sensor.read()
        contact = online.compensate(sample.wrench_sensor, c.pose().R_base_tcp)
        row = data[len(states)]
        row[0] = t
        row[9:12] = contact[:3]
        rls = online.rls
        if rls.samples:  # nothing estimated while empty (nan)
            row[1:3] = rls.mass_kg, rls.mass_std_kg
            row[3:6] = rls.cog_m
            row[6:9] = np.sqrt(np.clip(np.diagonal(rls.cog_covariance), 0.0, None))
        states.append(online.state.value)

    cell.move_joints(np.array(HOME_Q_RAD) + np.array(_SLOW_MOVE_RAD), move_s, on_cycle=cycle)
    data = data[: len(states)]
    period = cell.control_period_s
    events = [(e.kind, (e.sample + 1) * period) for e in online.events]
    return GraspRun(
        t=data[:, 0],
        mass_kg=data[:, 1],
        mass_std_kg=data[:, 2],
        cog_m=data[:, 3:6],
        cog_std_m=data[:, 6:9],
        state=states,
        contact_force_N=data[:, 9:12],
        grasp_s=grasp_s,
        release_s=release_s,
        detected_grasp_s=_first(events, "grasp", grasp_s),
        detected_release_s=_first(events, "release", release_s),
        true_mass_kg=load_kg,
        true_cog_m=np.mean(truth, axis=0),
        events=events,
    )


def _first(events: list[tuple[str, float]], kind: str, after_s: float) -> float:
    times = [t for k, t in events if k == kind and t >= after_s]
    return min(times) if times else float("nan")


@dataclass(frozen=True)
class NoGraspRun:
    """Motion with the empty gripper: the detector should report nothing.

    Attributes:
        duration_s: how long the arm moved [s].
        false_grasps: grasps the detector reported.
        events: every confirmed step, ``(kind, time [s])``.
        peak_joint_speed_rad_s: the fastest joint speed commanded [rad/s].
    """

    duration_s: float
    false_grasps: int
    events: list[tuple[str, float]]
    peak_joint_speed_rad_s: float


def run_motion_without_grasp(
    *, seed: int, duration_s: float = 60.0, move_s: float = 3.0, samples_per_pose: int = 200
) -> NoGraspRun:
    """Move between joint targets for ``duration_s`` (moves of ``move_s``), gripper empty."""
    cell = _cell(seed, None)
    online = OnlineLoadCompensator(_calibrated(cell, samples_per_pose))

    def cycle(c: SimCell) -> None:
        online.compensate(c.sensor.read().wrench_sensor, c.pose().R_base_tcp)

    n_moves = max(1, round(duration_s / move_s))
    home = np.array(HOME_Q_RAD)
    previous = home
    peak = 0.0
    for i in range(n_moves):
        target = home + np.array(_WANDER_RAD[i % len(_WANDER_RAD)])
        peak = max(peak, 1.875 * float(np.abs(target - previous).max()) / move_s)
        cell.move_joints(target, move_s, on_cycle=cycle)
        previous = target
    period = cell.control_period_s
    events = [(e.kind, (e.sample + 1) * period) for e in online.events]
    return NoGraspRun(
        duration_s=n_moves * move_s,
        false_grasps=sum(1 for k, _ in events if k == "grasp"),
        events=events,
        peak_joint_speed_rad_s=peak,
    )
