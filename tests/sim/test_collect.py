"""Recording on the simulated cell through the hardware protocols recovers the truth."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from scipy.spatial.transform import Rotation

from ftcomp.calibration.identify import calibrate, deviations_in_standard_errors
from ftcomp.io.samples_csv import read_samples, write_samples
from ftcomp.paper import paper_poses
from ftcomp.sim.cell import SimCell
from ftcomp.sim.collect import record_with_truth
from ftcomp.sim.scene import SceneConfig

PAPER_TILT_RAD = (math.radians(-0.204), math.radians(-0.129))


@pytest.mark.parametrize("method", ["paper", "joint"])
@pytest.mark.parametrize("gripper", [True, False])
def test_calibration_recovers_the_simulated_truth_within_three_standard_errors(
    tmp_path: Path, method: str, gripper: bool
) -> None:
    U, V = PAPER_TILT_RAD
    cell = SimCell(SceneConfig(tilt_U_rad=U, tilt_V_rad=V, gripper=gripper), seed=11)
    data, truth = record_with_truth(cell, paper_poses(), 500)
    path = tmp_path / "samples.csv"
    write_samples(
        path,
        data.wrench_sensor,
        Rotation.from_matrix(data.R_base_sensor),
        encoding="quaternion",
        pose=data.pose,
        t=data.t,
    )
    result = calibrate(read_samples(path), method=method)  # type: ignore[arg-type]
    expected_weight = 3.153 if gripper else 0.835
    assert truth.weight_N == pytest.approx(expected_weight, abs=1e-9)
    deviations = deviations_in_standard_errors(result, truth)
    # At the paper's noise level (one count) each estimate is off by noise alone: 3 SE.
    worst = max(deviations, key=deviations.__getitem__)
    assert deviations[worst] < 3.0, f"{worst} is {deviations[worst]:.2f} SE off: {deviations}"
