"""MCAP logs of live sessions: a session's rows through SessionMcapLog, read back with rosbags."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from scipy.spatial.transform import Rotation

from ftcomp.calibration.identify import calibrate
from ftcomp.cli import main
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.control.loop import Reading
from ftcomp.errors import ParameterError
from ftcomp.hardware.bota import DRIVER_CHANNELS
from ftcomp.io.calibration_json import save_calibration
from ftcomp.model import GravityModel
from ftcomp.ros2.mcap_log import SESSION_TOPICS, TOPICS, McapLog, SessionMcapLog
from ftcomp.session.compliant import CycleRecord
from ftcomp.session.run import RUN_COLUMNS, cycle_row
from ftcomp.session.stream import stream_columns

from conftest import synthetic_samples


def _read(path: Path) -> dict[str, list[tuple[int, object]]]:
    out: dict[str, list[tuple[int, object]]] = {}
    with AnyReader([path]) as reader:
        for conn in reader.connections:
            assert SESSION_TOPICS[conn.topic] == conn.msgtype
        for conn, t, raw in reader.messages():
            out.setdefault(conn.topic, []).append((t, reader.deserialize(raw, conn.msgtype)))
    return out


def _vec(v) -> list[float]:
    return [v.x, v.y, v.z]


def test_every_cycle_is_logged_with_its_values_and_stamps(tmp_path: Path, rng) -> None:
    path = tmp_path / "run.mcap"
    readings = []
    with SessionMcapLog(path, base_frame="base_link", sensor_frame="ft") as log:
        log.open(RUN_COLUMNS)
        for k in range(5):
            raw = rng.normal(size=6)
            contact = raw - 1.0 if k != 3 else np.full(6, np.nan)  # a fault stays visible
            R = Rotation.random(rng=rng).as_matrix()
            reading = Reading(
                1000 * k + 7, 10**9 + 1000 * k, raw, contact, rng.normal(size=3), R, R
            )
            twist = rng.normal(size=6)
            error = rng.normal(size=6)
            state: Any = None  # the row does not carry the controller's state
            record = CycleRecord(reading, state, error, None, twist, True, False)
            log.row(reading.now_ns, cycle_row(record, 0))
            readings.append((reading, twist))
    assert path.is_file() and [p.name for p in tmp_path.iterdir()] == ["run.mcap"]
    logged = _read(path)
    counts = {topic: len(msgs) for topic, msgs in logged.items()}
    assert counts == dict.fromkeys([*TOPICS, "/ftcomp/wrench_error"], 5)
    for k, (reading, twist) in enumerate(readings):
        t_raw, raw = logged["/ftcomp/wrench_raw"][k]
        assert t_raw == reading.now_ns
        assert raw.header.frame_id == "ft"
        # The sample's stamp from the row's seconds: to the nanosecond near 1 s.
        stamp = raw.header.stamp.sec * 10**9 + raw.header.stamp.nanosec
        assert abs(stamp - reading.t_sample_ns) <= 1
        assert (
            _vec(raw.wrench.force) + _vec(raw.wrench.torque) == reading.wrench_raw_sensor.tolist()
        )
        comp = logged["/ftcomp/wrench_compensated"][k][1].wrench
        np.testing.assert_array_equal(
            _vec(comp.force) + _vec(comp.torque), reading.wrench_contact_sensor
        )
        tf = logged["/tf"][k][1].transforms[0]
        assert (tf.header.frame_id, tf.child_frame_id) == ("base_link", "ft")
        q = tf.transform.rotation
        R = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()
        np.testing.assert_allclose(R, reading.R_base_sensor, atol=1e-12)
        tw = logged["/ftcomp/twist_command"][k][1].twist
        assert _vec(tw.linear) + _vec(tw.angular) == twist.tolist()
    assert "/ftcomp/events" not in logged  # a channel opened, no event written


def test_an_existing_log_is_kept(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    path.write_text("earlier run")
    with pytest.raises(ParameterError, match=r"run\.mcap: exists"):
        McapLog(path)
    assert path.read_text() == "earlier run"


def test_sim_place_log_reads_back_with_every_topic_and_message_count(
    tmp_path: Path, identified_tool: GravityModel, rng, capsys: pytest.CaptureFixture[str]
) -> None:
    cal = tmp_path / "cal.json"
    calibration = calibrate(synthetic_samples(rng, identified_tool, readings=200))
    save_calibration(cal, calibration)
    identified = calibration.model
    out, log = tmp_path / "run", tmp_path / "run.mcap"
    place = ["sim", "place", "--surface", "book", "--control", "admittance", "-c", str(cal)]
    assert main([*place, "--out", str(out), "--log", str(log)]) == 0
    printed = capsys.readouterr().out
    logged = _read(log)
    counts = {topic: len(msgs) for topic, msgs in logged.items()}
    cycles = counts["/ftcomp/wrench_raw"]
    every_cycle = dict.fromkeys([*TOPICS, "/ftcomp/wrench_error"], cycles)
    assert counts == {**every_cycle, "/ftcomp/events": 1}  # and how it ended
    assert f"wrote {log} ({5 * cycles + 1} messages)" in printed
    with (out / "timeseries.csv").open() as handle:
        rows = sum(1 for _ in csv.DictReader(handle))
    assert cycles == rows  # one per controlled cycle, the last (whose step ends the loop) too
    # The compensated wrench is the raw one less the calibration's bias and tool gravity at
    # the logged pose.
    compensator = GravityCompensator(identified)
    for k in range(0, cycles, 97):
        raw = logged["/ftcomp/wrench_raw"][k][1].wrench
        comp = logged["/ftcomp/wrench_compensated"][k][1].wrench
        q = logged["/tf"][k][1].transforms[0].transform.rotation
        R = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()
        expected = compensator.compensate(_vec(raw.force) + _vec(raw.torque), R)
        np.testing.assert_allclose(_vec(comp.force) + _vec(comp.torque), expected, atol=1e-9)


def test_a_sensors_extra_channels_are_temperature_and_imu_messages_of_each_row(
    tmp_path: Path,
) -> None:
    columns = stream_columns(with_pose=False, compensated=False, extras=DRIVER_CHANNELS)
    rng = np.random.default_rng(36)
    rows = [[k * 1e-3, *rng.normal(size=6), 30.0 + k, *rng.normal(size=6)] for k in range(5)]
    with SessionMcapLog(tmp_path / "s.mcap") as log:
        log.open(columns)
        for row in rows:
            log.row(round(row[0] * 1e9), row)
    messages = _read(tmp_path / "s.mcap")
    assert set(messages) == {
        "/ftcomp/wrench_raw",
        "/ftcomp/temperature",
        "/ftcomp/imu",
    }
    temperatures = [m.temperature for _, m in messages["/ftcomp/temperature"]]  # type: ignore[attr-defined]
    assert temperatures == [row[7] for row in rows]
    for (t_ns, imu), row in zip(messages["/ftcomp/imu"], rows, strict=True):
        a, w = imu.linear_acceleration, imu.angular_velocity  # type: ignore[attr-defined]
        assert [a.x, a.y, a.z, w.x, w.y, w.z] == row[8:]
        assert imu.orientation_covariance[0] == -1.0  # type: ignore[attr-defined]
        assert imu.header.frame_id == "ft_sensor" and t_ns == round(row[0] * 1e9)  # type: ignore[attr-defined]
