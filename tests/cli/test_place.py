"""``ftcomp sim place`` called as a function: exit code, files, one-line errors."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from ftcomp.cli import main
from ftcomp.experiments.placement import COLUMNS


def test_place_writes_timeseries_metrics_and_plot(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        ["sim", "place", "--surface", "sponge", "--control", "position", "--out", str(tmp_path)]
    )
    assert code == 0
    assert "depth_reached" in capsys.readouterr().out
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    for key in (
        "placed",
        "final_force_N",
        "peak_press_N",
        "settle_time_s",
        "descent_mm",
        "max_velocity_mm_s",
        "stop_reason",
    ):
        assert key in metrics
    with (tmp_path / "timeseries.csv").open() as handle:
        rows = list(csv.reader(handle))
    assert tuple(rows[0]) == COLUMNS and len(rows) > 100
    assert (tmp_path / "placement.png").stat().st_size > 1000


def test_place_rejects_a_negative_gain_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        [
            "sim",
            "place",
            "--surface",
            "book",
            "--control",
            "admittance",
            "--k2",
            "-1",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --k2 must be >= 0") and err.count("\n") == 1
