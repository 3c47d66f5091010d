"""Hostile sample files: over-long cells, lines and headers, endless input, absurd numbers,
a blank first line, rotation vectors in degrees. Each gives one clear error (or a warning)
within a bounded time, never a traceback, a hang or a wrong answer."""

from __future__ import annotations

import contextlib
import io
import signal
from collections.abc import Iterator

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.constants import PLAUSIBLE_FORCE_N, PLAUSIBLE_TORQUE_NM
from ftcomp.errors import InputFileError
from ftcomp.io.chunks import MAX_HEADER_BYTES, MAX_LINE_BYTES, iter_line_chunks
from ftcomp.io.samples_csv import read_samples

from conftest import PAPER_CSV

HEADER = "pose,alpha_deg,beta_deg,gamma_deg,fx,fy,fz,tx,ty,tz"
ROW = "1,90,0,-180,-0.8584,1.0668,3.3445,-0.0009,-0.0614,0.0255"
CSV_FIELD_LIMIT = 131_072  # csv.field_size_limit() by default


@contextlib.contextmanager
def deadline(seconds: float) -> Iterator[None]:
    """Fail (instead of hanging) when the block takes longer than ``seconds``."""

    def expire(signum: int, frame: object) -> None:
        raise TimeoutError(f"took longer than {seconds} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def write(tmp_path, text: str, name: str = "s.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_cell_beyond_the_csv_field_limit_is_an_error_naming_the_line(tmp_path) -> None:
    long = "1" * (CSV_FIELD_LIMIT + 10)
    path = write(tmp_path, f"{HEADER}\n{ROW}\n{ROW.replace('-0.8584', long)}\n")
    with deadline(10), pytest.raises(InputFileError, match=r"s\.csv, line 3: longer than"):
        read_samples(path)


def test_a_long_cell_in_an_extra_column_is_an_error_when_read_not_when_its_row_is_used(
    tmp_path,
) -> None:
    long = "a" * (CSV_FIELD_LIMIT + 10)
    path = write(tmp_path, f"{HEADER},note\n{ROW},short\n{ROW},{long}\n")
    with pytest.raises(InputFileError, match=r"line 3: longer than"):
        read_samples(path)


def test_a_quoted_cell_spanning_lines_beyond_the_field_limit_is_one_error(tmp_path) -> None:
    cell = '"' + ("a" * 999 + "\n") * (CSV_FIELD_LIMIT // 1000 + 5) + '"'
    path = write(tmp_path, f"{HEADER},note\n{ROW},x\n{ROW},{cell}\n")
    with (
        deadline(10),
        pytest.raises(InputFileError, match=r"row 2 \(line \d+\): not a CSV row \(field larger"),
    ):
        read_samples(path)


def test_a_header_of_100000_columns_answers_quickly(tmp_path) -> None:
    wide = ",".join(f"c{i}" for i in range(100_000))
    with deadline(10), pytest.raises(InputFileError, match="missing column 'fx'"):
        read_samples(write(tmp_path, wide + "\n1\n"))
    duplicated = ",".join(["x"] * 100_000)
    with deadline(10), pytest.raises(InputFileError, match="column 'x' appears more than once"):
        read_samples(write(tmp_path, duplicated + "\n1\n"))


def test_endless_input_without_a_line_end_is_bounded(tmp_path) -> None:
    with deadline(10), pytest.raises(InputFileError, match=r"header \(line 1\): longer than"):
        read_samples("/dev/zero")
    endless_row = write(tmp_path, HEADER + "\n" + "0" * (3 * MAX_LINE_BYTES))
    with deadline(10), pytest.raises(InputFileError, match=r"line 2: longer than 131072 bytes"):
        read_samples(endless_row)


def test_a_header_at_the_limit_is_read_and_one_beyond_is_not(tmp_path) -> None:
    pad = ",x" * ((MAX_HEADER_BYTES - len(HEADER)) // 2 - 1)
    ok = write(tmp_path, HEADER + pad + "\n")
    with pytest.raises(InputFileError, match="appears more than once"):  # read, then checked
        read_samples(ok)
    too_long = write(tmp_path, HEADER + ",y" * (MAX_HEADER_BYTES // 2) + "\n")
    with pytest.raises(InputFileError, match=r"header \(line 1\): longer than 1048576 bytes"):
        read_samples(too_long)


def test_line_chunks_stop_at_the_first_line_longer_than_the_limit() -> None:
    data = b"ok\n" * 10 + b"z" * 100 + b"\nok\n"
    chunks = iter_line_chunks(io.BytesIO(data), "mem", chunk_bytes=16, max_line_bytes=50)
    with pytest.raises(InputFileError, match="mem, line 11: longer than 50 bytes"):
        list(chunks)
    assert len(list(iter_line_chunks(io.BytesIO(data), "mem", max_line_bytes=100))) == 1


@pytest.mark.parametrize(
    ("column", "value", "unit"),
    [("fy", "1e155", "N"), ("fx", "-2e6", "N"), ("tz", "1e300", "N*m")],
)
def test_readings_beyond_any_plausible_sensor_are_errors_naming_row_and_column(
    tmp_path, column, value, unit
) -> None:
    cells = dict(zip(HEADER.split(","), ROW.split(","), strict=True))
    cells[column] = value
    path = write(tmp_path, f"{HEADER}\n{ROW}\n{','.join(cells.values())}\n")
    limit = PLAUSIBLE_FORCE_N if unit == "N" else PLAUSIBLE_TORQUE_NM
    with pytest.raises(InputFileError) as info:
        read_samples(path)
    message = str(info.value)
    assert f"row 2 (line 3), column '{column}': {float(value):g} {unit}" in message
    assert f"beyond any plausible F/T reading +-{limit:g} {unit}" in message


def test_readings_at_the_plausible_bound_are_accepted(tmp_path) -> None:
    row = ROW.replace("-0.8584", "-1e6").replace("0.0255", "1e5")
    assert read_samples(write(tmp_path, f"{HEADER}\n{row}\n")).wrench_sensor[0, 0] == -1e6


def test_a_given_sensor_range_still_names_the_sensor_range(tmp_path) -> None:
    path = write(tmp_path, f"{HEADER}\n{ROW.replace('3.3445', '1e155')}\n")
    with pytest.raises(InputFileError, match=r"1e\+155 N is beyond the sensor range \+-250 N"):
        read_samples(path, force_range_N=250.0, torque_range_Nm=6.0)


@pytest.mark.parametrize(
    ("header", "row", "column"),
    [
        ("qx,qy,qz,qw", "1e200,0,0,1", "qx"),
        ("rx,ry,rz", "0,1e300,0", "ry"),
        ("alpha_deg,beta_deg,gamma_deg", "0,0,1e308", "gamma_deg"),
    ],
)
def test_absurd_orientation_values_are_errors_not_nan_rotations(
    tmp_path, header, row, column
) -> None:
    path = write(tmp_path, f"{header},fx,fy,fz,tx,ty,tz\n{row},1,2,3,0,0,0\n")
    with pytest.raises(InputFileError, match=rf"column '{column}': .* beyond any orientation"):
        read_samples(path)


def test_parquet_files_get_the_same_plausibility_bound(tmp_path) -> None:
    path = tmp_path / "s.parquet"
    names = HEADER.split(",")
    columns = {n: [float(v)] for n, v in zip(names[1:], ROW.split(",")[1:], strict=True)}
    columns["fz"] = [1e155]
    pq.write_table(pa.table(columns), path)
    with pytest.raises(InputFileError, match=r"row 1, column 'fz': 1e\+155 N is beyond any"):
        read_samples(path)


def test_a_blank_first_line_is_reported_as_such_not_as_a_missing_column(tmp_path) -> None:
    path = write(tmp_path, "\n" + PAPER_CSV.read_text())
    with pytest.raises(InputFileError) as info:
        read_samples(path)
    message = str(info.value)
    assert "header (line 1): blank; the header" in message and "must be the first line" in message
    assert "missing column" not in message
    with pytest.raises(InputFileError, match="empty file"):
        read_samples(write(tmp_path, "\n\n  \n", "empty.csv"))


def test_rotation_vectors_in_degrees_warn_naming_the_columns(tmp_path) -> None:
    samples = read_samples(PAPER_CSV)
    rotvec_deg = Rotation.from_matrix(samples.R_base_sensor).as_rotvec(degrees=True)
    lines = ["rx,ry,rz,fx,fy,fz,tx,ty,tz"]
    for r, w in zip(rotvec_deg, samples.wrench_sensor, strict=True):
        lines.append(",".join(f"{v:.6f}" for v in (*r, *w)))
    degrees = read_samples(write(tmp_path, "\n".join(lines) + "\n"))
    assert any(
        "columns rx,ry,rz: a rotation vector longer than pi" in w and "degrees?" in w
        for w in degrees.warnings
    )
    radians = Rotation.from_matrix(samples.R_base_sensor).as_rotvec()
    lines[1:] = [
        ",".join(f"{v:.9f}" for v in (*r, *w))
        for r, w in zip(radians, samples.wrench_sensor, strict=True)
    ]
    # Pose 1 is a half turn: a norm of pi (to rounding) is radians, and no warning.
    assert read_samples(write(tmp_path, "\n".join(lines) + "\n", "rad.csv")).warnings == ()
