"""``ftcomp poses design --robot URI``: the robot's own reachability check
(:class:`~ftcomp.hardware.protocols.ChecksReachability`), the robot opened as a context manager."""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pytest

import ftcomp.sim.cell_config
from ftcomp.cli import main
from ftcomp.io.poses_csv import read_pose_file
from ftcomp.sim import SimCell


def _error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: "), err[:300]
    return err


class _TrackedCell(SimCell):
    """The simulated cell, noting when it is entered and left."""

    events: ClassVar[list[str]] = []

    def __enter__(self) -> _TrackedCell:
        self.events.append("enter")
        return self

    def __exit__(self, *exc: Any) -> None:
        self.events.append("exit")
        super().__exit__(*exc)


def test_a_robot_design_lists_poses_the_robot_reaches_at_the_stated_position(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(ftcomp.sim.cell_config, "SimCell", _TrackedCell)
    monkeypatch.setattr(_TrackedCell, "events", [])
    out = tmp_path / "poses.csv"
    argv = ["poses", "design", "--count", "6", "--robot", "sim://", "-o", str(out)]
    assert main([*argv, "--position-mm", "450", "0", "420"]) == 0
    assert _TrackedCell.events == ["enter", "exit"]  # opened with `with`, closed once
    printed = capsys.readouterr().out
    assert "reachability: sim://, tip at [0.45, 0.0, 0.42] m:" in printed
    poses = read_pose_file(out)
    assert len(poses) == 6 and poses.positions_base_m is not None
    np.testing.assert_array_equal(poses.positions_base_m, np.tile([0.45, 0.0, 0.42], (6, 1)))
    cell = SimCell()
    for p, R in zip(poses.positions_base_m, poses.rotations.as_matrix(), strict=True):
        assert cell.is_reachable(p, R)


def test_without_a_position_the_design_is_checked_where_the_tcp_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "poses.csv"
    argv = ["poses", "design", "--count", "3", "--max-tilt-deg", "40", "--robot", "sim://"]
    assert main([*argv, "-o", str(out)]) == 0
    here = SimCell().pose().p_base_tcp
    poses = read_pose_file(out)
    assert poses.positions_base_m is not None
    np.testing.assert_allclose(poses.positions_base_m, np.tile(here, (3, 1)), atol=1e-6)
    assert f"tip at {np.round(here, 4).tolist()} m" in capsys.readouterr().out


def test_a_robot_that_cannot_check_reachability_is_one_line_naming_it_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "poses.csv"
    uri = "fixed://?rpy_deg=0,180,0"
    assert main(["poses", "design", "--count", "3", "--robot", uri, "-o", str(out)]) == 2
    line = _error_line(capsys)
    assert f"--robot {uri}: this robot cannot check whether it reaches a pose" in line
    assert not out.exists()


def test_position_needs_a_robot_or_a_urdf(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["poses", "design", "--count", "3", "-o", str(tmp_path / "o.csv")]
    assert main([*argv, "--position-mm", "450", "0", "420"]) == 2
    assert "--position-mm needs --urdf or --robot" in _error_line(capsys)
