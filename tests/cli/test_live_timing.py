"""``ftcomp stream`` and ``ftcomp run`` end with their timing line and save the block beside
their log (the simulated cell: no lateness judged, compute time and sensor age given)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from ftcomp.cli import main

pytest.importorskip("mujoco")


def _calibration(path: Path) -> Path:
    from ftcomp.io.calibration_json import model_to_dict
    from ftcomp.sim.cell import SimCell

    document = model_to_dict(SimCell().true_gravity_model())
    document.update(format="ftcomp.calibration/1", method="paper")
    path.write_text(json.dumps(document))
    return path


@pytest.mark.parametrize("command", ["stream", "run"])
def test_a_live_command_prints_its_timing_and_saves_it_beside_the_log(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str
) -> None:
    out = tmp_path / "log.csv"
    argv = [command, "--robot", "sim://", "--sensor", "sim://", "--seconds", "0.3", "-o", str(out)]
    if command == "run":
        cal = _calibration(tmp_path / "cal.json")
        argv += ["-c", str(cal), "--control", "admittance", "--dry-run"]
    code = main(argv)
    captured = capsys.readouterr()
    assert code == 0, captured.err
    line = next(ln for ln in captured.out.splitlines() if ln.startswith("timing: "))
    assert "compute p50" in line and "sensor age p50" in line and "missed" not in line
    block = json.loads((tmp_path / "log.timing.json").read_text())
    assert block["format"] == "ftcomp.timing/1" and block["line"] == line
    assert block["cycles"] > 0 and block["paced"] is False
