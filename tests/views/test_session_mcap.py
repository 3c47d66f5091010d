"""``--log FILE.mcap`` on the live commands: rosbags reads it, the counts and values are the CSV's,
and ``import-bag`` turns a recording's MCAP back into samples that calibrate like its CSV."""

from __future__ import annotations

import json
import sys
import threading
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from ftcomp.cli import main
from ftcomp.session.log import SWITCH_INTERVAL_S, ObserverThread

SIM = "sim://?seed=4"


def _csv(path: Path) -> dict[str, np.ndarray]:
    header = path.read_text().splitlines()[0].split(",")
    data = np.genfromtxt(path, delimiter=",", skip_header=1, ndmin=2)
    return {name: data[:, i] for i, name in enumerate(header)}


def _messages(path: Path) -> dict[str, list[tuple[int, object]]]:
    """Every message by topic: (log time [ns], the deserialised message)."""
    out: dict[str, list[tuple[int, object]]] = {}
    with AnyReader([path]) as reader:
        for conn in reader.connections:
            out.setdefault(conn.topic, [])
        for conn, t_ns, raw in reader.messages():
            out[conn.topic].append((t_ns, reader.deserialize(raw, conn.msgtype)))
    return out


def _stamp_ns(message: object) -> int:
    stamp = message.header.stamp  # type: ignore[attr-defined]
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def _wrenches(messages: list[tuple[int, object]]) -> np.ndarray:
    def row(m: object) -> list[float]:
        f, t = m.wrench.force, m.wrench.torque  # type: ignore[attr-defined]
        return [f.x, f.y, f.z, t.x, t.y, t.z]

    return np.array([row(m) for _, m in messages])


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """The paper's poses recorded on sim:// with ``--log``: the CSV, its MCAP, the calibration."""
    folder = tmp_path_factory.mktemp("recording")
    samples, log, cal = folder / "s.csv", folder / "s.mcap", folder / "cal.json"
    record = ["record", "--robot", SIM, "--sensor", "sim://", "--poses", "paper"]
    argv = [*record, "--samples-per-pose", "200", "--move-s", "1", "-o", str(samples)]
    assert main([*argv, "--log", str(log)]) == 0
    assert main(["calibrate", str(samples), "-o", str(cal), "--json"]) == 0
    return samples, log, cal


