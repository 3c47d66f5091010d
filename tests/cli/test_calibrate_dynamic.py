"""``ftcomp calibrate-dynamic``: a recorded excitation in, the inertia out; bad input, one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from tests.calibration.test_dynamic import INERTIA, TOOL, excitation

from ftcomp.calibration.identify import calibrate
from ftcomp.cli import main
from ftcomp.io.calibration_json import save_calibration
from ftcomp.paper import paper_poses
from ftcomp.samples import WRENCH_COLUMNS, Samples


def _calibration(tmp_path: Path) -> Path:
    rng = np.random.default_rng(1)
    R = np.repeat(paper_poses().rotations.as_matrix(), 200, axis=0)
    w = TOOL.predict(R) + rng.normal(0.0, 1.0, (len(R), 6)) * ([0.125] * 3 + [0.003] * 3)
    path = tmp_path / "calibration.json"
    save_calibration(path, calibrate(Samples(w, R, "quaternion"), method="joint"))
    return path


def _motion_csv(path: Path, duration_s: float, speed: float) -> Path:
    t, w, p, R = excitation(duration_s, speed, seed=5)
    q = Rotation.from_matrix(R).as_quat()
    header = ["t", *WRENCH_COLUMNS, "qx", "qy", "qz", "qw", "px", "py", "pz"]
    rows = np.column_stack([t, w, q, p])
    lines = [",".join(header)] + [",".join(f"{v:.10g}" for v in r) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_calibrate_dynamic_writes_the_inertia(tmp_path: Path, capsys) -> None:
    cal = _calibration(tmp_path)
    motion = _motion_csv(tmp_path / "motion.csv", 2.0, 1.0)
    out = tmp_path / "dynamic.json"
    assert main(["calibrate-dynamic", str(motion), "-c", str(cal), "-o", str(out)]) == 0
    doc = json.loads(out.read_text())
    # Within 5 % of the largest moment: noise, the calibration's own error, the filter.
    assert doc["inertia_cog_kgm2"]["Ixx"] == pytest.approx(INERTIA[0, 0], abs=0.05 * 8e-4)
    assert doc["inertia_cog_kgm2"]["Izz"] == pytest.approx(INERTIA[2, 2], abs=0.05 * 8e-4)
    assert "Ixx" in capsys.readouterr().out
    # Never overwritten without --force.
    assert main(["calibrate-dynamic", str(motion), "-c", str(cal), "-o", str(out)]) == 2


def test_a_too_slow_recording_is_one_error_line(tmp_path: Path, capsys) -> None:
    cal = _calibration(tmp_path)
    motion = _motion_csv(tmp_path / "motion.csv", 2.0, 0.2)
    out = tmp_path / "dynamic.json"
    assert main(["calibrate-dynamic", str(motion), "-c", str(cal), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and "too slow" in err[0]
    assert not out.exists()


def test_a_recording_without_positions_names_the_column(tmp_path: Path, capsys) -> None:
    cal = _calibration(tmp_path)
    motion = _motion_csv(tmp_path / "motion.csv", 2.0, 1.0)
    lines = motion.read_text().splitlines()
    motion.write_text("\n".join(",".join(x.split(",")[:-1]) for x in lines) + "\n")
    code = main(["calibrate-dynamic", str(motion), "-c", str(cal), "-o", str(tmp_path / "d.json")])
    assert code == 2
    assert "'pz'" in capsys.readouterr().err
