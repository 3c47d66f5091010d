"""The pose file: labels, positions, and one-line errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ftcomp.errors import InputFileError
from ftcomp.io.poses_csv import read_pose_file


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


def test_a_pose_id_given_at_two_different_orientations_is_an_error_as_in_calibrate(
    tmp_path: Path,
) -> None:
    path = tmp_path / "poses.csv"
    path.write_text(
        "pose,alpha_deg,beta_deg,gamma_deg\n1,90,0,-180\n2,0,0,180\n1,60,0,-180\n",
        encoding="utf-8",
    )
    with pytest.raises(InputFileError, match="pose '1' is given twice at different poses"):
        read_pose_file(path)


def test_a_field_over_the_csv_limit_is_an_input_error_naming_the_file(tmp_path: Path) -> None:
    path = tmp_path / "poses.csv"
    path.write_text("qx,qy,qz,qw,note\n0,0,0,1," + "x" * (129 * 1024) + "\n")
    with pytest.raises(InputFileError, match=r"poses\.csv: not a readable pose CSV"):
        read_pose_file(path)


def test_a_missing_pose_file_named_like_paper_points_to_the_papers_poses(
    tmp_path, monkeypatch
) -> None:
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputFileError, match=r"^papr: no such pose file \(did you mean 'paper'"):
        read_pose_file("papr")
    with pytest.raises(InputFileError, match=r"^poses\.csv: no such pose file$"):
        read_pose_file("poses.csv")
