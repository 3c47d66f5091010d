"""The real workflow through the real clients (ur_rtde, pynetft) against ``ftcomp twin``:
robot-driven ``record`` -> ``calibrate`` recovers the twin's truth; ``run`` with that
calibration sets a 0.5 kg load down on the sponge and on the book gently (the twin's contact
log)."""

from __future__ import annotations

import csv
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

pytest.importorskip("rtde_control")
pytest.importorskip("pynetft")
pytest.importorskip("mujoco")

from ftcomp.calibration.identify import pose_means
from ftcomp.calibration.methods import fit_method
from ftcomp.io.samples_csv import read_samples
from standins.twin_process import running_twin

TILT = "--tilt-deg=-0.204,-0.129"
LOAD_WEIGHT_N = 0.5 * 9.81
KEYS = ("tool_weight_N", "center_of_gravity_m", "force_bias_N", "torque_bias_Nm")


#: ``ftcomp`` as a user runs it: the live loop sets the interpreter's switch interval and asks
#: for real-time priority itself (``ftcomp.hardware.pacing.realtime_loop``).
CLIENT = "import sys; from ftcomp.cli import main; sys.exit(main())"


def _ftcomp(*args: str, timeout_s: float = 120.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", CLIENT, *args],
        capture_output=True,
        text=True,
        timeout=timeout_s,
        check=False,
    )


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """Record the paper's poses on the twin, calibrate: (calibration, truth)."""
    folder = tmp_path_factory.mktemp("twin_e2e")
    truth, samples, calibration = folder / "truth.json", folder / "s.csv", folder / "cal.json"
    with running_twin("twin_e2e_record", "--truth", str(truth), TILT, seconds=90.0) as twin:
        robot = f"{twin.robot_uri}?max_speed_mm_s=250&max_accel_mm_s2=1500"
        done = _ftcomp(
            "record", "--robot", robot, "--sensor", twin.sensor_uri, "--poses", "paper",
            "--samples-per-pose", "60", "--move-s", "0.5", "--position-mm", "450", "0", "420",
            "-o", str(samples),
        )  # fmt: skip
    assert done.returncode == 0, done.stderr + twin.output()
    done = _ftcomp("calibrate", str(samples), "-o", str(calibration))
    assert done.returncode == 0, done.stderr
    return calibration, truth


#: The 13 identified numbers are checked at once, each a t-statistic with 42 degrees of freedom
#: (the covariance is scaled by the residual variance of 54 numbers less 12 parameters). At 3
#: standard errors each, 5.8 % of correct calibrations would fail one of the 13; the bound that
#: keeps the family's false alarms at 3 sigma's 0.27 % is t(42) at 1 - 0.0027 / 26: 4.06.
Z_MAX = 4.06
#: The 12 parameters together: their Mahalanobis distance from the truth through the fit's own
#: covariance, over 12, is F(12, 42) for a correct calibration (the numbers are strongly
#: correlated, weight with gravity's z at -1.0 and the torque bias with the centre of gravity at
#: -0.96, so no sum of their squares alone has a known law). It catches standard errors too
#: small across the board; beyond F's 1 - 0.0027 quantile, 3.18, 0.27 % of the time. Measured
#: under two busy loops: 25 recordings, mean 1.00 (1.05 expected), largest 2.02.
F_QUANTILE = 1.0 - 0.0027


