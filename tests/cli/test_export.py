"""``ftcomp export ros2``: called as a user would."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from ruamel.yaml import YAML

from ftcomp.cli import main
from ftcomp.io.calibration_json import FORMAT, model_to_dict

from conftest import TRUE_MODEL


@pytest.fixture
def calibration(tmp_path: Path) -> Path:
    path = tmp_path / "cal.json"
    path.write_text(json.dumps({"format": FORMAT, "method": "joint", **model_to_dict(TRUE_MODEL)}))
    return path


def test_export_writes_parameters_with_the_bias_as_a_negative_offset(
    tmp_path: Path, calibration: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "params.yaml"
    args = ["export", "ros2", str(calibration), "-o", str(out)]
    assert main([*args, "--world-frame", "base_link", "--sensor-frame", "ft_sensor"]) == 0
    assert "written to" in capsys.readouterr().out
    params = YAML(typ="safe", pure=True).load(out.read_text())
    offset = params["force_torque_sensor_broadcaster"]["ros__parameters"]["offset"]
    np.testing.assert_allclose(
        [offset["force"][a] for a in "xyz"], -TRUE_MODEL.force_bias_N, atol=1e-12
    )
    assert set(params) == {"force_torque_sensor_broadcaster", "admittance_controller"}


def test_export_keeps_an_existing_file_unless_force(
    tmp_path: Path, calibration: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "params.yaml"
    out.write_text("mine")
    args = ["export", "ros2", str(calibration), "-o", str(out), "--world-frame", "b"]
    assert main([*args, "--sensor-frame", "s"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "exists" in err
    assert out.read_text() == "mine"
    assert main([*args, "--sensor-frame", "s", "--force"]) == 0


def test_export_of_a_missing_calibration_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["export", "ros2", str(tmp_path / "none.json"), "-o", str(tmp_path / "p.yaml")]
    assert main([*args, "--world-frame", "b", "--sensor-frame", "s"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "none.json" in err
    assert not (tmp_path / "p.yaml").exists()
