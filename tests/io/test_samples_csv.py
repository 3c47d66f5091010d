"""The sample CSV: round trips in every encoding, and a clear error for every bad input."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.csv as pcsv
import pyarrow.parquet as pq
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.errors import InputFileError
from ftcomp.frames import ENCODING_COLUMNS
from ftcomp.io import samples_csv
from ftcomp.io.sample_format import SampleLayout, check_header
from ftcomp.io.samples_csv import SampleCsvReader, parse_rows, read_samples, write_samples

GOOD_HEADER = "pose,alpha_deg,beta_deg,gamma_deg,fx,fy,fz,tx,ty,tz"
GOOD_ROWS = [
    "1,90,0,-180,-0.8584,1.0668,3.3445,-0.0009,-0.0614,0.0255",
    "2,64.447,-0.721,-160.420,-0.8723,2.1192,3.1743,-0.0492,-0.0606,0.0256",
    "3,86.602,-13.491,-165.720,-1.5834,1.8812,3.1736,-0.0378,-0.0946,0.0253",
]


def write(tmp_path, text: str, name: str = "s.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize("encoding", tuple(ENCODING_COLUMNS))
def test_samples_round_trip_in_every_encoding(tmp_path, rng, encoding) -> None:
    rotations = Rotation.random(12, rng=rng)
    wrench = rng.normal(size=(12, 6))
    path = tmp_path / "out.csv"
    write_samples(
        path, wrench, rotations, encoding=encoding, pose=np.arange(12) // 4, t=np.arange(12) * 0.01
    )
    back = read_samples(path)
    assert back.encoding == encoding
    np.testing.assert_allclose(back.wrench_sensor, wrench, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(back.R_base_sensor, rotations.as_matrix(), atol=1e-9)
    assert list(back.pose) == [str(i // 4) for i in range(12)]
    np.testing.assert_allclose(back.t, np.arange(12) * 0.01)


def test_other_columns_are_kept_and_ignored(tmp_path) -> None:
    rows = [r + ",note" for r in GOOD_ROWS]
    samples = read_samples(write(tmp_path, GOOD_HEADER + ",comment\n" + "\n".join(rows) + "\n"))
    assert samples.header[-1] == "comment"
    assert samples.rows[0][-1] == "note"


BAD_INPUTS = [
    ("", r"s.csv: empty file"),
    (GOOD_HEADER + "\n", r"s.csv: a header but no data rows"),
    (
        GOOD_HEADER.replace(",", ";") + "\n1;2\n",
        r"s.csv, header \(line 1\): one column .*delimiter must be ','",
    ),
    (
        GOOD_HEADER.replace("fz", "fzz") + "\n" + "\n".join(GOOD_ROWS),
        r"missing column 'fz' \(did you mean 'fzz'\?\)",
    ),
    (
        # 't' is the time column: never offered for 'tz'; the wrench's columns are named.
        "pose,t,alpha_deg,beta_deg,gamma_deg,fx,fy,fz,tx,ty\n1,0,0,0,0,0,0,0,0,0\n",
        r"missing column 'tz': the wrench is the six columns fx,fy,fz,tx,ty,tz \[N, N\*m\] in "
        r"the sensor frame \(found fx,fy,fz,tx,ty\)$",
    ),
    (
        GOOD_HEADER.replace("fy", "Fy") + "\n" + "\n".join(GOOD_ROWS),
        r"missing column 'fy' \(found 'Fy': column names are case-sensitive\)",
    ),
    (
        "pose,fx,fy,fz,tx,ty,tz\n1,0,0,0,0,0,0\n",
        r"no orientation columns; give one of qx,qy,qz,qw \| rx,ry,rz",
    ),
    (
        "pose,alpha,beta,gamma,fx,fy,fz,tx,ty,tz\n1,0,0,0,0,0,0,0,0,0\n",
        r"no orientation columns.*did you mean 'alpha'",
    ),
    (
        GOOD_HEADER + ",rx,ry,rz\n" + GOOD_ROWS[0] + ",0,0,0\n",
        r"two orientation encodings at once, rotvec .* and paper_euler",
    ),
    (
        "qx,qy,qz,fx,fy,fz,tx,ty,tz\n0,0,0,0,0,0,0,0,0\n",
        r"missing column 'qw' of the quaternion orientation",
    ),
    (
        GOOD_HEADER + "\n" + GOOD_ROWS[0] + "\n2,1,2,3,abc,0,0,0,0,0\n",
        r"s.csv, row 2 \(line 3\), column 'fx': 'abc' is not a number",
    ),
    (
        GOOD_HEADER + "\n" + GOOD_ROWS[0].replace("3.3445", "nan") + "\n",
        r"row 1 \(line 2\), column 'fz': nan is not finite",
    ),
    (
        GOOD_HEADER + "\n" + GOOD_ROWS[0].replace("-0.0614", "inf") + "\n",
        r"row 1 \(line 2\), column 'ty': inf is not finite",
    ),
    (
        GOOD_HEADER + "\n" + GOOD_ROWS[0] + ",7\n",
        r"row 1 \(line 2\): 11 cells but the header has 10 columns",
    ),
    (
        "pose,qx,qy,qz,qw,fx,fy,fz,tx,ty,tz\n1,0,0,0,1,0,0,0,0,0,0\n2,0,0,0,0,0,0,0,0,0,0\n",
        r"row 2, columns qx,qy,qz,qw: zero-norm quaternion",
    ),
    (GOOD_HEADER + "\n,90,0,-180,0,0,0,0,0,0\n", r"row 1 \(line 2\), column 'pose': empty pose id"),
    ("fx,fx,fy,fz,tx,ty,tz,rx,ry,rz\n", r"column 'fx' appears more than once"),
]


@pytest.mark.parametrize(("text", "message"), BAD_INPUTS)
def test_bad_input_is_one_clear_error(tmp_path, text, message) -> None:
    with pytest.raises(InputFileError, match=message):
        read_samples(write(tmp_path, text))


def test_missing_file_is_named(tmp_path) -> None:
    with pytest.raises(InputFileError, match=r"nothere.csv: no such file"):
        read_samples(tmp_path / "nothere.csv")


def test_readings_beyond_the_sensor_range_are_errors(tmp_path) -> None:
    text = GOOD_HEADER + "\n" + GOOD_ROWS[0].replace("3.3445", "300") + "\n"
    with pytest.raises(
        InputFileError,
        match=r"row 1 \(line 2\), column 'fz': 300 N is beyond the sensor range \+-250 N",
    ):
        read_samples(write(tmp_path, text), force_range_N=250, torque_range_Nm=6)
    text = GOOD_HEADER + "\n" + GOOD_ROWS[0].replace("0.0255", "-6.5") + "\n"
    with pytest.raises(
        InputFileError, match=r"column 'tz': -6.5 N\*m is beyond the sensor range \+-6 N\*m"
    ):
        read_samples(write(tmp_path, text), force_range_N=250, torque_range_Nm=6)


def test_paper_angles_that_look_like_radians_give_a_warning(tmp_path) -> None:
    text = GOOD_HEADER + "\n1,1.57,0,-3.14,0,0,0,0,0,0\n2,1.1,0.1,-2.8,0,0,0,0,0,0\n"
    samples = read_samples(write(tmp_path, text))
    assert any("radians" in w for w in samples.warnings)
    assert not read_samples(
        write(tmp_path, GOOD_HEADER + "\n" + "\n".join(GOOD_ROWS), "ok.csv")
    ).warnings


def test_non_unit_quaternions_are_normalised_with_a_warning(tmp_path) -> None:
    samples = read_samples(write(tmp_path, "qx,qy,qz,qw,fx,fy,fz,tx,ty,tz\n0,0,0,2,0,0,0,0,0,0\n"))
    np.testing.assert_allclose(samples.R_base_sensor[0], np.eye(3))
    assert any("not of unit norm" in w for w in samples.warnings)


# --- Streaming, strict numbers, chunk boundaries, Parquet (issue 11) ---------------------------


def _rows_text(rng, n: int) -> list[str]:
    q = Rotation.random(n, rng=rng).as_quat()
    w = rng.normal(size=(n, 6))
    return [
        f"{i // 7},{i * 0.001:.3f},{','.join(f'{v:.8f}' for v in q[i])},"
        f"{','.join(f'{v:.6f}' for v in w[i])}"
        for i in range(n)
    ]


QUAT_HEADER = "pose,t,qx,qy,qz,qw,fx,fy,fz,tx,ty,tz"


def _replace_cell(row: str, column: int, cell: str) -> str:
    cells = row.split(",")
    cells[column] = cell
    return ",".join(cells)


def _layout(path) -> SampleLayout:
    return check_header(QUAT_HEADER.split(","), str(path), where="x")


@pytest.mark.parametrize(
    "cell",
    ["3_3445", "1_0", "١٢", "٣", "0x10", "1d5", "1.5f", "--1", "1.2.3", "e5", "1e", "", "N/A"],
)
def test_a_cell_python_would_misread_is_not_a_number(tmp_path, cell) -> None:
    """float('3_3445') is 33445 and float('١٢') is 12: a sample file's numbers are decimal."""
    text = GOOD_HEADER + "\n" + GOOD_ROWS[0] + "\n" + GOOD_ROWS[1].replace("3.1743", cell) + "\n"
    with pytest.raises(InputFileError, match=r"row 2 \(line 3\), column 'fz': .* is not a number"):
        read_samples(write(tmp_path, text))


