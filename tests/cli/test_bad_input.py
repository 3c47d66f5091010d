"""Hostile sample files through ``ftcomp calibrate`` and ``ftcomp compensate``: one line
``error: ...``, exit 2, nothing written; or, for a corrupt reading that parses, a loud warning
naming the pose. Each case is bounded in time (a subprocess with a timeout where a hang was
the old behaviour)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from ftcomp.cli import main

from conftest import PAPER_CSV

CSV_FIELD_LIMIT = 131_072


def _error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: "), err[:300]
    return err


def _paper_with(tmp_path, old: str, new: str, name: str = "bad.csv"):
    path = tmp_path / name
    path.write_text(PAPER_CSV.read_text().replace(old, new, 1))
    return path


@pytest.mark.parametrize(
    ("make", "expected"),
    [
        (lambda p: "\n" + PAPER_CSV.read_text(), "header (line 1): blank; the header"),
        (
            lambda p: PAPER_CSV.read_text().replace("3.3445", "3" * (CSV_FIELD_LIMIT + 1)),
            "line 2: longer than 131072 bytes",
        ),
        (
            lambda p: ",".join(f"c{i}" for i in range(100_000)) + "\n1\n",
            "header (line 1): missing column 'fx'",
        ),
        (
            lambda p: ",".join(["fx"] * 100_000) + "\n1\n",
            "header (line 1): column 'fx' appears more than once",
        ),
        (
            lambda p: PAPER_CSV.read_text().replace("3.3445", "1e155"),
            "row 1 (line 2), column 'fz': 1e+155 N is beyond any plausible F/T reading",
        ),
        (
            lambda p: PAPER_CSV.read_text().replace("0.0255", "-1e150"),
            "row 1 (line 2), column 'tz': -1e+150 N*m is beyond any plausible F/T reading",
        ),
    ],
    ids=["blank-first-line", "long-cell", "wide-header", "wide-duplicates", "1e155", "1e150"],
)
def test_calibrate_answers_bad_files_with_one_line_and_exit_2(
    tmp_path, capsys, make, expected
) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text(make(tmp_path))
    out = tmp_path / "cal.json"
    assert main(["calibrate", str(bad), "-o", str(out)]) == 2
    assert expected in _error_line(capsys)
    assert not out.exists()


def test_calibrate_of_endless_input_stops_with_one_line() -> None:
    """``/dev/zero`` used to be read until memory ran out."""
    done = subprocess.run(
        [sys.executable, "-m", "ftcomp", "calibrate", "/dev/zero"],
        capture_output=True,
        text=True,
        timeout=60,  # interpreter start-up on a busy machine; the read itself is ~1 MiB
        check=False,
    )
    assert done.returncode == 2
    assert done.stderr.startswith("error: /dev/zero, header (line 1): longer than 1048576")
    assert done.stderr.count("\n") == 1


def test_compensate_refuses_an_absurd_reading_with_one_line(tmp_path, capsys) -> None:
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(PAPER_CSV), "-o", str(cal)]) == 0
    capsys.readouterr()
    bad = _paper_with(tmp_path, "-0.8723", "1e155")
    out = tmp_path / "out.csv"
    assert main(["compensate", str(bad), "-c", str(cal), "-o", str(out)]) == 2
    assert "row 2 (line 3), column 'fx': 1e+155 N is beyond any plausible" in _error_line(capsys)
    assert not out.exists()


def test_a_misplaced_decimal_point_gives_a_loud_warning_naming_the_pose(tmp_path, capsys) -> None:
    """``3.3445`` typed as ``33445``: G = 4703 N used to come out with exit 0 and no word."""
    bad = _paper_with(tmp_path, "3.3445", "33445")
    assert main(["calibrate", str(bad)]) == 0
    err = capsys.readouterr().err
    line = next(w for w in err.splitlines() if "OUTLIER" in w)
    assert line.startswith("warning: OUTLIER POSE(S) 1 (fz: ")
    assert "standard deviations" in line and "leave those poses out" in line


def test_rotation_vectors_in_degrees_warn(tmp_path, capsys) -> None:
    from scipy.spatial.transform import Rotation

    from ftcomp.io.samples_csv import read_samples

    samples = read_samples(PAPER_CSV)
    rotvec_deg = Rotation.from_matrix(samples.R_base_sensor).as_rotvec(degrees=True)
    rows = ["pose,rx,ry,rz,fx,fy,fz,tx,ty,tz"] + [
        ",".join([str(k + 1)] + [f"{v:.6f}" for v in (*r, *w)])
        for k, (r, w) in enumerate(zip(rotvec_deg, samples.wrench_sensor, strict=True))
    ]
    path = tmp_path / "deg.csv"
    path.write_text("\n".join(rows) + "\n")
    main(["calibrate", str(path)])
    err = capsys.readouterr().err
    assert "columns rx,ry,rz: a rotation vector longer than pi" in err
    assert "were they given in degrees?" in err


def test_pose_ids_in_messages_are_plain_text(tmp_path, capsys) -> None:
    bad = _paper_with(tmp_path, "\n2,", "\n1,")  # pose 2's row labelled 1: two orientations
    assert main(["calibrate", str(bad)]) == 2
    err = _error_line(capsys)
    assert "pose '1' has readings at orientations that differ" in err
    assert "np.str_" not in err
