"""Property-based: whatever a sample CSV or a calibration file holds, the readers either read it
or raise the package's error (an ``FtcompError``), never another exception, and never hang
(small inputs, a per-example deadline). A sample file that reads is also calibrated: the
identification too raises only ``FtcompError``."""

from __future__ import annotations

import json
import math
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from ftcomp.calibration.identify import calibrate
from ftcomp.errors import FtcompError
from ftcomp.io.calibration_json import load_calibration
from ftcomp.io.samples_csv import SampleCsvReader, read_samples

from conftest import PAPER_CSV

FUZZ = settings(
    max_examples=120,
    deadline=3000,  # ms per example: generous for a busy machine, far from a hang
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

WRENCH = ["fx", "fy", "fz", "tx", "ty", "tz"]
ORIENTATIONS = [
    ["qx", "qy", "qz", "qw"],
    ["rx", "ry", "rz"],
    ["alpha_deg", "beta_deg", "gamma_deg"],
]
JUNK_NAMES = ["pose", "t", "note", "", "FX", "fx ", "q x", '"fx"', "a;b", "\t"]

floats_any = st.floats(allow_nan=True, allow_infinity=True, width=64)
number_text = st.one_of(
    st.floats(-10.0, 10.0).map(lambda v: f"{v:.6g}"),
    floats_any.map(repr),
    floats_any.map(lambda v: f"{v:.3e}"),
    st.sampled_from(["nan", "-inf", "Infinity", "1e155", "1e400", "3_3445", "0x10", "1,5", ""]),
)
cell = st.one_of(
    number_text,
    number_text,
    st.text(max_size=12),
    st.sampled_from(['"', '""', '"a\nb"', "\x00", "\r", " ", "١٢", "1e6", "-1e5"]),
    st.integers(1, 3000).map(lambda n: "9" * n),  # long cells (the slow path's limits)
)


@st.composite
def header(draw: st.DrawFn) -> list[str]:
    names = list(WRENCH) + list(draw(st.sampled_from(ORIENTATIONS)))
    if draw(st.booleans()):
        names += draw(st.lists(st.sampled_from([*JUNK_NAMES, "pose", "t"]), max_size=3))
    if draw(st.integers(0, 3)) == 0:
        names = [n for n in names if draw(st.integers(0, 9)) > 0]  # drop a few
    if draw(st.integers(0, 3)) == 0:
        names += draw(st.lists(st.sampled_from([*WRENCH, "qx", "rx"]), max_size=2))  # dups
    return draw(st.permutations(names))


@st.composite
def sample_text(draw: st.DrawFn) -> str:
    names = draw(header())
    junk = draw(st.sampled_from([0.0, 0.02, 0.2, 1.0]))  # share of cells that may be anything
    clean = st.floats(-10.0, 10.0).map(lambda v: f"{v:.6g}")
    rows = []
    for _ in range(draw(st.integers(0, 12))):
        width = len(names) + (draw(st.sampled_from([0, -1, 1, -len(names)])) if junk else 0)
        cells = [
            draw(cell if draw(st.floats(0.0, 1.0)) < junk else clean) for _ in range(max(width, 0))
        ]
        rows.append(",".join(cells))
    end = draw(st.sampled_from(["\n", "\r\n", "\r", "\n\n"]))
    lead = draw(st.sampled_from(["", "", "\ufeff", "\n", " "]))
    return lead + end.join([",".join(names), *rows]) + draw(st.sampled_from(["", end]))


@st.composite
def corrupted_paper(draw: st.DrawFn) -> bytes:
    """The paper's file with a few bytes changed, inserted or deleted."""
    data = bytearray(PAPER_CSV.read_bytes())
    for _ in range(draw(st.integers(1, 4))):
        at = draw(st.integers(0, len(data)))
        action = draw(st.sampled_from(["set", "insert", "delete"]))
        byte = draw(st.integers(0, 255))
        if action == "insert" or at == len(data):
            data[at:at] = bytes([byte])
        elif action == "set":
            data[at] = byte
        else:
            del data[at]
    return bytes(data)


def _read_and_calibrate(data: bytes, chunk_bytes: int) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "fuzz.csv"
        path.write_bytes(data)
        try:
            with SampleCsvReader(path, chunk_bytes=chunk_bytes) as reader:
                for block in reader.blocks():
                    assert np.isfinite(block.wrench_sensor).all()
                    assert np.isfinite(block.R_base_sensor).all()
            samples = read_samples(path)
            _ = list(samples.rows)  # the rows are read again on access: same rules
            event("read")
            calibrate(samples, method="paper", leave_one_out=False)
            event("calibrated")
        except FtcompError as exc:
            event(type(exc).__name__)


@FUZZ
@given(st.binary(max_size=400), st.integers(8, 4096))
def test_sample_reader_on_random_bytes_raises_only_ftcomp_errors(data, chunk_bytes) -> None:
    _read_and_calibrate(data, chunk_bytes)


@FUZZ
@given(sample_text(), st.integers(8, 4096))
def test_sample_reader_on_csv_like_text_raises_only_ftcomp_errors(text, chunk_bytes) -> None:
    _read_and_calibrate(text.encode("utf-8", "surrogatepass"), chunk_bytes)


@FUZZ
@given(corrupted_paper(), st.integers(8, 4096))
def test_corrupted_paper_files_raise_only_ftcomp_errors(data, chunk_bytes) -> None:
    _read_and_calibrate(data, chunk_bytes)


# -- the calibration file ---------------------------------------------------------------------

KEYS = [
    "format",
    "method",
    "tool_weight_N",
    "center_of_gravity_m",
    "force_bias_N",
    "torque_bias_Nm",
    "base_tilt_deg",
    "gravity_in_base_N",
    "std_errors",
    "pose_ids",
    "readings_per_pose",
    "pose_quaternions_xyzw",
    "per_pose_residuals",
    "leave_one_out",
    "warnings",
    "condition_number",
    "pose_mean_wrench",
    "bias_drift",
    "mount",
    "U",
    "V",
]
json_scalar = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**30), 10**30),
    st.floats(allow_nan=False, allow_infinity=False),
    st.sampled_from([1e308, -1e308, 5e-324, 10**400]),
    st.text(max_size=8),
    st.sampled_from(["ftcomp.calibration/1", "ftcomp.truth/1", "paper", "joint"]),
)
json_value = st.recursive(
    json_scalar,
    lambda inner: st.one_of(
        st.lists(inner, max_size=5),
        st.dictionaries(st.one_of(st.sampled_from(KEYS), st.text(max_size=5)), inner, max_size=6),
    ),
    max_leaves=30,
)


