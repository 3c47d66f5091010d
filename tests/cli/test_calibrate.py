"""``ftcomp calibrate`` and ``ftcomp compensate``: called as a user would, exit codes and output."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ftcomp.cli import main

from conftest import PAPER_CSV, PUBLISHED_JSON

PUBLISHED = json.loads(PUBLISHED_JSON.read_text())


def test_calibrate_paper_data_prints_a_table_and_writes_the_file(tmp_path, capsys) -> None:
    out = tmp_path / "cal.json"
    assert main(["calibrate", str(PAPER_CSV), "--method", "paper", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "tool weight G" in printed and "+3.1526 ± 0.0220" in printed
    assert "mean δ" in printed and "1.99" in printed and "2.98" in printed
    data = json.loads(out.read_text())
    assert round(data["tool_weight_N"], 3) == PUBLISHED["tool_weight_N"]
    assert data["method"] == "paper"


def test_calibrate_json_output_is_machine_readable(tmp_path, capsys) -> None:
    out = tmp_path / "cal.json"
    assert main(["calibrate", str(PAPER_CSV), "-o", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["method"] == "joint"
    assert data == json.loads(out.read_text())


def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text(PAPER_CSV.read_text().replace("3.3445", "x"))
    out = tmp_path / "cal.json"
    assert main(["calibrate", str(bad), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("error: ") and "row 1 (line 2), column 'fz': 'x' is not a number" in err
    assert not out.exists()
    assert list(tmp_path.iterdir()) == [bad]


def test_existing_output_is_kept_unless_force(tmp_path, capsys) -> None:
    out = tmp_path / "cal.json"
    out.write_text("precious")
    assert main(["calibrate", str(PAPER_CSV), "-o", str(out)]) == 2
    assert "exists; pass --force" in capsys.readouterr().err
    assert out.read_text() == "precious"
    assert main(["calibrate", str(PAPER_CSV), "-o", str(out), "--force"]) == 0
    assert json.loads(out.read_text())["format"] == "ftcomp.calibration/1"


def test_range_option_rejects_saturated_readings(tmp_path, capsys) -> None:
    out = tmp_path / "cal.json"
    assert main(["calibrate", str(PAPER_CSV), "-o", str(out), "--range", "3,6"]) == 2
    assert "column 'fz': 3.3445 N is beyond the sensor range +-3 N" in capsys.readouterr().err


def test_radian_angles_warn_on_stderr(tmp_path, capsys) -> None:
    lines = PAPER_CSV.read_text().splitlines()
    rad = tmp_path / "rad.csv"
    rows = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        cells[1:4] = [f"{np.radians(float(c)):.6f}" for c in cells[1:4]]
        rows.append(",".join(cells))
    rad.write_text("\n".join(rows) + "\n")
    main(["calibrate", str(rad), "-o", str(tmp_path / "c.json")])
    assert "were the angles given in radians?" in capsys.readouterr().err


def test_compensate_adds_contact_wrench_and_load_weight(tmp_path, capsys) -> None:
    cal = tmp_path / "cal.json"
    out = tmp_path / "out.csv"
    assert main(["calibrate", str(PAPER_CSV), "--method", "paper", "-o", str(cal)]) == 0
    assert main(["compensate", str(PAPER_CSV), "-c", str(cal), "-o", str(out)]) == 0
    header = out.read_text().splitlines()[0].split(",")
    assert header[-7:] == [
        "fx_ext",
        "fy_ext",
        "fz_ext",
        "tx_ext",
        "ty_ext",
        "tz_ext",
        "load_weight_N",
    ]
    assert header[:-7] == PAPER_CSV.read_text().splitlines()[0].split(",")
    data = np.genfromtxt(out, delimiter=",", names=True)
    # At the calibration poses the contact wrench is the residual: a few hundredths of a newton.
    assert np.all(data["load_weight_N"] < 0.06)


def test_compensate_refuses_to_overwrite_its_input(tmp_path, capsys) -> None:
    cal = tmp_path / "cal.json"
    samples = tmp_path / "s.csv"
    samples.write_text(PAPER_CSV.read_text())
    main(["calibrate", str(samples), "-o", str(cal)])
    assert main(["compensate", str(samples), "-c", str(cal), "-o", str(samples), "--force"]) == 2
    assert "would replace the input" in capsys.readouterr().err
    assert samples.read_text() == PAPER_CSV.read_text()


def test_compensate_with_a_broken_calibration_file_exits_2(tmp_path, capsys) -> None:
    cal = tmp_path / "cal.json"
    cal.write_text('{"format": "ftcomp.calibration/1", "method": "paper"}')
    assert main(["compensate", str(PAPER_CSV), "-c", str(cal), "-o", str(tmp_path / "o.csv")]) == 2
    assert "missing key 'tool_weight_N'" in capsys.readouterr().err


@pytest.mark.parametrize("argv", [["calibrate"], ["calibrate", "x.csv"], ["nope"]])
def test_usage_errors_exit_2_without_traceback(argv) -> None:
    proc = subprocess.run([sys.executable, "-m", "ftcomp", *argv], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr


def test_calibrate_never_writes_over_its_own_input_even_with_force(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    samples = tmp_path / "s.csv"
    samples.write_bytes(PAPER_CSV.read_bytes())
    assert main(["calibrate", str(samples), "-o", str(samples), "--force"]) == 2
    assert "is also an input of this command" in capsys.readouterr().err
    assert samples.read_bytes() == PAPER_CSV.read_bytes()


def test_a_calibration_with_many_poses_lists_only_the_worst_in_the_terminal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from scipy.spatial.transform import Rotation

    from ftcomp.cli.calibrate import MAX_POSES_SHOWN
    from ftcomp.io.samples_csv import write_samples
    from ftcomp.model import GravityModel

    rng = np.random.default_rng(3)
    n = MAX_POSES_SHOWN + 10
    rotations = Rotation.random(n, random_state=rng)
    model = GravityModel(3.0, [0, 0, 0.05], [0.1, 0, 0], [0, 0.01, 0], tilt_U_rad=0, tilt_V_rad=0)
    wrench = model.predict(rotations.as_matrix()) + rng.normal(scale=0.01, size=(n, 6))
    wrench[7, 2] += 2.0  # one pose far off: it must be among those listed
    samples = tmp_path / "s.csv"
    write_samples(samples, wrench, rotations, encoding="quaternion", pose=np.arange(n))
    assert main(["calibrate", str(samples), "-o", str(tmp_path / "c.json")]) == 0
    out = capsys.readouterr().out
    assert f"the {MAX_POSES_SHOWN} worst of {n} poses" in out
    listed = [line.split()[1] for line in out.splitlines() if line.startswith("│ ")]
    assert "7" in listed
