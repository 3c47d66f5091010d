"""The twin's faults through ``ftcomp run``: each ends the run with the documented stop, the log
kept and valid; a robot fault at once, a sensor fault in the period that sees it; added RTDE
latency within the limits is no fault and the run goes on to its end (a frozen sensor:
test_run_watchdog.py)."""

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
SECONDS = 3.0
CLIENT = "import sys; from ftcomp.cli import main; sys.exit(main())"
#: robot faults: what run says, and how long after the fault it may take to see it [s]
ROBOT_STOPS = {
    "protective-stop": ("the arm is in a protective stop", 0.0),
    "rtde-stop": ("no new data from the controller for 0.50 s", 0.5),
    "script-stop": ("the controller refused speedL", 0.0),
}
#: sensor faults: what run says (the record after the fault carries the status; 200 records,
#: ~0.17 s, lost: data older than --stale-ms, 20 ms)
SENSOR_STOPS = {
    "sensor-fault": "sensor fault serious_status",
    "rdt-loss": "stale_sample",
    # The robot's stream goes silent too: the stale reading is seen first, and the stop and
    # the disconnect, sent into a silent controller, must not wait on it (the subprocess's
    # time-out is the hang's guard).
    "network-loss": "stale_sample",
}


def _run_with_fault(
    fault: str, tmp_path: Path
) -> tuple[subprocess.CompletedProcess[str], list[float]]:
    """``ftcomp run`` against a twin given ``--fault``; the process and its log's times [s]
    (the log checked whole: every row complete, times finite and in order)."""
    truth, calibration, log = tmp_path / "truth.json", tmp_path / "cal.json", tmp_path / "run.csv"
    options = ("--truth", str(truth), "--fault", fault, "--fault-at-s", str(FAULT_AT_S))
    with running_twin(f"twin_run_{fault}", *options) as twin:
        calibration_from_truth(truth, calibration)
        done = subprocess.run(
            [sys.executable, "-c", CLIENT, "run", "--robot", twin.robot_uri,
             "--sensor", twin.sensor_uri, "-c", str(calibration), "--control", "admittance",
             "--axes", "z", "--settle-band-N", "0.0001", "--seconds", str(SECONDS),
             "--max-late-cycles", "50", "-o", str(log)],
            capture_output=True, text=True, timeout=30, check=False,
        )  # fmt: skip
    with log.open() as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    assert body and all(len(row) == len(header) for row in body)
    t_s = [float(row[0]) for row in body]
    assert all(math.isfinite(t) for t in t_s) and t_s == sorted(t_s)
    return done, t_s


@pytest.mark.parametrize("fault", sorted(ROBOT_STOPS))
def test_a_robot_fault_ends_run_at_once_with_its_stop_and_a_valid_log(
    fault: str, tmp_path: Path
) -> None:
    done, t_s = _run_with_fault(fault, tmp_path)
    message, detection_s = ROBOT_STOPS[fault]
    assert done.returncode == 1, done.stdout + done.stderr
    assert message in done.stderr and "the robot was stopped" in done.stderr, done.stderr
    # at once: the run's clock starts with its RTDE stream, the fault's clock too
    assert t_s[-1] <= FAULT_AT_S + detection_s + 0.5, t_s[-1]


@pytest.mark.parametrize("fault", sorted(SENSOR_STOPS))
def test_a_sensor_fault_ends_run_in_the_period_that_sees_it(fault: str, tmp_path: Path) -> None:
    done, t_s = _run_with_fault(fault, tmp_path)
    assert done.returncode == 1, done.stdout + done.stderr
    message = SENSOR_STOPS[fault]
    assert message in done.stderr and "the robot was stopped" in done.stderr, done.stderr
    assert t_s[-1] <= FAULT_AT_S + 0.1, t_s[-1]


def test_added_latency_within_the_limits_is_no_fault(tmp_path: Path) -> None:
    done, t_s = _run_with_fault("latency", tmp_path)  # RTDE packages 8-14 ms late
    assert done.returncode == 0, done.stdout + done.stderr
    assert SECONDS - 0.1 <= t_s[-1] <= SECONDS + 0.1, t_s[-1]  # it ran its time