@st.composite
def calibration_like(draw: st.DrawFn) -> object:
    """A valid calibration file's content with some values replaced by anything."""
    data = json.loads(_valid_calibration_text())
    for key in draw(st.lists(st.sampled_from(KEYS), max_size=4)):
        if draw(st.booleans()):
            data[key] = draw(json_value)
        else:
            data.pop(key, None)
    return data


_VALID: list[str] = []


def _valid_calibration_text() -> str:
    if not _VALID:
        from ftcomp.io.calibration_json import calibration_to_dict

        result = calibrate(read_samples(PAPER_CSV), method="paper")
        _VALID.append(json.dumps(calibration_to_dict(result), allow_nan=False))
    return _VALID[0]


def _load(text: str) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "cal.json"
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        try:
            calibration = load_calibration(path)
        except FtcompError:
            return
        model = calibration.model
        assert math.isfinite(model.weight_N)
        assert np.isfinite(model.force_bias_N).all() and np.isfinite(model.torque_bias_Nm).all()


@FUZZ
@given(json_value)
def test_calibration_reader_on_arbitrary_json_raises_only_ftcomp_errors(value) -> None:
    _load(json.dumps(value))


@FUZZ
@given(calibration_like())
def test_calibration_reader_on_damaged_calibrations_raises_only_ftcomp_errors(value) -> None:
    _load(json.dumps(value))


@FUZZ
@given(st.one_of(st.text(max_size=200), st.sampled_from(["[" * 100_000, '{"a":' * 50_000])))
def test_calibration_reader_on_arbitrary_text_raises_only_ftcomp_errors(text) -> None:
    _load(text)
