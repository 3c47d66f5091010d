"""``ftcomp sim collect``: files, determinism, refusing to overwrite, clear errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from ftcomp.cli import main


def _collect(tmp_path: Path, *extra: str, name: str = "samples") -> tuple[Path, Path, int]:
    samples, truth = tmp_path / f"{name}.csv", tmp_path / f"{name}_truth.json"
    args = ["sim", "collect", "--samples-per-pose", "40", "-o", str(samples), "--truth", str(truth)]
    code = main([*args, *extra])
    return samples, truth, code


def test_collect_writes_samples_and_truth_with_calibration_keys(tmp_path: Path) -> None:
    samples, truth, code = _collect(tmp_path)
    assert code == 0
    header = samples.read_text(encoding="utf-8").splitlines()[0]
    assert header == "pose,t,alpha_deg,beta_deg,gamma_deg,fx,fy,fz,tx,ty,tz"
    assert len(samples.read_text(encoding="utf-8").splitlines()) == 1 + 9 * 40
    data = json.loads(truth.read_text(encoding="utf-8"))
    for key in ("tool_weight_N", "center_of_gravity_m", "force_bias_N", "torque_bias_Nm"):
        assert key in data
    assert data["tool_weight_N"] == pytest.approx(3.153, abs=1e-9)
    assert data["base_tilt_deg"] == pytest.approx({"U": -0.204, "V": -0.129})
    assert len(data["gravity_in_base_N"]) == 3


def test_collect_then_calibrate_runs_end_to_end(tmp_path: Path) -> None:
    samples, _, code = _collect(tmp_path)
    assert code == 0
    assert main(["calibrate", str(samples), "-o", str(tmp_path / "cal.json"), "--json"]) == 0


def test_same_seed_writes_the_same_file(tmp_path: Path) -> None:
    a, _, _ = _collect(tmp_path, "--seed", "3", name="a")
    b, _, _ = _collect(tmp_path, "--seed", "3", name="b")
    c, _, _ = _collect(tmp_path, "--seed", "4", name="c")
    assert a.read_bytes() == b.read_bytes()
    assert a.read_bytes() != c.read_bytes()


def test_no_gripper_and_a_load_change_the_truth(tmp_path: Path) -> None:
    _, bare, _ = _collect(tmp_path, "--no-gripper", name="bare")
    _, loaded, _ = _collect(tmp_path, "--load-kg", "0.5", name="loaded")
    assert json.loads(bare.read_text())["tool_weight_N"] == pytest.approx(0.835, abs=1e-9)
    weight = json.loads(loaded.read_text())["tool_weight_N"]
    assert weight == pytest.approx(3.153 + 0.5 * 9.80665, abs=1e-9)


def test_collect_refuses_to_overwrite_without_force(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    samples, _, _ = _collect(tmp_path)
    before = samples.read_bytes()
    _, _, code = _collect(tmp_path, "--seed", "9")
    assert code == 2
    assert "exists" in capsys.readouterr().err
    assert samples.read_bytes() == before
    _, _, code = _collect(tmp_path, "--seed", "9", "--force")
    assert code == 0 and samples.read_bytes() != before


def test_unreachable_pose_in_a_file_is_an_error_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    poses = tmp_path / "poses.csv"
    poses.write_text(
        "pose,alpha_deg,beta_deg,gamma_deg,x_m,y_m,z_m\n"
        "near,90,0,-180,0.45,0,0.42\n"
        "far,90,0,-180,2.0,0,0.42\n",
        encoding="utf-8",
    )
    samples, truth, code = _collect(tmp_path, "--poses", str(poses))
    assert code == 2
    assert "pose far" in capsys.readouterr().err
    assert not samples.exists() and not truth.exists(), "nothing half-written"


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (("--load-kg", "-1"), "--load-kg"),
        (("--tilt-deg", "45", "0"), "--tilt-deg"),
        (("--no-gripper", "--load-kg", "0.5"), "gripper"),
    ],
)
def test_bad_arguments_are_one_line_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: tuple[str, ...], message: str
) -> None:
    _, _, code = _collect(tmp_path, *extra)
    assert code == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("reach", ["robot", "urdf"])
def test_designed_poses_are_all_reached_by_sim_collect(tmp_path: Path, reach: str) -> None:
    # Issue 15: a design checked by the simulated arm's IK (--robot), or by its URDF's
    # (--urdf, the same arm described as a URDF, at a position of its own), is a --poses file
    # that the cell visits pose for pose.
    import numpy as np

    from ftcomp.io.samples_csv import read_samples
    from ftcomp.sim import SceneConfig, SimCell
    from ros2.simbag import urdf_of_cell

    poses = tmp_path / "poses.csv"
    design = ["poses", "design", "--count", "9", "-o", str(poses)]
    if reach == "robot":
        design += ["--robot", "sim://"]
    else:
        urdf = tmp_path / "arm.urdf"
        urdf.write_text(urdf_of_cell(SimCell(SceneConfig())), encoding="utf-8")
        design += ["--urdf", str(urdf), "--position-mm", "450", "0", "420"]
    assert main(design) == 0
    samples, _, code = _collect(tmp_path, "--poses", str(poses))
    assert code == 0
    got = read_samples(samples)
    assert got.pose is not None
    assert len(np.unique(got.pose)) == 9 and len(got.pose) == 9 * 40
