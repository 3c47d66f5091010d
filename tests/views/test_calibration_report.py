"""``calibrate --report cal.html``: one self-contained page, checked in headless Chromium for the
paper's data, a designed-pose recording (with the designed poses drawn) and a drift fit."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from ftcomp.calibration.identify import calibrate
from ftcomp.cli import main
from ftcomp.io.poses_csv import read_pose_file
from ftcomp.io.samples_csv import read_samples
from ftcomp.paper import data_path
from ftcomp.views.calibration_report import coverage_gap, write_calibration_report
from views.headless_chromium import chromium_binary, measure_page

pytest.importorskip("matplotlib")


def _pages_fit(path: Path) -> None:
    """Not blank, every figure embedded and loaded, nothing wider than 800 or 1280 px."""
    if chromium_binary() is None:
        pytest.skip("chromium not installed (Debian: apt-get install chromium); CI installs it")
    text = path.read_text()
    assert 'src="data:image/png;base64,' in text and not re.search(r'src="(?!data:)', text)
    for width, page in measure_page(path, [800, 1280]).items():
        assert page["images"] and all(i["loaded"] for i in page["images"]), page["images"]
        assert all(i["shownWidth"] > 300 for i in page["images"])  # not blank: drawn, shown
        assert page["scrollWidth"] <= width and not page["overflowing"], (
            width,
            page["overflowing"][:3],
        )


def test_the_paper_data_report_shows_parameters_poses_and_what_would_help(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    report = tmp_path / "cal.html"
    assert (
        main(["calibrate", data_path(), "--sensor-map", "physical", "--report", str(report)]) == 0
    )
    assert f"report written to {report}" in capsys.readouterr().out.replace("\n", "")
    text = report.read_text()
    for words in ("tool weight G", "3.1537 ± 0.0219", "leave-one-out", "largest uncovered"):
        assert words in text, words
    assert text.count("<img") == 2 and "Bias drift" not in text
    _pages_fit(report)


def test_the_largest_gap_is_where_no_pose_is_and_a_pose_there_helps() -> None:
    result = calibrate(read_samples(data_path()), method="joint")
    gap = coverage_gap(result)
    # The paper's poses all hold gravity near the sensor's +z: the gap is around -z.
    assert gap.direction_sensor[2] < -0.9
    assert gap.angle_rad > math.radians(120.0)
    assert gap.condition_number == pytest.approx(result.condition_number, rel=1e-6)
    assert gap.condition_with_pose < gap.condition_number


def test_a_designed_pose_recording_report_draws_the_designed_poses(tmp_path: Path) -> None:
    poses, samples = tmp_path / "poses.csv", tmp_path / "s.csv"
    assert main(["poses", "design", "--count", "7", "--robot", "sim://", "-o", str(poses)]) == 0
    record = ["record", "--robot", "sim://?seed=3", "--sensor", "sim://", "--poses", str(poses)]
    assert main([*record, "--samples-per-pose", "50", "--move-s", "1", "-o", str(samples)]) == 0
    readings = read_samples(samples)
    designed = read_pose_file(poses)
    report = tmp_path / "designed.html"
    write_calibration_report(
        report,
        calibrate(readings, method="joint"),
        source=str(samples),
        samples=readings,
        designed_R_base_sensor=designed.rotations.as_matrix(),
    )
    _pages_fit(report)


def test_a_drift_fit_report_plots_the_drift(tmp_path: Path) -> None:
    samples, report = tmp_path / "s.csv", tmp_path / "drift.html"
    robot = "sim://?seed=2&drift_N_per_min=0.6,0,-0.3"
    record = ["record", "--robot", robot, "--sensor", "sim://", "--poses", "paper"]
    assert main([*record, "--samples-per-pose", "50", "--move-s", "1", "-o", str(samples)]) == 0
    argv = ["calibrate", str(samples), "--bias-drift", "linear", "--report", str(report)]
    assert main(argv) == 0
    text = report.read_text()
    assert "Bias drift" in text and "drift c1 fx" in text and text.count("<img") == 3
    _pages_fit(report)


def test_the_report_refuses_to_replace_the_samples(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    samples = tmp_path / "s.csv"
    samples.write_text(Path(data_path()).read_text())
    assert main(["calibrate", str(samples), "--report", str(samples), "--force"]) == 2
    assert "is also an input" in capsys.readouterr().err
    assert np.loadtxt(samples, delimiter=",", skiprows=1, ndmin=2).size > 0
