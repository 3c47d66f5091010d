"""Usage errors are one line and exit 2, for every command; negative seeds are refused."""

from __future__ import annotations

from pathlib import Path

import pytest

from ftcomp.cli import main


@pytest.mark.parametrize(
    "argv",
    [
        ["calibrate"],
        ["bogus"],
        ["sim", "place", "--surface", "sand", "--control", "admittance", "--out", "x"],
        ["compensate", "a.csv"],
        ["sim", "collect", "--samples-per-pose", "many", "-o", "s.csv", "--truth", "t.json"],
    ],
)
def test_usage_errors_are_one_line(argv: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ftcomp") and err.count("\n") == 1


@pytest.mark.parametrize(
    "argv",
    [
        ["sim", "place", "--surface", "book", "--control", "admittance", "--seed", "-1"],
        ["demo", "--quick", "--seed", "-3"],
        ["sim", "collect", "--seed", "-1", "--truth", "t.json"],
        ["sim", "collect", "--samples-per-pose", "1000000000", "--truth", "t.json"],
    ],
)
def test_negative_seeds_and_absurd_counts_are_refused_before_any_file_is_written(
    tmp_path: Path, argv: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    where = ["-o", str(out)] if argv[:2] == ["sim", "collect"] else ["--out", str(out)]
    assert main([*argv, *where]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1
    assert not out.exists()
