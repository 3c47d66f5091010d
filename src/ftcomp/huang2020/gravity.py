"""The paper's gravity-compensation experiments (section 2.2.1) on the simulated cell.

- :func:`run_calibration`: readings at the 9 poses of Table 1, identified by both methods, with
  and without the gripper (the latter weighs the sensor's sensing end).
- :func:`run_continuous_pose`: a 500 g load carried through a continuous change of orientation
  (Fig. 5): measured wrench, compensation value and error over time.
- :func:`run_load_weighing`: the six loads of Table 4 weighed through compensation (Eq. 23).

Each returns a frozen dataclass of numbers and arrays; :mod:`ftcomp.huang2020.demo` turns them
into files, figures and the report.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.calibration.identify import calibrate, pose_means
from ftcomp.calibration_record import Calibration, Method
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.compensation.load import estimate_load, load_weight_N
from ftcomp.frames import encode_orientation, rotation_from_encoding
from ftcomp.model import GravityModel
from ftcomp.paper import paper_poses
from ftcomp.samples import Samples
from ftcomp.sim.cell import SimCell
from ftcomp.sim.collect import record_with_truth
from ftcomp.sim.scene import SceneConfig
from ftcomp.sim.sensor import SensorSpec
from ftcomp.sim.tool import LoadSpec, table4_loads

__all__ = [
    "CalibrationRun",
    "ContinuousPoseRun",
    "LoadWeighingRun",
    "collect_paper_poses",
    "run_calibration",
    "run_continuous_pose",
    "run_load_weighing",
]

Progress = Callable[[str], None]


def _quiet(_: str) -> None:
    """A progress callback that says nothing."""


def collect_paper_poses(cell: SimCell, samples_per_pose: int) -> tuple[Samples, GravityModel]:
    """Readings at the 9 Table-1 poses through the hardware protocols, with the simulated truth."""
    return record_with_truth(cell, paper_poses(), samples_per_pose, move_duration_s=0.6)


@dataclass(frozen=True)
class CalibrationRun:
    """Section 2.2.1 in simulation.

    Attributes:
        samples: the readings with the gripper at the Table-1 poses.
        truth: the simulated truth with the gripper.
        results: the calibration by each method, with the gripper.
        bare_samples: readings with no gripper (the sensing end alone).
        bare_truth: the simulated truth without the gripper.
        bare_result: the joint-method calibration without the gripper.
    """

    samples: Samples = field(repr=False)
    truth: GravityModel
    results: dict[Method, Calibration] = field(repr=False)
    bare_samples: Samples = field(repr=False)
    bare_truth: GravityModel
    bare_result: Calibration = field(repr=False)


def _cell(
    seed: int, tilt_deg: tuple[float, float], *, gripper: bool = True, load: LoadSpec | None = None
) -> SimCell:
    config = SceneConfig(
        tilt_U_rad=np.radians(tilt_deg[0]),
        tilt_V_rad=np.radians(tilt_deg[1]),
        gripper=gripper,
        load=load,
    )
    return SimCell(config, SensorSpec(), seed=seed)


def run_calibration(
    *,
    samples_per_pose: int,
    seed: int,
    tilt_deg: tuple[float, float],
    progress: Progress = _quiet,
) -> CalibrationRun:
    """Collect at the 9 Table-1 poses with and without the gripper and identify.

    Args:
        samples_per_pose: readings per pose (the paper: 500).
        seed: sensor-noise seed.
        tilt_deg: the simulated base tilt (U, V) [deg] (the paper found about (-0.204, -0.129)).
    """
    samples, truth = collect_paper_poses(_cell(seed, tilt_deg), samples_per_pose)
    progress("calibration with the gripper")
    results: dict[Method, Calibration] = {
        method: calibrate(samples, method=method) for method in ("paper", "joint")
    }
    bare_samples, bare_truth = collect_paper_poses(
        _cell(seed + 1, tilt_deg, gripper=False), samples_per_pose
    )
    progress("calibration without the gripper")
    return CalibrationRun(
        samples=samples,
        truth=truth,
        results=results,
        bare_samples=bare_samples,
        bare_truth=bare_truth,
        bare_result=calibrate(bare_samples, method="joint", leave_one_out=False),
    )


@dataclass(frozen=True)
class ContinuousPoseRun:
    """Fig. 5: readings while the orientation changes continuously, holding a load.

    Attributes:
        t: time [s], shape (N,).
        measured: raw readings [N, N*m], (N, 6).
        compensation: the compensation value (bias + tool-and-load gravity) at each sample, (N, 6).
        error: measured - compensation, (N, 6).
        calibration: the calibration (tool with the load held) used for compensation.
        load_kg: the load's mass.
        euler_deg: the paper angles of each sample, (N, 3).
    """

    t: NDArray[np.float64] = field(repr=False)
    measured: NDArray[np.float64] = field(repr=False)
    compensation: NDArray[np.float64] = field(repr=False)
    error: NDArray[np.float64] = field(repr=False)
    calibration: Calibration = field(repr=False)
    load_kg: float
    euler_deg: NDArray[np.float64] = field(repr=False)


def run_continuous_pose(
    *,
    samples_per_pose: int,
    seed: int,
    tilt_deg: tuple[float, float],
    load_kg: float,
    from_deg: tuple[float, float, float],
    to_deg: tuple[float, float, float],
    duration_s: float,
    progress: Progress = _quiet,
) -> ContinuousPoseRun:
    """Calibrate with the load held at the Table-1 poses, then sweep the orientation.

    The move is a minimum-jerk joint move of ``duration_s``; every sensor output during it is
    recorded (the sensor's 1.2 kHz, sampled at the 1 kHz control cycle).
    """
    cell = _cell(seed, tilt_deg, load=LoadSpec(load_kg, name=f"{load_kg * 1000:.0f} g"))
    cell.grasp()
    samples, _ = collect_paper_poses(cell, samples_per_pose)
    calibration = calibrate(samples, method="joint", leave_one_out=False)
    progress("calibration holding the load")
    p_base, _ = cell.sensor_pose()
    R_from = rotation_from_encoding("paper_euler", from_deg).as_matrix()
    R_to = rotation_from_encoding("paper_euler", to_deg).as_matrix()
    cell.move_pose(p_base, R_from, 1.0, label="start of the continuous change")
    cell.settle(label="start of the continuous change")
    t, measured, Rs = [], [], []

    def record(c: SimCell) -> None:
        sample = c.sensor.read()
        t.append(sample.t_s)
        measured.append(sample.wrench_sensor)
        Rs.append(c.pose().R_base_tcp)  # the simulated TCP is the sensor frame

    record(cell)
    cell.move_pose(p_base, R_to, duration_s, on_cycle=record, label="end of the continuous change")
    progress("continuous pose change")
    R = np.array(Rs)
    w = np.array(measured)
    compensation = calibration.model.predict(R)
    euler = encode_orientation(Rotation.from_matrix(R), "paper_euler")
    return ContinuousPoseRun(
        t=np.array(t) - t[0],
        measured=w,
        compensation=compensation,
        error=w - compensation,
        calibration=calibration,
        load_kg=load_kg,
        euler_deg=euler,
    )


@dataclass(frozen=True)
class LoadWeighingRun:
    """Table 4: each load weighed through compensation with the tool's calibration.

    Attributes:
        true_weight_N: the simulated loads' weights, (6,).
        computed_weight_N: Eq. 23 on each pose's mean reading, averaged over the 9 poses, (6,).
        estimated_mass_kg: mass from the least-squares load estimate, (6,).
        relative_error_percent: 100 |computed - true| / true, (6,).
    """

    true_weight_N: NDArray[np.float64]
    computed_weight_N: NDArray[np.float64]
    estimated_mass_kg: NDArray[np.float64]
    relative_error_percent: NDArray[np.float64]


def run_load_weighing(
    calibration: Calibration,
    *,
    samples_per_pose: int,
    seed: int,
    tilt_deg: tuple[float, float],
    progress: Progress = _quiet,
) -> LoadWeighingRun:
    """Grasp each Table-4 load, read at the 9 Table-1 poses, and weigh it (Eq. 23)."""
    compensator = GravityCompensator(calibration)
    true_w, computed, mass = [], [], []
    for i, load in enumerate(table4_loads()):
        cell = _cell(seed + 10 + i, tilt_deg, load=load)
        cell.grasp()
        samples, _ = collect_paper_poses(cell, samples_per_pose)
        # Average each pose's readings first, as the paper does: |F'| of single noisy readings
        # is biased upward by about 3 sigma^2 / (2 G') (2 % for the 1 N load).
        _, R_pose, mean_pose, _, _ = pose_means(samples)
        weights = load_weight_N(compensator, mean_pose, R_pose)
        estimate = estimate_load(compensator, mean_pose, R_pose)
        true_w.append(load.weight_N)
        computed.append(float(np.mean(weights)))
        mass.append(estimate.mass_kg)
        progress(f"load {i + 1}")
    true_arr, computed_arr = np.array(true_w), np.array(computed)
    return LoadWeighingRun(
        true_weight_N=true_arr,
        computed_weight_N=computed_arr,
        estimated_mass_kg=np.array(mass),
        relative_error_percent=100.0 * np.abs(computed_arr - true_arr) / true_arr,
    )