def test_record_then_calibrate_recovers_the_twins_truth_within_its_standard_errors(
    calibrated: tuple[Path, Path],
) -> None:
    calibration, truth = calibrated
    found, true = json.loads(calibration.read_text()), json.loads(truth.read_text())
    for key in (*KEYS, "gravity_in_base_N"):
        error = np.atleast_1d(found[key]) - np.atleast_1d(true[key])
        se = np.atleast_1d(found["std_errors"][key])
        assert np.all(np.abs(error) <= Z_MAX * se), (key, error, se)
    # The joint fit again (what ``calibrate`` ran) for its whole covariance.
    ids, R, wrench, count, var_mean = pose_means(read_samples(calibration.parent / "s.csv"))
    fit, _ = fit_method("joint", wrench, R, var_mean, count)
    assert np.allclose(fit.theta[:3], found["gravity_in_base_N"], rtol=1e-9, atol=1e-12)
    keys = ("gravity_in_base_N", "force_bias_N", "torque_bias_Nm", "center_of_gravity_m")
    error = fit.theta[:12] - np.concatenate([true[key] for key in keys])
    f = float(error @ np.linalg.solve(fit.covariance[:12, :12], error)) / 12
    dof = 6 * len(ids) - 12
    assert f <= stats.f.ppf(F_QUANTILE, 12, dof), (f, dof)


#: The paper's gains per surface (``ftcomp sim place``'s defaults): on the stiff book K1 = 0 and
#: K2 = 0.1 mm/(s*N). With the sponge's (K1 0.1 mm/N, K2 1) the force loop's time constant on
#: the book, 1 / (K2 * stiffness) with ~1.4e5 N/m from command to force, is 7 ms: shorter than
#: the loop's round trip through the twin (3-4 cycles), so it rings and presses 50-140 N (and
#: on sim:// it does not settle in 30 s either).
GAINS = {"sponge": ("--k1", "0.1", "--k2", "1"), "book": ("--k1", "0", "--k2", "0.1")}
ERROR = re.compile(r"mean force error over the last 0\.3 s \[(\S+) (\S+) (\S+)\]")


@pytest.mark.parametrize("surface", ["sponge", "book"])
def test_run_sets_a_half_kilogram_load_down_gently(
    calibrated: tuple[Path, Path], surface: str, tmp_path: Path
) -> None:
    calibration, _ = calibrated
    contact, log = tmp_path / "contact.csv", tmp_path / "run.csv"
    options = ("--load-kg", "0.5", "--surface", surface, "--clearance-mm", "2", TILT)
    with running_twin(f"twin_e2e_{surface}", *options, "--contact-log", str(contact)) as twin:
        done = _ftcomp(
            "run", "--robot", twin.robot_uri, "--sensor", twin.sensor_uri,
            "-c", str(calibration), "--control", "admittance", "--axes", "z",
            *GAINS[surface], "--settle-band-N", "0.03", "--seconds", "30",
            "--max-late-cycles", "50",  # a shared CI host: the client process is not real-time
            # nor is the twin, hardware's stand-in, on the same two cores: readings 18-19 ms
            # old were seen in runs that passed, one 20 ms stopped a CI run. A stale sensor's
            # stop at 20 ms is tested by test_run_faults.py (rdt-loss, network-loss).
            "--stale-ms", "50",
            "-o", str(log),
        )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr + twin.output()
    assert "settled" in done.stdout
    with contact.open() as f:
        rows = list(csv.DictReader(f))
    fz = np.array([float(r["fz"]) for r in rows])  # the surface pushing up (base z ~ up)
    assert fz.max() <= LOAD_WEIGHT_N + 0.3  # never pressed in beyond the weight
    # The surface carries it all (issue 20: within 0.05 N). The run ends as its error enters the
    # settle band, so the band (0.03 N) takes part of that and the calibration's error along z
    # the rest: with a 0.05 N band a run under load ended 0.052 N short, 0.032 N inside the band
    # and 0.020 N from the calibration's z bias (1.6 standard errors off).
    assert fz[-1] == pytest.approx(LOAD_WEIGHT_N, abs=0.05)
    assert all(r["safety"] == "normal" for r in rows)
    # The lateral contact (on the book the arm's servo springback held by friction, about 2 N;
    # on the sponge, which shears, almost none) is the lateral force the run reports at its end.
    found = ERROR.search(done.stdout)
    assert found is not None, done.stdout
    reported = np.array([float(found[1]), float(found[2])])
    lateral = np.array([float(rows[-1]["fx"]), float(rows[-1]["fy"])])
    assert np.all(np.abs(lateral - reported) <= 0.25), (lateral, reported)
