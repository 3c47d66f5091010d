"""The documented first session works from wherever the arm stands (issue 34).

On the UR5e twin started at a random joint configuration (``ftcomp twin --start-q-deg``: wrist 3
anywhere within +-150 deg of the twin's home, the other joints 12 to 40 deg away from it, either
side) and a small base tilt, ``poses design --count 9 --robot ur://H`` -> ``record --robot ur://H
--sensor netft://S --poses poses.csv`` -> ``calibrate``, every command at its defaults, records
all 9 poses and calibrates within the family bound of the twin's truth (as
``tests/devices/test_conformance.py`` checks it). Before the record's joint moves and the
design's visit check, record's moveLs wound a wrist joint to its end by the 4th pose from the
twin's own home (the issue's trial). ``bench/bench_first_session.py`` runs 20 starts.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("rtde_control")

from ftcomp.io.samples_csv import read_samples
from ftcomp.sim.arm import UR5E_HOME_Q_RAD
from standins.twin_process import running_twin

CLIENT = "import sys; from ftcomp.cli import main; sys.exit(main())"
KEYS = ("tool_weight_N", "center_of_gravity_m", "force_bias_N", "torque_bias_Nm")
#: The family bound of test_conformance.py: 13 numbers at once, each a t-statistic with 42
#: degrees of freedom, false alarms at 3 sigma's 0.27 % for the family: t(42) at 1 - 0.0027/26.
Z_MAX = 4.06


#: Untimed: a session at its defaults, judged by its poses and its calibration
#: (no stop, rate or lateness).
pytestmark = [pytest.mark.live, pytest.mark.untimed]


def random_start(rng: np.random.Generator) -> tuple[list[float], tuple[float, float]]:
    """A start configuration [deg] and a base tilt (U, V) [deg] as the issue states them."""
    home = np.degrees(UR5E_HOME_Q_RAD)
    away = rng.uniform(12.0, 40.0, 5) * rng.choice([-1.0, 1.0], 5)
    q = home + np.concatenate([away, [rng.uniform(-150.0, 150.0)]])
    tilt = rng.uniform(-1.5, 1.5, 2)
    return [round(float(v), 2) for v in q], (round(float(tilt[0]), 3), round(float(tilt[1]), 3))


def _ftcomp(*args: str, timeout_s: float = 300.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", CLIENT, *args],
        capture_output=True,
        text=True,
        timeout=timeout_s,
        check=False,
        env=dict(os.environ),
    )


#: Three starts in the suite, as issue 34 asks (a session is 45-60 s of the suite);
#: bench/bench_first_session.py runs any number (its 20 are in the issue's note).
STARTS = [random_start(np.random.default_rng(seed)) for seed in (1, 2, 3)]


@pytest.mark.parametrize(("start_q_deg", "tilt_deg"), STARTS)
def test_the_first_session_at_its_defaults_completes_from_a_random_start(
    start_q_deg: list[float], tilt_deg: tuple[float, float], tmp_path: Path
) -> None:
    truth, poses, samples, cal = (tmp_path / n for n in ("t.json", "p.csv", "s.csv", "c.json"))
    start = ",".join(f"{v:g}" for v in start_q_deg)
    tilt = f"--tilt-deg={tilt_deg[0]:g},{tilt_deg[1]:g}"
    name = f"first_session_{start}"
    with running_twin(
        name,
        f"--start-q-deg={start}",
        tilt,
        "--truth",
        str(truth),
        seconds=400.0,
        ready_timeout_s=120.0,  # the start move (up to 2.5 s of arm time) on a busy host
    ) as twin:
        design = _ftcomp(
            "poses", "design", "--count", "9", "--robot", twin.robot_uri, "-o", str(poses)
        )
        assert design.returncode == 0, design.stdout + design.stderr + twin.output()
        assert "visit: 9 poses by joint moves" in design.stdout, design.stdout
        recorded = _ftcomp(
            "record", "--robot", twin.robot_uri, "--sensor", twin.sensor_uri,
            "--poses", str(poses), "-o", str(samples),
        )  # fmt: skip
        assert recorded.returncode == 0, recorded.stdout + recorded.stderr + twin.output()
        assert "skipped" not in recorded.stderr, recorded.stderr
    calibrated = _ftcomp("calibrate", str(samples), "-o", str(cal))
    assert calibrated.returncode == 0, calibrated.stderr
    pose = read_samples(samples).pose
    assert pose is not None and len(set(pose)) == 9
    found, true = json.loads(cal.read_text()), json.loads(truth.read_text())
    for key in (*KEYS, "gravity_in_base_N"):
        error = np.atleast_1d(found[key]) - np.atleast_1d(true[key])
        se = np.atleast_1d(found["std_errors"][key])
        assert np.all(np.abs(error) <= Z_MAX * se), (key, error, se, start, tilt)
    assert math.isfinite(found["tool_weight_N"])