@pytest.mark.parametrize(
    ("cell", "value"), [(" 3.5 ", 3.5), ("+3.5", 3.5), (".5", 0.5), ("5.", 5.0), ("1E-3", 1e-3)]
)
def test_decimal_numbers_in_every_usual_spelling_are_read(tmp_path, cell, value) -> None:
    text = GOOD_HEADER + "\n" + GOOD_ROWS[0].replace("3.3445", cell) + "\n"
    assert read_samples(write(tmp_path, text)).wrench_sensor[0, 2] == value


@pytest.mark.parametrize("cell", ["Infinity", "-inf", "NaN", "1e400"])
def test_non_finite_spellings_are_not_finite(tmp_path, cell) -> None:
    text = GOOD_HEADER + "\n" + GOOD_ROWS[0].replace("3.3445", cell) + "\n"
    with pytest.raises(InputFileError, match=r"column 'fz': .* is not finite"):
        read_samples(write(tmp_path, text))


def test_chunked_reading_gives_the_cell_by_cell_result(tmp_path, rng) -> None:
    """Many small chunks (blank lines, CRLF and quoted cells among them) read exactly what the
    reference parser reads from the whole text at once."""
    rows = _rows_text(rng, 400)
    rows[50] = ""  # blank lines, skipped
    rows[51] = "   "
    rows[200] = rows[200] + ""
    lines = [
        QUAT_HEADER + ",note",
        *(r + (',"a, b"' if i % 9 else ",x") if r.strip() else r for i, r in enumerate(rows)),
    ]
    path = tmp_path / "s.csv"
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode())
    layout = check_header([*QUAT_HEADER.split(","), "note"], str(path), where="x")
    reference = parse_rows("\n".join(lines[1:]) + "\n", layout, first_row=1, first_line=2)
    with SampleCsvReader(path, chunk_bytes=512) as reader:
        blocks = list(reader.blocks())
    assert len(blocks) > 20
    values = np.concatenate([np.column_stack([b.wrench_sensor, b.t]) for b in blocks])
    np.testing.assert_array_equal(values, reference.values[:, [0, 1, 2, 3, 4, 5, 10]])
    assert list(np.concatenate([b.pose for b in blocks])) == reference.pose
    samples = read_samples(path)
    assert len(samples) == 398 and samples.rows[397] == tuple(reference.cells[397])
    assert samples.rows[0][-1] == "x" and samples.rows[1][-1] == "a, b"


