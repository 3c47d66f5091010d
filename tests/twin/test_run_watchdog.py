"""``ftcomp run``'s sensor watchdog against the twin's Net F/T, through pynetft: a sensor frozen
under fresh stamps stops the run (``frozen_sample``); the run prints its timing and saves the
block beside its log."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rtde_receive")
pytest.importorskip("pynetft")
pytest.importorskip("mujoco")

from standins.twin_process import running_twin


def _calibration(path: Path) -> Path:
    """The twin's default tool as a calibration file (the dry run needs one)."""
    from ftcomp.io.calibration_json import model_to_dict
    from ftcomp.sim.cell import SimCell

    document = model_to_dict(SimCell().true_gravity_model())
    document.update(format="ftcomp.calibration/1", method="paper")
    path.write_text(json.dumps(document))
    return path


def test_a_frozen_net_ft_stops_the_run_and_the_run_reports_its_timing(tmp_path: Path) -> None:
    calibration = _calibration(tmp_path / "cal.json")
    log = tmp_path / "run.csv"
    with running_twin(
        "twin_run_frozen", "--fault", "sensor-frozen", "--fault-at-s", "1.0", seconds=40.0
    ) as twin:
        done = subprocess.run(
            [sys.executable, "-m", "ftcomp", "run", "--robot", twin.robot_uri, "--sensor",
             twin.sensor_uri, "-c", str(calibration), "--control", "admittance", "--dry-run",
             "--seconds", "20", "-o", str(log)],
            capture_output=True, text=True, timeout=90, check=False,
        )  # fmt: skip
    assert done.returncode == 1, done.stdout + done.stderr
    assert "protective stop: frozen_sample" in done.stderr, done.stderr
    assert "timing: " in done.stdout
    block = json.loads((tmp_path / "run.timing.json").read_text())
    assert block["cycles"] > 0 and block["period_s"] == pytest.approx(0.002)
