"""The sample CSV: round trips in every encoding, and a clear error for every bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.errors import InputFileError
from ftcomp.frames import ENCODING_COLUMNS
from ftcomp.io.samples_csv import read_samples, write_samples

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
