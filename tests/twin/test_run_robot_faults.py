"""Robot-side faults of the twin end ``ftcomp run`` at once with the documented stop, the log
kept and valid: a protective stop, the RTDE stream stopping, the program stopped from the
pendant (sensor-side faults: helper rt's watchdog tests)."""

from __future__ import annotations

import csv
import math
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rtde_control")
pytest.importorskip("pynetft")
pytest.importorskip("mujoco")

from standins.twin_process import calibration_from_truth, running_twin

FAULT_AT_S = 0.5
SECONDS = 4.0
#: fault -> (what run says, how long after the fault it may take to see it [s])
STOPS = {
    "protective-stop": ("the arm is in a protective stop", 0.0),
    "rtde-stop": ("no new data from the controller for 0.50 s", 0.5),
    "script-stop": ("the controller refused speedL", 0.0),
}
CLIENT = "import sys; from ftcomp.cli import main; sys.exit(main())"


@pytest.mark.parametrize(
    "fault",
    [
        "protective-stop",
        "rtde-stop",
        "script-stop",
    ],
)
def test_a_robot_fault_ends_run_at_once_with_its_stop_and_a_valid_log(
    fault: str, tmp_path: Path
) -> None:
    truth, calibration, log = tmp_path / "truth.json", tmp_path / "cal.json", tmp_path / "run.csv"
    options = ("--truth", str(truth), "--fault", fault, "--fault-at-s", str(FAULT_AT_S))
    with running_twin(f"twin_run_{fault}", *options) as twin:
        calibration_from_truth(truth, calibration)
        done = subprocess.run(
            [sys.executable, "-c", CLIENT, "run", "--robot", twin.robot_uri,
             "--sensor", twin.sensor_uri, "-c", str(calibration), "--control", "admittance",
             "--axes", "z", "--settle-band-N", "0.0001", "--seconds", str(SECONDS),
             "--max-late-cycles", "50", "-o", str(log)],
            capture_output=True, text=True, timeout=20, check=False,
        )  # fmt: skip
    message, detection_s = STOPS[fault]
    assert done.returncode == 1, done.stdout + done.stderr
    assert message in done.stderr and "the robot was stopped" in done.stderr, done.stderr
    with log.open() as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    assert body and all(len(row) == len(header) for row in body)
    t_s = [float(row[0]) for row in body]
    assert all(math.isfinite(t) for t in t_s) and t_s == sorted(t_s)
    # at once: the run's clock starts with its RTDE stream, the fault's clock too
    assert t_s[-1] <= FAULT_AT_S + detection_s + 0.5, t_s[-1]