@pytest.mark.parametrize("chunk_bytes", [256, 4096, 1 << 20])
def test_a_bad_cell_deep_inside_is_named_by_row_line_and_column(tmp_path, rng, chunk_bytes) -> None:
    rows = _rows_text(rng, 3000)
    rows[10] = ""  # a blank line before it shifts the line number, not the row number
    rows[2345] = _replace_cell(rows[2345], 1, "3_3445")
    path = write(tmp_path, QUAT_HEADER + "\n" + "\n".join(rows) + "\n")
    with (
        pytest.raises(
            InputFileError,
            match=r"s.csv, row 2345 \(line 2347\), column 't': '3_3445' is not a number",
        ),
        SampleCsvReader(path, chunk_bytes=chunk_bytes) as reader,
    ):
        for _ in reader.blocks():
            pass


def test_a_quoted_cell_spanning_lines_across_a_chunk_boundary_is_one_row(tmp_path, rng) -> None:
    rows = [r + f',"line one\nline two {i}"' for i, r in enumerate(_rows_text(rng, 60))]
    path = write(tmp_path, QUAT_HEADER + ",note\n" + "\n".join(rows) + "\n")
    samples = read_samples(path)
    assert len(samples) == 60
    assert samples.rows[59][-1] == "line one\nline two 59"
    with SampleCsvReader(path, chunk_bytes=300) as reader:
        assert sum(len(b) for b in reader.blocks()) == 60


