"""Static collection: poses, pose files, and calibration recovering the simulated truth."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ftcomp.calibration import calibrate
from ftcomp.errors import InputFileError
from ftcomp.io.samples import read_samples, write_samples
from ftcomp.model import GravityModel
from ftcomp.sim.cell import SimCell
from ftcomp.sim.collect import collect_static_samples, paper_poses, read_pose_file
from ftcomp.sim.scene import SceneConfig

PAPER_TILT_RAD = (math.radians(-0.204), math.radians(-0.129))


def test_paper_poses_are_the_nine_of_table_1() -> None:
    poses = paper_poses()
    assert poses.ids == tuple(str(i) for i in range(1, 10))
    np.testing.assert_allclose(
        poses.rotations[3].as_euler("ZYX", degrees=True), [114.513, 6.333, 158.351], atol=1e-9
    )


def _deviations_in_standard_errors(estimate, truth: GravityModel) -> dict[str, float]:
    model, se = estimate.model, estimate.std_errors
    pairs = {
        "weight": (model.weight_N, truth.weight_N, se.weight_N),
        "U": (model.tilt_U_rad, truth.tilt_U_rad, se.tilt_U_rad),
        "V": (model.tilt_V_rad, truth.tilt_V_rad, se.tilt_V_rad),
    }
    for name in ("center_of_gravity_m", "force_bias_N", "torque_bias_Nm"):
        for k in range(3):
            pairs[f"{name}[{k}]"] = (
                getattr(model, name)[k],
                getattr(truth, name)[k],
                getattr(se, name)[k],
            )
    return {name: abs(est - true) / s for name, (est, true, s) in pairs.items()}


@pytest.mark.parametrize("method", ["paper", "joint"])
@pytest.mark.parametrize("gripper", [True, False])
def test_calibration_recovers_the_simulated_truth_within_three_standard_errors(
    tmp_path: Path, method: str, gripper: bool
) -> None:
    U, V = PAPER_TILT_RAD
    cell = SimCell(SceneConfig(tilt_U_rad=U, tilt_V_rad=V, gripper=gripper), seed=11)
    data = collect_static_samples(cell, paper_poses(), 500)
    path = tmp_path / "samples.csv"
    write_samples(
        path, data.wrench_sensor, data.rotations, encoding="quaternion", pose=data.pose, t=data.t
    )
    result = calibrate(read_samples(path), method=method)  # type: ignore[arg-type]
    expected_weight = 3.153 if gripper else 0.835
    assert data.truth.weight_N == pytest.approx(expected_weight, abs=1e-9)
    deviations = _deviations_in_standard_errors(result, data.truth)
    # At the paper's noise level (one count) each estimate is off by noise alone: 3 SE.
    worst = max(deviations, key=deviations.__getitem__)
    assert deviations[worst] < 3.0, f"{worst} is {deviations[worst]:.2f} SE off: {deviations}"


def test_pose_file_rows_sharing_a_pose_id_become_one_pose_with_its_position(
    tmp_path: Path,
) -> None:
    path = tmp_path / "poses.csv"
    path.write_text(
        "pose,qx,qy,qz,qw,x_m,y_m,z_m,fx\n"
        "a,1,0,0,0,0.4,0.0,0.4,1\n"
        "a,1,0,0,0,0.4,0.0,0.4,2\n"
        "b,0,1,0,0,0.5,0.1,0.4,3\n",
        encoding="utf-8",
    )
    poses = read_pose_file(path)
    assert poses.ids == ("a", "b")
    assert poses.positions_base_m is not None
    np.testing.assert_allclose(poses.positions_base_m[1], [0.5, 0.1, 0.4])
    np.testing.assert_allclose(poses.rotations[0].as_quat(canonical=True), [1, 0, 0, 0])


def test_pose_file_without_an_orientation_encoding_is_an_error(tmp_path: Path) -> None:
    path = tmp_path / "poses.csv"
    path.write_text("pose,alpha_deg,beta_deg\n1,90,0\n", encoding="utf-8")
    with pytest.raises(InputFileError, match="no orientation encoding"):
        read_pose_file(path)


def test_pose_file_with_a_bad_cell_names_row_and_column(tmp_path: Path) -> None:
    path = tmp_path / "poses.csv"
    path.write_text("alpha_deg,beta_deg,gamma_deg\n90,0,-180\n90,x,-180\n", encoding="utf-8")
    with pytest.raises(InputFileError, match="row 2, column 'beta_deg'"):
        read_pose_file(path)
