"""``ftcomp calibrate SAMPLES.csv``: the model the data support by default, said with why; a flag
forces one; ``--truth`` scores the result; what a new user met on the way."""

from __future__ import annotations

import json

import numpy as np
from scipy.spatial.transform import Rotation

from calibration.drift_data import readings, tilted_poses, truth
from ftcomp.cli import main
from ftcomp.io.samples_csv import write_samples
from ftcomp.io.truth_json import truth_document

from conftest import PAPER_CSV


def _steady_csv(tmp_path, seed: int = 0):
    rng = np.random.default_rng(seed)
    samples = readings(rng, truth(), tilted_poses(rng, 9), 100, pose_period_s=2.0)
    path = tmp_path / "s.csv"
    write_samples(
        path,
        samples.wrench_sensor,
        Rotation.from_matrix(samples.R_base_sensor),
        encoding="quaternion",
        pose=samples.pose,
        t=samples.t,
    )
    return path


def test_calibrate_says_which_model_it_chose_and_why(tmp_path, capsys) -> None:
    path = _steady_csv(tmp_path)
    assert main(["calibrate", str(path)]) == 0
    out = capsys.readouterr().out
    assert "model: a constant bias: the data do not support a drift" in out
    assert "model: the data do not support the linear sensor map" in out
    assert "Linear sensor map delta" not in out  # not applied, not asked for: no table


def test_a_flag_forces_the_model_and_no_choice_is_printed(tmp_path, capsys) -> None:
    path = _steady_csv(tmp_path)
    argv = ["calibrate", str(path), "--bias-drift", "linear", "--sensor-map", "physical"]
    assert main([*argv, "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["bias_drift"]["model"] == "linear"
    assert "model:" not in captured.err


def test_truth_prints_each_parameters_distance_in_standard_errors(tmp_path, capsys) -> None:
    path = _steady_csv(tmp_path, seed=1)
    truth_path = tmp_path / "truth.json"
    truth_path.write_text(json.dumps(truth_document(truth())))
    assert main(["calibrate", str(path), "--bias-drift", "none", "--truth", str(truth_path)]) == 0
    out = capsys.readouterr().out
    assert "Distance from the" in out and "centre of gravity P" in out
    largest = float(out.split("largest: ")[1].split(" at ")[1].split()[0])
    assert 0.0 < largest < 4.0  # 15 numbers from data made with this truth: a few SE at most
    # A calibration given as the truth is refused by name.
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(PAPER_CSV), "--method", "paper", "-o", str(cal)]) == 0
    capsys.readouterr()
    assert main(["calibrate", str(path), "--truth", str(cal)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {cal}: a calibration, not a truth file") and "\n" not in err


def test_an_existing_output_names_the_force_flag_once(tmp_path, capsys) -> None:
    out = tmp_path / "c.json"
    out.write_text("{}")
    assert main(["calibrate", str(PAPER_CSV), "--method", "paper", "-o", str(out)]) == 2
    assert capsys.readouterr().err.strip() == f"error: {out}: exists; pass --force to replace it"
