"""Calibration readings from the simulated cell, with the truth behind them.

The readings are recorded exactly as on a real arm (:func:`ftcomp.calibration.collect.record_static`
through the hardware protocols); the cell adds what no real arm can: the true parameters a
calibration should find, for scoring.
"""

from __future__ import annotations

import numpy as np

from ftcomp.calibration.collect import record_static
from ftcomp.model import GravityModel
from ftcomp.samples import PoseList, Samples
from ftcomp.sim.cell import COLLECTION_POSITION_BASE_M, SimCell

__all__ = ["record_with_truth"]


def record_with_truth(
    cell: SimCell,
    poses: PoseList,
    samples_per_pose: int,
    *,
    move_duration_s: float = 1.0,
) -> tuple[Samples, GravityModel]:
    """Readings at every pose (sensor held at the collection position unless the poses say
    otherwise) and the truth: what hangs below the sensor, its bias and the base tilt.

    A held load's weld flexes by micrometres from pose to pose, so the truth's weight and
    centre of gravity are their means over the poses.
    """
    weights: list[float] = []
    cogs: list[np.ndarray] = []

    def note_truth(_index: int, _pose_id: str) -> None:
        truth = cell.true_gravity_model()
        weights.append(truth.weight_N)
        cogs.append(truth.center_of_gravity_m)

    samples = record_static(
        cell,
        cell.sensor,
        poses,
        samples_per_pose,
        position_base_m=COLLECTION_POSITION_BASE_M,
        move_duration_s=move_duration_s,
        on_pose=note_truth,
    )
    last = cell.true_gravity_model()
    truth = GravityModel(
        float(np.mean(weights)),
        np.mean(cogs, axis=0),
        last.force_bias_N,
        last.torque_bias_Nm,
        tilt_U_rad=last.tilt_U_rad,
        tilt_V_rad=last.tilt_V_rad,
    )
    return samples, truth