def test_import_bag_turns_a_recording_mcap_into_samples_that_calibrate_like_its_csv(
    tmp_path: Path, recording: tuple[Path, Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    samples, log, cal = recording
    messages = _messages(log)
    rows = len(_csv(samples)["fx"])
    assert len(messages["/ftcomp/wrench_raw"]) == len(messages["/tf"]) == rows
    assert [m.msg for _, m in messages["/ftcomp/events"]][-1] == "complete"  # type: ignore[attr-defined]
    imported, cal_bag = tmp_path / "b.csv", tmp_path / "b.json"
    argv = ["import-bag", str(log), "--wrench-topic", "/ftcomp/wrench_raw"]
    argv += ["--base-frame", "base", "--sensor-frame", "ft_sensor", "-o", str(imported)]
    assert main([*argv, "--still-min-s", "0.1", "--still-window-s", "0.05"]) == 0
    assert "kept 1800 of 1800 readings in 9 still segments" in capsys.readouterr().out
    assert main(["calibrate", str(imported), "-o", str(cal_bag), "--json"]) == 0
    a, b = json.loads(cal.read_text()), json.loads(cal_bag.read_text())
    for key in ("tool_weight_N", "center_of_gravity_m", "force_bias_N", "torque_bias_Nm"):
        # Exact algebra on the same readings: the MCAP's doubles are the CSV's readings.
        np.testing.assert_allclose(a[key], b[key], rtol=1e-9, atol=1e-12, err_msg=key)
    assert a["base_tilt_deg"] == pytest.approx(b["base_tilt_deg"], rel=1e-9, abs=1e-12)


def _live(folder: Path, argv: list[str]) -> tuple[dict[str, np.ndarray], dict[str, list]]:
    """Run a live command on sim:// with ``-o`` and ``--log``: its CSV and its messages."""
    out, log = folder / f"{argv[0]}.csv", folder / f"{argv[0]}.mcap"
    robot = ["--robot", SIM, "--sensor", "sim://"]
    assert main([argv[0], *robot, *argv[1:], "-o", str(out), "--log", str(log)]) == 0
    return _csv(out), _messages(log)


def test_run_log_has_every_channel_with_the_csv_rows_values_and_stamps(
    tmp_path: Path, recording: tuple[Path, Path, Path]
) -> None:
    cal = str(recording[2])
    argv = ["run", "-c", cal, "--control", "admittance", "--dry-run", "--seconds", "0.2"]
    csv, messages = _live(tmp_path, argv)
    rows = len(csv["t_s"])
    counts = {topic: len(m) for topic, m in messages.items() if topic != "/ftcomp/events"}
    assert counts == dict.fromkeys(
        [
            "/ftcomp/wrench_raw",
            "/ftcomp/wrench_compensated",
            "/tf",
            "/ftcomp/wrench_error",
            "/ftcomp/twist_command",
        ],
        rows,
    )
    columns = ["cfx", "cfy", "cfz", "ctx", "cty", "ctz"]
    contact = np.column_stack([csv[c] for c in columns])
    np.testing.assert_array_equal(_wrenches(messages["/ftcomp/wrench_compensated"]), contact)
    error = np.column_stack([csv[c] for c in ("ex", "ey", "ez", "etx", "ety", "etz")])
    np.testing.assert_array_equal(_wrenches(messages["/ftcomp/wrench_error"]), error)
    # The wrenches carry the sample's stamp, the log time is the cycle's: as in the CSV.
    log_ns = np.array([t for t, _ in messages["/ftcomp/wrench_compensated"]])
    stamps = np.array([_stamp_ns(m) for _, m in messages["/ftcomp/wrench_compensated"]])
    np.testing.assert_allclose((log_ns - log_ns[0]) * 1e-9, csv["t_s"], atol=1e-9)
    np.testing.assert_allclose((stamps - log_ns[0]) * 1e-9, csv["t_sample_s"], atol=2e-9)
    assert [m.msg for _, m in messages["/ftcomp/events"]] == ["duration"]  # type: ignore[attr-defined]


def test_stream_log_has_a_message_per_csv_row(
    tmp_path: Path, recording: tuple[Path, Path, Path]
) -> None:
    csv, messages = _live(tmp_path, ["stream", "-c", str(recording[2]), "--seconds", "0.1"])
    rows = len(csv["t"])
    assert {t: len(m) for t, m in messages.items()} == {
        "/ftcomp/wrench_raw": rows,
        "/ftcomp/wrench_compensated": rows,
        "/tf": rows,
        "/ftcomp/events": 1,
    }
    stamps = np.array([_stamp_ns(m) for _, m in messages["/ftcomp/wrench_raw"]])
    np.testing.assert_allclose(stamps * 1e-9, csv["t"], rtol=0, atol=1e-9)
    raw = np.column_stack([csv[c] for c in ("fx", "fy", "fz", "tx", "ty", "tz")])
    np.testing.assert_allclose(_wrenches(messages["/ftcomp/wrench_raw"]), raw, rtol=1e-9)


def test_a_log_that_exists_is_refused_before_anything_runs(
    tmp_path: Path, recording: tuple[Path, Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "run.mcap"
    log.write_text("keep me")
    argv = ["stream", "--robot", SIM, "--sensor", "sim://", "--seconds", "0.1"]
    assert main([*argv, "-o", str(tmp_path / "s.csv"), "--log", str(log)]) == 2
    assert "exists; pass --force" in capsys.readouterr().err
    assert log.read_text() == "keep me" and not (tmp_path / "s.csv").exists()


def test_a_command_that_fails_before_its_session_leaves_no_log(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "run.mcap"
    argv = ["stream", "--robot", "sim://", "--sensor", "netft://127.0.0.9?connect_timeout_s=0.2"]
    code = main([*argv, "--seconds", "0.1", "-o", str(tmp_path / "s.csv"), "--log", str(log)])
    assert code != 0 and capsys.readouterr().err.startswith("error: ")
    assert list(tmp_path.iterdir()) == []  # neither the log nor its temporary folder


class _Recorder:
    def __init__(self, fail_at: int | None = None) -> None:
        self.calls: list[tuple[str, object]] = []
        self.thread: set[str] = set()
        self.fail_at = fail_at

    def open(self, columns: Sequence[str]) -> None:
        self.calls.append(("open", tuple(columns)))

    def row(self, t_ns: int, row: Sequence[float]) -> None:
        self.thread.add(threading.current_thread().name)
        if self.fail_at is not None and t_ns == self.fail_at:
            raise OSError("disk full")
        self.calls.append(("row", t_ns))

    def event(self, t_ns: int, kind: str, text: str) -> None:
        self.calls.append(("event", kind))

    def close(self) -> None:
        self.calls.append(("close", None))


def test_observers_see_everything_in_order_on_their_own_thread() -> None:
    seen = _Recorder()
    before = sys.getswitchinterval()
    thread = ObserverThread([seen])
    assert sys.getswitchinterval() == pytest.approx(min(before, SWITCH_INTERVAL_S), rel=1e-6)
    thread.open(["t"])
    for k in range(100):
        thread.row(k, [k * 1e-9])
    thread.event(100, "end", "duration")
    thread.close()
    thread.close()  # idempotent
    assert seen.calls == [
        ("open", ("t",)),
        *(("row", k) for k in range(100)),
        ("event", "end"),
        ("close", None),
    ]
    assert seen.thread == {"ftcomp-observers"}
    assert sys.getswitchinterval() == before


def test_an_observer_error_is_raised_at_close_not_in_the_loop() -> None:
    failing = _Recorder(fail_at=3)
    thread = ObserverThread([failing])
    for k in range(10):
        thread.row(k, [0.0])  # never raises on the caller's thread
    with pytest.raises(OSError, match="disk full"):
        thread.close()
    assert ("close", None) in failing.calls
