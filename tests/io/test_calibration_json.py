"""The calibration file: round trip, atomic writes, and checks on load."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from ftcomp.calibration.identify import calibrate
from ftcomp.errors import CalibrationFileError, ParameterError
from ftcomp.io.atomic import atomic_write_text, check_writable
from ftcomp.io.calibration_json import FORMAT, load_calibration, save_calibration
from ftcomp.io.samples_csv import read_samples

from conftest import PAPER_CSV

REQUIRED_KEYS = {
    "format",
    "method",
    "tool_weight_N",
    "tool_mass_kg",
    "center_of_gravity_m",
    "force_bias_N",
    "torque_bias_Nm",
    "base_tilt_deg",
    "gravity_in_base_N",
    "std_errors",
    "residual_rms",
    "relative_error_percent",
    "poses",
}


@pytest.fixture(scope="module")
def paper_calibration():
    return calibrate(read_samples(PAPER_CSV), method="paper")


def test_calibration_file_has_every_documented_key(tmp_path, paper_calibration) -> None:
    path = tmp_path / "cal.json"
    save_calibration(path, paper_calibration)
    data = json.loads(path.read_text())
    assert set(data) >= REQUIRED_KEYS
    assert data["format"] == FORMAT
    assert set(data["std_errors"]) >= {
        "tool_weight_N",
        "center_of_gravity_m",
        "force_bias_N",
        "torque_bias_Nm",
        "base_tilt_deg",
        "gravity_in_base_N",
    }
    assert len(data["relative_error_percent"]["per_pose"]) == 9
    assert data["poses"] == 9


def test_calibration_file_round_trips(tmp_path, paper_calibration) -> None:
    path = tmp_path / "cal.json"
    save_calibration(path, paper_calibration)
    back = load_calibration(path)
    for name in ("center_of_gravity_m", "force_bias_N", "torque_bias_Nm", "gravity_base_N"):
        np.testing.assert_allclose(
            getattr(back.model, name), getattr(paper_calibration.model, name), atol=1e-12
        )
    assert back.model.weight_N == pytest.approx(paper_calibration.model.weight_N, abs=1e-12)
    np.testing.assert_allclose(back.R_base_sensor, paper_calibration.R_base_sensor, atol=1e-12)
    np.testing.assert_allclose(
        back.relative_error_percent, paper_calibration.relative_error_percent
    )
    np.testing.assert_allclose(
        back.std_errors.center_of_gravity_m, paper_calibration.std_errors.center_of_gravity_m
    )
    assert back.std_errors.tilt_U_rad == pytest.approx(paper_calibration.std_errors.tilt_U_rad)
    assert back.pose_ids == paper_calibration.pose_ids
    assert back.method == "paper"


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (
            lambda d: d.update(format="other/2"),
            r"not an ftcomp calibration file: its format is 'other/2'; ftcomp reads calibration "
            r"files with \"format\": \"ftcomp.calibration/1\"",
        ),
        (lambda d: d.pop("force_bias_N"), r"missing key 'force_bias_N'"),
        (lambda d: d.update(tool_weight_N=float("nan")), r"'tool_weight_N' is not finite"),
        (
            lambda d: d.update(center_of_gravity_m=[0, 0]),
            r"'center_of_gravity_m' must be a list of 3 numbers",
        ),
        (
            lambda d: d.update(torque_bias_Nm=[0, "x", 0]),
            r"'torque_bias_Nm' must be a number, got 'x'",
        ),
        (lambda d: d["base_tilt_deg"].pop("V"), r"base_tilt_deg: 'V' must be a number, got None"),
        (lambda d: d.update(method="magic"), r"'method' must be 'paper' or 'joint'"),
    ],
)
def test_bad_calibration_files_are_rejected_clearly(
    tmp_path, paper_calibration, mutate, message
) -> None:
    path = tmp_path / "cal.json"
    save_calibration(path, paper_calibration)
    data = json.loads(path.read_text())
    mutate(data)
    path.write_text(json.dumps(data))
    with pytest.raises(CalibrationFileError, match=message):
        load_calibration(path)


def test_non_json_and_missing_files_are_rejected(tmp_path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(CalibrationFileError, match=r"bad.json: not valid JSON \(line 1, column 2"):
        load_calibration(bad)
    with pytest.raises(CalibrationFileError, match="no such file"):
        load_calibration(tmp_path / "none.json")


def test_atomic_write_leaves_the_old_file_when_writing_fails(tmp_path) -> None:
    path = tmp_path / "keep.txt"
    path.write_text("old")

    class Boom:
        def __str__(self) -> str:
            raise RuntimeError("boom")

    with pytest.raises(TypeError):
        atomic_write_text(path, Boom())  # type: ignore[arg-type]
    assert path.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.txt"]


def test_existing_files_are_not_replaced_without_being_asked(tmp_path) -> None:
    path = tmp_path / "x.json"
    path.write_text("mine")
    with pytest.raises(ParameterError, match=r"x.json: exists; pass overwrite=True"):
        check_writable(path, overwrite=False)
    assert check_writable(path, overwrite=True) == path


def _paper_file(tmp_path: Path, **changes: object) -> Path:
    """The paper's calibration as a file, with some keys changed."""
    from ftcomp.calibration.identify import calibrate
    from ftcomp.io.calibration_json import calibration_to_dict
    from ftcomp.paper import paper_samples

    data = calibration_to_dict(calibrate(paper_samples(), method="paper"))
    data.update(changes)
    path = tmp_path / "cal.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"tool_weight_N": 1e308}, "'tool_weight_N' = 1e\\+308 is beyond any plausible"),
        ({"tool_weight_N": 10**400}, "too large"),
        ({"center_of_gravity_m": [0, 0, 1e6]}, "'center_of_gravity_m' = 1e\\+06"),
        ({"base_tilt_deg": {"U": 120, "V": 0}}, "base_tilt_deg.U = 120 deg"),
    ],
)
def test_absurd_numbers_in_a_calibration_file_are_one_clear_error(
    tmp_path: Path, changes: dict[str, object], message: str
) -> None:
    path = _paper_file(tmp_path, **changes)
    with pytest.raises(CalibrationFileError, match=message) as info:
        load_calibration(path)
    assert str(path) in str(info.value)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
        ('{"tool_weight_N": ' + "9" * 5000 + "}", "not valid JSON"),
        ('{"a":' * 40 + "1" + "}" * 40, "nested too deeply"),
    ],
)
def test_hostile_json_is_one_clear_error(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "cal.json"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(CalibrationFileError, match=message):
        load_calibration(path)


def test_an_absurd_calibration_is_never_written(tmp_path: Path) -> None:
    from dataclasses import replace

    from ftcomp.calibration.identify import calibrate
    from ftcomp.paper import paper_samples

    good = calibrate(paper_samples(), method="paper")
    absurd = replace(good, model=replace(good.model, weight_N=1e308))
    with pytest.raises(CalibrationFileError, match="beyond any plausible"):
        save_calibration(tmp_path / "out.json", absurd)
    assert not (tmp_path / "out.json").exists()


def test_a_parameters_only_file_loads_and_saves_again(tmp_path: Path) -> None:
    from ftcomp.io.calibration_json import model_to_dict
    from ftcomp.model import GravityModel

    model = GravityModel(
        3.0, [0, 0, 0.05], [0.1, 0, 0], [0, 0.01, 0], tilt_U_rad=0.0, tilt_V_rad=0.0
    )
    minimal = tmp_path / "min.json"
    minimal.write_text(json.dumps({"format": FORMAT, "method": "joint", **model_to_dict(model)}))
    again = tmp_path / "again.json"
    save_calibration(again, load_calibration(minimal))
    back = load_calibration(again).model
    assert back.weight_N == model.weight_N
    np.testing.assert_array_equal(back.center_of_gravity_m, model.center_of_gravity_m)
    assert json.loads(again.read_text())["std_errors"]["tool_weight_N"] is None


def test_another_tools_json_is_described_and_what_ftcomp_reads_is_said(tmp_path) -> None:
    path = tmp_path / "payload.json"
    path.write_text('{"mass": 1.2, "cog": [0, 0, 0.05], "inertia": [0, 0, 0]}')
    with pytest.raises(CalibrationFileError) as info:
        load_calibration(path)
    message = str(info.value)
    assert message.startswith(f"{path}: not an ftcomp calibration file: a JSON object with no ")
    assert "(keys: 'mass', 'cog', 'inertia')" in message
    assert '"format": "ftcomp.calibration/1"' in message and "None" not in message
