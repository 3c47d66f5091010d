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


def test_a_reader_that_goes_away_ends_the_command_quietly(tmp_path: Path) -> None:
    # `ftcomp poses design ... | head -1`: the pipe breaks while the errors are printed. (The
    # commands that print tables through rich get rich's own handling: the same, exit code 1.)
    import subprocess
    import sys

    argv = [sys.executable, "-c", "import sys; from ftcomp.cli import main; sys.exit(main())"]
    out = tmp_path / "poses.csv"
    proc = subprocess.Popen(
        [*argv, "poses", "design", "--count", "6", "-o", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # the reader is gone before the first line
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141
    assert "Traceback" not in err and "BrokenPipe" not in err, err
    assert out.exists()  # the file was written before the printing