def test_rows_are_read_again_from_the_file_and_a_changed_file_is_refused(tmp_path, rng) -> None:
    path = write(tmp_path, QUAT_HEADER + "\n" + "\n".join(_rows_text(rng, 50)) + "\n")
    assert read_samples(path).rows[-1][0] == "7" and len(read_samples(path).rows[10:20]) == 10
    samples = read_samples(path)
    assert len(samples.rows) == 50
    path.write_text(path.read_text() + "\n")
    with pytest.raises(InputFileError, match="changed since it was read"):
        samples.rows[3]


def test_a_bom_old_mac_line_ends_and_trailing_blank_lines_are_read(tmp_path) -> None:
    text = "\ufeff" + GOOD_HEADER + "\r" + "\r".join(GOOD_ROWS) + "\r\r\r"
    samples = read_samples(write(tmp_path, text))
    assert len(samples) == 3 and samples.header[0] == "pose"


def test_rows_of_blank_cells_are_skipped_as_before(tmp_path) -> None:
    text = GOOD_HEADER + "\n" + GOOD_ROWS[0] + "\n,,,,,,,,,\n \n" + GOOD_ROWS[1] + "\n"
    samples = read_samples(write(tmp_path, text))
    assert len(samples) == 2 and list(samples.pose) == ["1", "2"]


def test_a_bad_cell_in_the_fast_path_reports_the_first_in_row_order(tmp_path, rng) -> None:
    rows = _rows_text(rng, 100)
    rows[40] = _replace_cell(rows[40], 6, "nan")
    rows[60] = _replace_cell(rows[60], 1, "x")
    path = write(tmp_path, QUAT_HEADER + "\n" + "\n".join(rows) + "\n")
    with pytest.raises(InputFileError, match=r"row 41 \(line 42\), column 'fx': nan is not finite"):
        read_samples(path)


def _parquet(tmp_path, columns: dict, name: str = "s.parquet"):
    path = tmp_path / name
    pq.write_table(pa.table(columns), path)
    return path


def test_parquet_samples_read_like_the_same_csv(tmp_path, rng) -> None:
    csv_path = write(tmp_path, QUAT_HEADER + "\n" + "\n".join(_rows_text(rng, 300)) + "\n")
    from_csv = read_samples(csv_path)
    table = pcsv.read_csv(
        csv_path, convert_options=pcsv.ConvertOptions(column_types={"pose": pa.string()})
    )
    path = tmp_path / "s.parquet"
    pq.write_table(table, path, row_group_size=64)
    from_parquet = read_samples(path)
    np.testing.assert_array_equal(from_parquet.wrench_sensor, from_csv.wrench_sensor)
    np.testing.assert_allclose(from_parquet.R_base_sensor, from_csv.R_base_sensor, atol=1e-15)
    assert list(from_parquet.pose) == list(from_csv.pose)
    assert from_parquet.header == from_csv.header


