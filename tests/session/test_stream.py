"""``stream``: a sensor logged live as a library call, on the simulated cell."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import ftcomp
from ftcomp.errors import ParameterError
from ftcomp.session.stream import StreamConfig, StreamProgress, stream, stream_columns


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


def test_stream_configurations_are_checked() -> None:
    with pytest.raises(ParameterError, match="duration_s must be > 0"):
        StreamConfig(0.0)
    with pytest.raises(ParameterError, match="online_rate_hz needs online_load"):
        StreamConfig(1.0, online_rate_hz=500.0)
