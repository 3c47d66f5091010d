"""The twin's remaining faults through ``ftcomp run``: a Net F/T reporting a serious fault and a
burst of lost RDT records stop the run in the period that sees them, with the documented stop
and the log kept; added RTDE latency within the limits is no fault, and the run goes on to its
end (the robot's faults: test_run_robot_faults.py; a frozen sensor: test_run_watchdog.py)."""

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
#: fault -> (exit code, what run says or None, the latest the log may end [s] on its clock)
ENDS = {
    # the record after the fault carries the status: seen in the period it arrives
    "sensor-fault": (1, "sensor fault serious_status", FAULT_AT_S + 0.1),
    # 200 records (~0.17 s) lost: data older than --stale-ms (20 ms) stops the run
    "rdt-loss": (1, "stale_sample", FAULT_AT_S + 0.1),
    # RTDE packages 8-12 ms late: under the robot's 0.5 s time-out, not a fault
    "latency": (0, None, SECONDS + 0.1),
}


@pytest.mark.parametrize("fault", sorted(ENDS))
def test_a_sensor_fault_stops_run_in_the_period_that_sees_it_and_latency_does_not(
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
            capture_output=True, text=True, timeout=30, check=False,
        )  # fmt: skip
    code, message, latest_s = ENDS[fault]
    assert done.returncode == code, done.stdout + done.stderr
    if message is not None:
        assert message in done.stderr and "the robot was stopped" in done.stderr, done.stderr
    with log.open() as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    assert body and all(len(row) == len(header) for row in body)
    t_s = [float(row[0]) for row in body]
    assert all(math.isfinite(t) for t in t_s) and t_s == sorted(t_s)
    assert t_s[-1] <= latest_s, t_s[-1]
    if message is None:
        assert t_s[-1] >= SECONDS - 0.1, t_s[-1]  # it ran its time
