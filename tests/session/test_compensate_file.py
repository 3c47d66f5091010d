"""Compensating a whole sample file as a library call: result figures, block sizes, refusals."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pyarrow.csv as pcsv
import pyarrow.parquet as pq
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.calibration.identify import calibrate
from ftcomp.calibration_record import BiasDrift, Calibration
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.errors import InputFileError, ParameterError
from ftcomp.io.calibration_json import save_calibration
from ftcomp.io.samples_csv import read_samples
from ftcomp.session.compensate_file import (
    EXTRA_COLUMNS,
    CompensateConfig,
    CompensateResult,
    compensate_file,
)

from conftest import synthetic_samples

HEADER = "t,qx,qy,qz,qw,fx,fy,fz,tx,ty,tz"


@pytest.fixture
def calibration(rng: np.random.Generator) -> Calibration:
    return calibrate(synthetic_samples(rng))


def write_recording(path: Path, rng: np.random.Generator, n: int, t0_s: float = 0.0) -> None:
    """``n`` rows at random orientations, time stamps from ``t0_s`` every millisecond."""
    q = Rotation.random(n, rng=rng).as_quat()
    w = rng.normal(size=(n, 6)) + np.array([0, 0, 3, 0, 0, 0])
    rows = [
        f"{t0_s + i / 1000:.3f},{','.join(f'{v:.9f}' for v in q[i])},"
        + ",".join(f"{v:.6f}" for v in w[i])
        for i in range(n)
    ]
    path.write_text(HEADER + "\n" + "\n".join(rows) + "\n")


def test_the_result_gives_the_rows_and_the_means_of_what_was_written(
    tmp_path: Path, rng: np.random.Generator, calibration: Calibration
) -> None:
    src, out = tmp_path / "rec.csv", tmp_path / "out.csv"
    write_recording(src, rng, 400)
    result = compensate_file(src, out, calibration)
    samples = read_samples(src)
    contact = GravityCompensator(calibration).compensate(
        samples.wrench_sensor, samples.R_base_sensor
    )
    weight = np.linalg.norm(contact[:, :3], axis=1)
    assert isinstance(result, CompensateResult)
    assert result.output == out and result.rows == 400 and result.duration_s >= 0.0
    assert result.load_weight_mean_N == pytest.approx(weight.mean(), rel=1e-12)
    assert result.load_weight_max_N == pytest.approx(weight.max(), rel=1e-12)
    np.testing.assert_allclose(
        result.contact_wrench_mean_sensor, contact.mean(axis=0), rtol=1e-9, atol=1e-12
    )
    assert result.t_range_s is None and result.warnings == ()
    assert out.read_text().splitlines()[0] == HEADER + "," + ",".join(EXTRA_COLUMNS)


def test_small_blocks_and_a_calibration_file_give_the_same_output_as_one_block(
    tmp_path: Path, rng: np.random.Generator, calibration: Calibration
) -> None:
    src, cal = tmp_path / "rec.csv", tmp_path / "cal.json"
    write_recording(src, rng, 300)
    save_calibration(cal, calibration)
    whole = compensate_file(src, tmp_path / "whole.csv", calibration)
    blocks = compensate_file(
        src, tmp_path / "blocks.csv", cal, CompensateConfig(csv_chunk_bytes=700)
    )
    assert (tmp_path / "blocks.csv").read_bytes() == (tmp_path / "whole.csv").read_bytes()
    assert blocks.rows == whole.rows == 300


def test_parquet_blocks_of_a_few_rows_cover_the_whole_file(
    tmp_path: Path, rng: np.random.Generator, calibration: Calibration
) -> None:
    src = tmp_path / "rec.csv"
    write_recording(src, rng, 100)
    pq.write_table(pcsv.read_csv(src), tmp_path / "rec.parquet", row_group_size=30)
    config = CompensateConfig(parquet_batch_rows=7)
    result = compensate_file(tmp_path / "rec.parquet", tmp_path / "out.csv", calibration, config)
    whole = compensate_file(src, tmp_path / "whole.csv", calibration)
    assert result.rows == 100
    assert result.load_weight_mean_N == pytest.approx(whole.load_weight_mean_N, rel=1e-12)


def test_the_output_never_replaces_an_input_nor_an_existing_file_without_overwrite(
    tmp_path: Path, rng: np.random.Generator, calibration: Calibration
) -> None:
    src, cal, out = tmp_path / "rec.csv", tmp_path / "cal.json", tmp_path / "out.csv"
    write_recording(src, rng, 20)
    save_calibration(cal, calibration)
    with pytest.raises(ParameterError, match="would replace the input samples"):
        compensate_file(src, src, calibration, CompensateConfig(overwrite=True))
    with pytest.raises(ParameterError, match="is also an input"):
        compensate_file(src, cal, cal, CompensateConfig(overwrite=True))
    out.write_text("precious")
    with pytest.raises(ParameterError, match="exists; pass overwrite=True"):
        compensate_file(src, out, calibration)
    assert out.read_text() == "precious"
    assert compensate_file(src, out, calibration, CompensateConfig(overwrite=True)).rows == 20


def test_a_bias_drift_needs_time_stamps_and_is_reported_when_held_beyond_its_range(
    tmp_path: Path, rng: np.random.Generator, calibration: Calibration
) -> None:
    drift = BiasDrift(1, 0.0, 0.0, 1.0, np.full((1, 6), 1e-3), np.full((1, 6), 1e-4))
    drifting = dataclasses.replace(calibration, bias_drift=drift)
    src = tmp_path / "rec.csv"
    write_recording(src, rng, 50, t0_s=0.98)  # 0.98 .. 1.029 s: past the fitted 0 .. 1 s
    result = compensate_file(src, tmp_path / "out.csv", drifting)
    assert result.t_range_s == pytest.approx((0.98, 1.029))
    assert len(result.warnings) == 1 and "not extrapolated" in result.warnings[0]
    untimed = tmp_path / "untimed.csv"
    untimed.write_text("qx,qy,qz,qw,fx,fy,fz,tx,ty,tz\n0,0,0,1,0,0,3,0,0,0\n")
    with pytest.raises(ParameterError, match=r"linear bias drift.*no 't'"):
        compensate_file(untimed, tmp_path / "out2.csv", drifting)
    assert not (tmp_path / "out2.csv").exists()


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("force_range_N", 0.0),
        ("torque_range_Nm", -6.0),
        ("csv_chunk_bytes", 0),
        ("parquet_batch_rows", 2.5),
    ],
)
def test_the_config_refuses_a_bad_value_naming_it(field: str, value: float) -> None:
    with pytest.raises(ParameterError, match=field):
        CompensateConfig(**{field: value})  # type: ignore[arg-type]


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_compensate_reports_its_progress_up_to_the_whole_input(
    suffix: str, tmp_path: Path, rng: np.random.Generator, calibration: Calibration
) -> None:
    src, out = tmp_path / "rec.csv", tmp_path / f"out{suffix}"
    write_recording(src, rng, 3000)
    if suffix == ".parquet":  # a Parquet input: progress in rows
        pq.write_table(pcsv.read_csv(src), tmp_path / "rec.parquet")
        src = tmp_path / "rec.parquet"
    config = CompensateConfig(csv_chunk_bytes=16384, parquet_batch_rows=500)
    calls: list[tuple[int, int]] = []
    compensate_file(src, out, calibration, config, lambda d, t: calls.append((d, t)))
    done = [d for d, _ in calls]
    assert len(calls) > 3 and done == sorted(done)
    whole = 3000 if suffix == ".parquet" else src.stat().st_size
    assert {t for _, t in calls} == {whole} and done[-1] == whole


def test_the_accelerometer_columns_give_each_row_its_tools_acceleration(
    tmp_path: Path, rng: np.random.Generator, calibration: Calibration
) -> None:
    src, out = tmp_path / "rec.csv", tmp_path / "out.csv"
    write_recording(src, rng, 300)
    accel = rng.normal(0.0, 3.0, (300, 3)) + np.array([0.0, 0.0, -9.8])
    lines = src.read_text().splitlines()
    rows = [
        f"{line},{a[0]:.6f},{a[1]:.6f},{a[2]:.6f}" for line, a in zip(lines[1:], accel, strict=True)
    ]
    header = lines[0] + ",accel_x_m_s2,accel_y_m_s2,accel_z_m_s2"
    src.write_text("\n".join([header, *rows]) + "\n")
    compensate_file(src, out, calibration, CompensateConfig(accelerometer=True, overwrite=True))
    samples = read_samples(src)
    expected = GravityCompensator(calibration).compensate(
        samples.wrench_sensor, samples.R_base_sensor, specific_force_mps2=np.round(accel, 6)
    )
    written = pcsv.read_csv(out)
    got = np.column_stack([written.column(c).to_numpy() for c in EXTRA_COLUMNS[:6]])
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)
    # Each refusal names the file, and the row and column of a bad cell.
    src.write_text("\n".join([header, *rows[:5], rows[5].rsplit(",", 1)[0] + ",x"]) + "\n")
    with pytest.raises(InputFileError, match=r"row 6, column 'accel_z_m_s2': 'x' is not a finite"):
        compensate_file(src, out, calibration, CompensateConfig(accelerometer=True, overwrite=True))
    write_recording(src, rng, 10)
    with pytest.raises(ParameterError, match=r"rec.csv: accelerometer: .* no 'accel_x_m_s2'"):
        compensate_file(src, out, calibration, CompensateConfig(accelerometer=True, overwrite=True))
