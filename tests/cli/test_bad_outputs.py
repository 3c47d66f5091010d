"""Bad input that used to crash or leave files behind: an output on a pseudo-filesystem, an
oversized CSV field, a placement whose load is refused after its folder was made."""

from __future__ import annotations

from pathlib import Path

import pytest

from ftcomp.cli import main
from ftcomp.paper import paper_poses

from conftest import PAPER_CSV

needs_proc = pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs /proc")


def _one_error_line(capsys: pytest.CaptureFixture[str], *words: str) -> str:
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    for word in words:
        assert word in err, err
    return err


@needs_proc
@pytest.mark.parametrize(
    "args",
    [
        ["calibrate", str(PAPER_CSV), "-o", "/proc/ftcomp-x/calibration.json"],
        ["sim", "place", "--surface", "sponge", "--control", "admittance", "--out", "/proc/x"],
        ["demo", "--quick", "--out", "/proc/ftcomp-x"],
    ],
    ids=["calibrate", "sim-place", "demo"],
)
def test_an_output_under_proc_is_one_line_and_exit_2(
    args: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(args) == 2
    _one_error_line(capsys, "/proc/", "cannot be written")


@pytest.mark.parametrize("load", ["-1", "nan", "0"])
def test_a_refused_load_leaves_no_run_folder(
    load: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    args = ["sim", "place", "--surface", "sponge", "--control", "admittance", "--out", str(out)]
    assert main([*args, "--load-kg", load]) == 2
    _one_error_line(capsys, "--load-kg")  # the flag typed (the library's error names load_kg)
    assert not out.exists()


def test_a_pose_file_with_a_field_over_the_csv_limit_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    q = paper_poses().rotations.as_quat()
    poses = tmp_path / "poses.csv"
    rows = ["pose,qx,qy,qz,qw,note"]
    rows += [f"{k},{a},{b},{c},{d},ok" for k, (a, b, c, d) in enumerate(q, start=1)]
    rows[3] += "x" * (200 * 1024)  # one field of 200 KiB (csv's limit: 128 KiB)
    poses.write_text("\n".join(rows) + "\n")
    out = tmp_path / "samples.csv"
    assert main(["sim", "collect", "--poses", str(poses), "-o", str(out)]) == 2
    _one_error_line(capsys, str(poses))
    assert not out.exists()
