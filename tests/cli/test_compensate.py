"""``ftcomp compensate`` streaming: block by block, CSV or Parquet, output only when complete."""

from __future__ import annotations

import json

import numpy as np
import pyarrow as pa
import pyarrow.csv as pcsv
import pyarrow.parquet as pq
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.cli import main
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.io import samples_csv
from ftcomp.io.calibration_json import load_calibration

from conftest import PAPER_CSV

EXTRA = ["fx_ext", "fy_ext", "fz_ext", "tx_ext", "ty_ext", "tz_ext", "load_weight_N"]
HEADER = "t,qx,qy,qz,qw,fx,fy,fz,tx,ty,tz"


@pytest.fixture
def calibration(tmp_path):
    path = tmp_path / "cal.json"
    assert main(["calibrate", str(PAPER_CSV), "--method", "paper", "-o", str(path), "--json"]) == 0
    return path


@pytest.fixture
def small_chunks(monkeypatch):
    """Chunks of a few rows, so a test file of a few hundred rows streams in many blocks."""
    monkeypatch.setattr(samples_csv, "DEFAULT_CHUNK_BYTES", 700)
    from ftcomp.io import parquet

    monkeypatch.setattr(parquet, "BATCH_ROWS", 13)


def recording(rng, n: int) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Lines of a recording, with its wrenches (n, 6) and orientations (n, 3, 3)."""
    R = Rotation.random(n, rng=rng)
    w = rng.normal(size=(n, 6)) + np.array([0, 0, 3, 0, 0, 0])
    q = R.as_quat()
    lines = [
        f"{i / 1000:.3f},{','.join(f'{v:.9f}' for v in q[i])},{','.join(f'{v:.6f}' for v in w[i])}"
        for i in range(n)
    ]
    values = np.array([[float(c) for c in line.split(",")] for line in lines])
    return lines, values[:, 5:], Rotation.from_quat(values[:, 1:5]).as_matrix()


def expected_extra(calibration, w, R) -> np.ndarray:
    contact = GravityCompensator(load_calibration(calibration)).compensate(w, R)
    return np.column_stack([contact, np.linalg.norm(contact[:, :3], axis=1)])


def test_each_input_line_comes_out_as_it_was_with_the_contact_wrench_appended(
    tmp_path, rng, calibration, small_chunks, capsys
) -> None:
    lines, w, R = recording(rng, 500)
    src, out = tmp_path / "rec.csv", tmp_path / "out.csv"
    src.write_text(HEADER + "\n" + "\n".join(lines) + "\n")
    assert main(["compensate", str(src), "-c", str(calibration), "-o", str(out)]) == 0
    assert "500 rows compensated" in capsys.readouterr().out
    got = out.read_text().splitlines()
    assert got[0] == HEADER + "," + ",".join(EXTRA)
    assert [g[: len(line)] for g, line in zip(got[1:], lines, strict=True)] == lines
    values = np.array([[float(c) for c in g.split(",")[11:]] for g in got[1:]])
    # Written with ten significant digits: relative 5e-10 (and 1e-12 N for values near zero).
    np.testing.assert_allclose(values, expected_extra(calibration, w, R), rtol=6e-10, atol=1e-12)


def test_crlf_and_blank_lines_are_normalised_like_the_reader_does(
    tmp_path, rng, calibration, small_chunks
) -> None:
    lines, _, _ = recording(rng, 40)
    src, out = tmp_path / "rec.csv", tmp_path / "out.csv"
    src.write_bytes(("\r\n".join([HEADER, *lines[:20], "", *lines[20:]]) + "\r\n\r\n").encode())
    assert main(["compensate", str(src), "-c", str(calibration), "-o", str(out)]) == 0
    got = out.read_bytes().decode().split("\n")
    assert len(got) == 42 and got[-1] == "" and "\r" not in out.read_text()
    assert [g.split(",")[:11] for g in got[1:-1]] == [line.split(",") for line in lines]


def test_one_bad_cell_deep_inside_is_one_line_exit_2_and_no_output(
    tmp_path, rng, calibration, small_chunks, capsys
) -> None:
    lines, _, _ = recording(rng, 400)
    cells = lines[345].split(",")
    cells[7] = "3_3445"
    lines[345] = ",".join(cells)
    src, out = tmp_path / "rec.csv", tmp_path / "out.csv"
    src.write_text(HEADER + "\n" + "\n".join(lines) + "\n")
    before = sorted(p.name for p in tmp_path.iterdir())
    assert main(["compensate", str(src), "-c", str(calibration), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err == f"error: {src}, row 346 (line 347), column 'fz': '3_3445' is not a number\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # no output, no temporary


def test_a_failed_run_leaves_an_earlier_output_untouched(tmp_path, rng, calibration, capsys):
    lines, _, _ = recording(rng, 30)
    src, out = tmp_path / "rec.csv", tmp_path / "out.csv"
    src.write_text(HEADER + "\n" + "\n".join([*lines, "1,2,3"]) + "\n")
    out.write_text("precious")
    assert main(["compensate", str(src), "-c", str(calibration), "-o", str(out)]) == 2
    assert "exists; pass --force" in capsys.readouterr().err
    assert main(["compensate", str(src), "-c", str(calibration), "-o", str(out), "--force"]) == 2
    assert "row 31 (line 32): 3 cells but the header has 11 columns" in capsys.readouterr().err
    assert out.read_text() == "precious"


@pytest.mark.parametrize(
    ("src_ext", "out_ext"), [(".csv", ".parquet"), (".parquet", ".csv"), (".parquet", ".parquet")]
)
def test_parquet_in_and_out_by_extension(
    tmp_path, rng, calibration, small_chunks, src_ext, out_ext
) -> None:
    lines, w, R = recording(rng, 300)
    csv_path = tmp_path / "rec.csv"
    csv_path.write_text(
        HEADER + ",note\n" + "\n".join(f"{line},n{i}" for i, line in enumerate(lines)) + "\n"
    )
    src = csv_path
    if src_ext == ".parquet":
        src = tmp_path / "rec.parquet"
        pq.write_table(pcsv.read_csv(csv_path), src, row_group_size=50)
    out = tmp_path / f"out{out_ext}"
    assert main(["compensate", str(src), "-c", str(calibration), "-o", str(out)]) == 0
    table = pq.read_table(out) if out_ext == ".parquet" else pcsv.read_csv(out)
    assert table.column_names == [*HEADER.split(","), "note", *EXTRA]
    assert table.column("note").to_pylist() == [f"n{i}" for i in range(300)]
    extra = np.column_stack([table.column(c).to_numpy() for c in EXTRA])
    tolerance = 1e-15 if out_ext == ".parquet" else 6e-10  # float64 columns, or ten digits
    np.testing.assert_allclose(extra, expected_extra(calibration, w, R), rtol=tolerance, atol=1e-12)
    if out_ext == ".parquet":
        assert table.schema.field("fx").type == pa.float64()


def test_json_summary_covers_every_block(tmp_path, rng, calibration, small_chunks, capsys):
    lines, w, R = recording(rng, 250)
    src, out = tmp_path / "rec.csv", tmp_path / "out.csv"
    src.write_text(HEADER + "\n" + "\n".join(lines) + "\n")
    assert main(["compensate", str(src), "-c", str(calibration), "-o", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    extra = expected_extra(calibration, w, R)
    assert summary["rows"] == 250
    assert summary["load_weight_N"]["max"] == pytest.approx(extra[:, 6].max(), rel=1e-12)
    assert summary["load_weight_N"]["mean"] == pytest.approx(extra[:, 6].mean(), rel=1e-12)
    np.testing.assert_allclose(
        summary["contact_wrench_mean"], extra[:, :6].mean(axis=0), rtol=1e-9, atol=1e-12
    )


def test_no_rows_or_a_clashing_column_are_errors_without_output(tmp_path, calibration, capsys):
    out = tmp_path / "out.csv"
    src = tmp_path / "empty.csv"
    src.write_text(HEADER + "\n\n")
    assert main(["compensate", str(src), "-c", str(calibration), "-o", str(out)]) == 2
    assert "empty.csv: a header but no data rows" in capsys.readouterr().err
    src = tmp_path / "done.csv"
    src.write_text(HEADER + ",fz_ext\n0,0,0,0,1,0,0,0,0,0,0,0\n")
    assert main(["compensate", str(src), "-c", str(calibration), "-o", str(out)]) == 2
    assert "already has column 'fz_ext'" in capsys.readouterr().err
    assert not out.exists()


def test_warnings_of_the_whole_file_are_printed(tmp_path, calibration, small_chunks, capsys):
    rows = [f"{i},0.{i % 9},0.1,-3.1,0,0,3,0,0,0" for i in range(100)]
    src, out = tmp_path / "rad.csv", tmp_path / "out.csv"
    src.write_text("pose,alpha_deg,beta_deg,gamma_deg,fx,fy,fz,tx,ty,tz\n" + "\n".join(rows))
    assert main(["compensate", str(src), "-c", str(calibration), "-o", str(out)]) == 0
    assert "were the angles given in radians?" in capsys.readouterr().err
    assert len(out.read_text().splitlines()) == 101
