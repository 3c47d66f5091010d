"""``calibrate --bias-drift stochastic`` and ``compensate`` with it, called as a user would:
exit codes, one-line errors, the calibration file's drift model and validity window."""

from __future__ import annotations

import csv
import json

from scipy.spatial.transform import Rotation

from calibration.sim_drift_data import session
from ftcomp.cli import main


def write_csv(path, samples, *, with_t: bool = True, t=None) -> None:
    """A sample CSV of ``samples`` (optionally without t, or with other times)."""
    times = samples.t if t is None else t
    quat = Rotation.from_matrix(samples.R_base_sensor).as_quat()
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        head = ["pose", *(["t"] if with_t else []), "fx", "fy", "fz", "tx", "ty", "tz"]
        w.writerow([*head, "qx", "qy", "qz", "qw"])
        for k in range(0, len(samples), 10):  # every 10th reading: 60 per pose
            stamp = [f"{times[k]:.6f}"] if with_t else []
            w.writerow([samples.pose[k], *stamp, *samples.wrench_sensor[k], *quat[k]])


def test_calibrate_stochastic_writes_the_drift_and_its_window(tmp_path, capsys) -> None:
    _, samples, _ = session(31, 8)
    path, cal = tmp_path / "s.csv", tmp_path / "cal.json"
    write_csv(path, samples)
    assert main(["calibrate", str(path), "--bias-drift", "stochastic", "-o", str(cal)]) == 0
    out = capsys.readouterr().out
    assert "stochastic" in out and "held" in out
    drift = json.loads(cal.read_text())["bias_drift"]
    assert drift["model"] == "stochastic"
    assert drift["t_range_s"][0] <= drift["t_range_s"][1]
    assert len(drift["knots_t_s"]) == 8
    out_csv = tmp_path / "out.csv"
    assert main(["compensate", str(path), "-c", str(cal), "-o", str(out_csv)]) == 0


def test_bad_input_for_a_stochastic_drift_is_one_line_and_exit_2(tmp_path, capsys) -> None:
    _, samples, _ = session(32, 8)
    cases = {}
    cases["no_t.csv"] = dict(with_t=False)
    t = samples.t.copy()
    t[3000:] -= 100.0  # the clock goes back mid-recording
    cases["back.csv"] = dict(t=t)
    for name, kwargs in cases.items():
        path = tmp_path / name
        write_csv(path, samples, **kwargs)
        assert main(["calibrate", str(path), "--bias-drift", "stochastic"]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: ") and "\n" not in err and "Traceback" not in err
    _, few, _ = session(33, 5)
    path = tmp_path / "few.csv"
    write_csv(path, few)
    assert main(["calibrate", str(path), "--bias-drift", "stochastic"]) == 2
    err = capsys.readouterr().err.strip()
    assert "needs at least 6" in err and "\n" not in err


def test_calibrate_sensor_map_reports_its_verdict_and_writes_it(tmp_path, capsys) -> None:
    _, samples, _ = session(34, 8)
    path, cal = tmp_path / "s.csv", tmp_path / "cal.json"
    write_csv(path, samples)
    argv = ["calibrate", str(path), "--bias-drift", "stochastic", "--sensor-map", "linear"]
    assert main([*argv, "-o", str(cal)]) == 0
    captured = capsys.readouterr()
    assert "Linear sensor map" in captured.out
    assert "linear sensor map" in captured.err  # the verdict, supported or not
    data = json.loads(cal.read_text())["sensor_map"]
    assert isinstance(data["supported"], bool) and len(data["delta"]) == 6
    assert main([*argv, "--method", "paper"]) == 2
    assert "need --method joint" in capsys.readouterr().err