def test_parquet_problems_name_row_and_column(tmp_path) -> None:
    good = {c: [0.0, 0.0, 1.0] for c in ("fx", "fy", "fz", "tx", "ty", "tz", "rx", "ry", "rz")}
    path = _parquet(tmp_path, {**good, "fz": [0.0, None, 1.0]})
    with pytest.raises(InputFileError, match=r"s.parquet, row 2, column 'fz': empty \(null\) cell"):
        read_samples(path)
    path = _parquet(tmp_path, {**good, "ty": [0.0, 1.0, float("inf")]}, "b.parquet")
    with pytest.raises(InputFileError, match=r"b.parquet, row 3, column 'ty': inf is not finite"):
        read_samples(path)
    path = _parquet(tmp_path, {**good, "fx": ["1", "2", "3"]}, "c.parquet")
    with pytest.raises(
        InputFileError, match=r"c.parquet, column 'fx': type string is not a number"
    ):
        read_samples(path)
    path = _parquet(tmp_path, {k: v for k, v in good.items() if k != "tz"}, "d.parquet")
    with pytest.raises(InputFileError, match=r"d.parquet, columns: missing column 'tz'"):
        read_samples(path)
    (tmp_path / "e.parquet").write_text("not parquet")
    with pytest.raises(InputFileError, match=r"e.parquet: not a readable Parquet file"):
        read_samples(tmp_path / "e.parquet")
    path = _parquet(tmp_path, {**good, "fx": [0.0, 300.0, 0.0]}, "f.parquet")
    with pytest.raises(InputFileError, match=r"f.parquet, row 2, column 'fx': 300 N is beyond"):
        read_samples(path, force_range_N=250)


def test_the_strict_number_rule_and_the_fast_parser_agree_on_every_spelling(tmp_path) -> None:
    """The block parser may never accept a cell the cell-by-cell rule rejects (or read it
    differently): each spelling, alone in a file, gives the same value or the same error."""
    spellings = [
        "1",
        "-2.5",
        " 3 ",
        "+4",
        ".5",
        "6.",
        "7e1",
        "8E-1",
        "9e+0",
        "0x1",
        "1_0",
        "inf",
        "nan",
        "1e999",
        "",
        "a",
        "1,5",
        "١",
        "\t2",
    ]
    layout = check_header(GOOD_HEADER.split(","), "x", where="x")
    for cell in spellings:
        row = GOOD_ROWS[0].replace("3.3445", f'"{cell}"' if "," in cell else cell)
        try:
            expected = parse_rows(row + "\n", layout, first_row=1, first_line=2).values[0, 2]
        except InputFileError as exc:
            with pytest.raises(InputFileError, match=str(exc).split(": ", 1)[1][:12]):
                read_samples(write(tmp_path, GOOD_HEADER + "\n" + row + "\n"))
        else:
            assert (
                read_samples(write(tmp_path, GOOD_HEADER + "\n" + row + "\n")).wrench_sensor[0, 2]
                == expected
            )
    assert samples_csv.DEFAULT_CHUNK_BYTES > 1 << 20


def test_a_failing_chunk_is_narrowed_down_and_rows_after_a_skipped_one_keep_their_numbers(
    tmp_path, rng
) -> None:
    """A row of blank cells (skipped) makes the block parser fail; the halving finds it, and a
    bad cell later on is still named by the right row and line."""
    rows = _rows_text(rng, 2000)
    rows[1500] = ",,,,,,,,,,,"
    good = write(tmp_path, QUAT_HEADER + "\n" + "\n".join(rows) + "\n", "good.csv")
    samples = read_samples(good)
    assert len(samples) == 1999
    np.testing.assert_allclose(samples.t[1500], 1.501)
    rows[1800] = _replace_cell(rows[1800], 8, "1,5")
    bad = write(tmp_path, QUAT_HEADER + "\n" + "\n".join(rows) + "\n", "bad.csv")
    with pytest.raises(InputFileError, match=r"row 1800 \(line 1802\): 13 cells but the header"):
        read_samples(bad)


def test_time_stamps_keep_their_microseconds_on_a_unix_clock(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # Ten significant digits of 1.7e9 s would round every stamp to the second.
    t = 1_763_790_000.0 + np.array([0.0, 0.001, 0.002001])
    path = tmp_path / "s.csv"
    samples_csv.write_samples(
        path, np.zeros((3, 6)), Rotation.identity(3), encoding="quaternion", t=t
    )
    back = samples_csv.read_samples(path).t
    assert back is not None
    np.testing.assert_allclose(np.diff(back), np.diff(t), rtol=0, atol=1e-6)  # float64 at 1.7e9
