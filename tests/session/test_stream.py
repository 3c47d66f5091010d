"""``stream``: a sensor logged live as a library call, on the simulated cell."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import ftcomp
from channelled_sensor import CHANNELS, ChannelledSensor
from ftcomp.compensation.bias_tracking import BiasTrackingConfig
from ftcomp.compensation.pipeline import Compensated
from ftcomp.control.loop import Reading
from ftcomp.errors import ParameterError
from ftcomp.session.stream import (
    StreamConfig,
    StreamLogger,
    StreamProgress,
    stream,
    stream_columns,
)


def test_a_stream_logs_every_reading_compensated_with_its_pose(tmp_path: Path) -> None:
    progress: list[StreamProgress] = []
    with ftcomp.open_robot("sim://?seed=4") as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        tool = robot.true_gravity_model()  # type: ignore[attr-defined]
        config = StreamConfig(0.5, progress_period_s=1e-6)
        result = stream(
            robot, sensor, config, tmp_path / "s.csv", calibration=tool, on_progress=progress.append
        )
    assert result.outcome == "duration" and not result.faulted
    header = (tmp_path / "s.csv").read_text().splitlines()[0].split(",")
    assert tuple(header) == stream_columns(with_pose=True, compensated=True)
    rows = np.loadtxt(tmp_path / "s.csv", delimiter=",", skiprows=1, ndmin=2)
    assert len(rows) == result.readings
    # The sensor's rate, not the loop's (1.2 kHz simulated sensor, 1 kHz loop), over 0.5 s.
    assert 1.1e3 < result.rate_hz < 1.3e3
    # Nothing but the tool acts on it: the contact wrench is noise about zero.
    contact = rows[:, header.index("cfx") : header.index("cfz") + 1]
    assert np.all(np.abs(contact.mean(axis=0)) < 0.05)
    assert progress and progress[-1].readings <= result.readings
    assert all(p.duration_s == 0.5 and p.lost_packets is None for p in progress)


def test_a_stream_logs_each_readings_extra_channels_last(tmp_path: Path) -> None:
    with ftcomp.open_robot("sim://?seed=4") as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        tool = robot.true_gravity_model()  # type: ignore[attr-defined]
        config = StreamConfig(0.2)
        result = stream(
            robot, ChannelledSensor(sensor), config, tmp_path / "s.csv", calibration=tool
        )
    assert result.outcome == "duration"
    header = (tmp_path / "s.csv").read_text().splitlines()[0].split(",")
    assert tuple(header) == stream_columns(with_pose=True, compensated=True, extras=CHANNELS)
    assert header[-2:] == ["temperature_C", "accel_x_m_s2"]
    rows = np.loadtxt(tmp_path / "s.csv", delimiter=",", skiprows=1, ndmin=2)
    assert len(rows) == result.readings > 100
    # every row the channels of its own reading (they carry its fx, fy: 10 digits both)
    np.testing.assert_array_equal(rows[:, -2:], rows[:, 1:3])


def _reading(now_ns: int, stamps: range = range(0)) -> Reading:
    zero = np.zeros(6)
    new = tuple(
        Compensated(k * 1_000_000, np.full(6, float(k)), zero, np.eye(3), np.zeros(3))
        for k in stamps
    )
    return Reading(now_ns, now_ns, zero, zero, np.zeros(3), np.eye(3), np.eye(3), new)


def test_a_late_last_cycle_still_logs_the_readings_stamped_before_the_end() -> None:
    # A loop held up under load reaches the end 20 ms late: the readings of the 100 ms it
    # streamed are all logged (and none after it), not those up to the previous cycle alone.
    rows = list[list[float]]()
    logger = StreamLogger(rows.append, 0.1, with_pose=False)
    ms = 1_000_000
    assert logger(_reading(0)) is not None  # the first cycle: readings from now on
    assert logger(_reading(50 * ms, range(1, 50))) is not None
    assert logger(_reading(120 * ms, range(50, 121))) is None  # over: the stream ends
    assert [round(row[0] * 1e3) for row in rows] == list(range(1, 100))
    assert logger.count == 99


def test_stream_configurations_are_checked() -> None:
    with pytest.raises(ParameterError, match="duration_s must be > 0"):
        StreamConfig(0.0)
    with pytest.raises(ParameterError, match="online_rate_hz needs online_load"):
        StreamConfig(1.0, online_rate_hz=500.0)


def test_a_tracked_bias_follows_a_drifting_sensor_while_still_and_free(tmp_path: Path) -> None:
    """The simulated sensor's force bias drifts by a known rate; the arm stands still with
    nothing touching: the tracked bias follows it (within the tracker's lag and the noise),
    where the calibration's alone is off by the whole drift."""
    rate_N_per_s = np.array([0.02, -0.01, 0.03])
    per_min = ",".join(f"{r * 60:g}" for r in rate_N_per_s)
    seconds = 8.0
    with (
        ftcomp.open_robot(f"sim://?seed=5&drift_N_per_min={per_min}") as robot,
        ftcomp.open_sensor("sim://", robot) as sensor,
    ):
        tool = robot.true_gravity_model()  # type: ignore[attr-defined]
        config = StreamConfig(seconds, track_bias=BiasTrackingConfig())
        result = stream(robot, sensor, config, tmp_path / "s.csv", calibration=tool)
    assert result.outcome == "duration" and result.bias_correction is not None
    header = (tmp_path / "s.csv").read_text().splitlines()[0].split(",")
    assert header == list(stream_columns(with_pose=True, compensated=True, tracked=True))
    rows = np.loadtxt(tmp_path / "s.csv", delimiter=",", skiprows=1, ndmin=2)
    updated = rows[:, header.index("bias_updated")]
    assert result.bias_updates == int(updated.sum()) > 0.5 * len(rows)
    t = rows[:, 0] - rows[0, 0]
    last = t > t[-1] - 1.0
    contact = rows[last, header.index("cfx") : header.index("cfz") + 1].mean(axis=0)
    drift_end = rate_N_per_s * t[-1]  # what the calibration's bias alone would leave
    assert np.all(np.abs(drift_end) > 0.07)
    # The tracker lags a ramp by rate * ~0.4 s (its Kalman gain) and waits 0.5 s still first.
    np.testing.assert_allclose(contact, 0.0, atol=0.03)
    np.testing.assert_allclose(result.bias_correction[:3], drift_end, atol=0.04)


def test_tracking_the_bias_needs_a_calibration_and_excludes_the_online_load() -> None:
    with pytest.raises(ParameterError, match="track_bias and online_load: choose one"):
        StreamConfig(1.0, online_load=True, track_bias=BiasTrackingConfig())
