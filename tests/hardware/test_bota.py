"""The ``bota://`` backend: Gen0 frames from the twin's face on a pty (a process of its own
streaming a known, seeded sequence), and Bota's own client, ``bota-driver``, reading its
built-in simulated sensor (``bota://dummy``)."""

from __future__ import annotations

import importlib.util
import re
import struct
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.bota import (
    DRIVER_CHANNELS,
    GEN0_CHANNELS,
    GEN0_FRAME_SIZE,
    Gen0Decoder,
    crc16_x25,
    gen0_frame,
)
from ftcomp.hardware.fixed import FixedRobot
from ftcomp.hardware.protocols import ReportsExtraChannels
from ftcomp.hardware.registry import open_robot, open_sensor
from ftcomp.io.samples_csv import read_samples
from ftcomp.model import GravityModel
from ftcomp.paper import paper_poses
from ftcomp.ros2.mcap_log import SessionMcapLog
from ftcomp.session.pose_record import WrenchTolerance
from ftcomp.session.record import RecordConfig, RobotDriven, record
from ftcomp.session.stream import StreamConfig, stream, stream_columns

pytest.importorskip("serial")

SEED = 37
SPREAD = np.array([30.0, 30.0, 60.0, 2.0, 2.0, 1.0])

#: The stand-in: the twin's Gen0 face serving ``SPREAD * normal(seed)`` samples at 800 Hz for
#: at most 20 s, once its reader has sent ``go`` on stdin; prints the face's URI, injects each
#: other line of stdin as a fault.
SERVE = """
import sys, threading, time
import numpy as np
from ftcomp.hardware.protocols import WrenchSample
from ftcomp.twin.bota_face import BotaGen0Face
face = BotaGen0Face("", rate_hz=800.0, realtime=False)
spread = np.array([30.0, 30.0, 60.0, 2.0, 2.0, 1.0])
rng = np.random.default_rng(int(sys.argv[1]))
go = threading.Event()
print(face.uri(), flush=True)
def commands():
    for line in sys.stdin:
        go.set() if line.strip() == "go" else face.inject(line.strip())
threading.Thread(target=commands, daemon=True).start()
go.wait(10.0)
start = time.monotonic()
k = 0
while time.monotonic() - start < 20.0 and not face.pty.closed:
    samples = []
    while k < (time.monotonic() - start) * 800.0:
        samples.append(WrenchSample(k * 1_250_000, spread * rng.standard_normal(6)))
        k += 1
    face.push(samples)
    time.sleep(0.002)
face.close()
"""


pytestmark = pytest.mark.live


@contextmanager
def serving() -> Iterator[tuple[str, subprocess.Popen[str]]]:
    proc = subprocess.Popen(
        [sys.executable, "-c", SERVE, str(SEED)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        uri = proc.stdout.readline().strip()
        assert uri.startswith("bota:///dev/"), uri
        yield uri, proc
    finally:
        proc.kill()
        proc.wait(10)


def say(proc: subprocess.Popen[str], line: str) -> None:
    assert proc.stdin is not None
    proc.stdin.write(line + "\n")
    proc.stdin.flush()


def sent(count: int) -> np.ndarray:
    rng = np.random.default_rng(SEED)
    return np.array([SPREAD * rng.standard_normal(6) for _ in range(count)])


def as_float32(values: np.ndarray) -> np.ndarray:
    return values.astype(np.float32).astype(float)


def wait_readings(sensor: object, count: int, timeout_s: float = 10.0) -> list:
    readings: list = []
    deadline = time.monotonic() + timeout_s
    while len(readings) < count and time.monotonic() < deadline:
        readings += sensor.read_new()  # type: ignore[attr-defined]
        time.sleep(0.01)
    return readings


def test_crc16_x25_matches_the_standard_check_value() -> None:
    # The CRC catalogue's check value of CRC-16/IBM-SDLC over "123456789".
    assert crc16_x25(b"123456789") == 0x906E


def test_a_gen0_frame_is_37_bytes_and_decodes_to_what_was_packed() -> None:
    frame = gen0_frame(0b1, [1.5, -2.25, 3.0, 0.125, -0.5, 0.75], 123456, 31.5)
    assert len(frame) == GEN0_FRAME_SIZE == 37 and frame[0] == 0xAA
    assert struct.unpack_from("<H", frame, 1)[0] == 1
    decoder = Gen0Decoder()
    found = list(decoder.feed(b"\x00\xaa\x01" + frame + frame[:10]))
    assert found == [(1, (1.5, -2.25, 3.0, 0.125, -0.5, 0.75), 123456, 31.5)]
    bad = bytearray(frame)
    bad[5] ^= 0x10
    with pytest.raises(HardwareError, match=r"corrupted frame \(bad CRC\) after 2 frames"):
        list(decoder.feed(frame[10:] + bytes(bad)))


@pytest.mark.parametrize(
    ("uri", "match"),
    [
        ("bota://", "give the serial device"),
        ("bota:///dev/ttyUSB0?baud=0", "baud must be > 0"),
        ("bota:///dev/ttyUSB0?rate=1", "unknown option 'rate'"),
    ],
)
def test_bad_uris_are_one_line_naming_the_uri(uri: str, match: str) -> None:
    with pytest.raises(ParameterError, match=match):
        open_sensor(uri)


def test_gen0_frames_from_the_twins_face_are_read_exactly_with_the_temperature() -> None:
    with serving() as (uri, proc):
        sensor = open_sensor(uri)
        say(proc, "go")  # the stream starts once the port is open (its buffer flushed)
        with sensor:
            readings = wait_readings(sensor, 400)
            temperature = sensor.temperature_C  # type: ignore[attr-defined]
    assert isinstance(sensor, ReportsExtraChannels)
    assert sensor.extra_channels == GEN0_CHANNELS == ("temperature_C",)
    assert len(readings) >= 400
    # every reading carries its own frame's temperature (the face sends 30 degC)
    assert {r.extras for r in readings} == {(30.0,)}
    got = np.array([r.wrench_sensor for r in readings])
    # float32 on the wire: the values as sent, rounded to float32; none lost or reordered
    # (the first reading may be any of the first frames: the port opened as they came).
    first = int(np.argmin(np.abs(sent(4000) - got[0]).sum(axis=1)))
    expected = as_float32(sent(first + len(got))[first:])
    assert np.array_equal(got, expected)
    assert temperature == 30.0


class InstantArm(FixedRobot):
    """A robot on the host's clock (a Bota sensor's) that is at each pose as soon as asked."""

    def __init__(self) -> None:
        super().__init__(np.zeros(3), np.eye(3), 500.0, pose_known=True)

    def move_pose(self, p_base_tcp: np.ndarray, R_base_tcp: np.ndarray, duration_s: float) -> None:
        self._p, self._R = np.array(p_base_tcp), np.array(R_base_tcp)


def test_a_recording_from_the_twins_gen0_face_has_its_temperature_column(
    tmp_path: Path,
) -> None:
    out = tmp_path / "s.csv"
    # The face's readings are noise of tens of N: any drift between a window's halves is taken.
    plan = RobotDriven(
        paper_poses(), samples_per_pose=10, tolerance=WrenchTolerance(1e6, 1e6), max_tries=1
    )
    with serving() as (uri, proc):
        sensor = open_sensor(uri)
        say(proc, "go")
        with sensor, InstantArm() as arm:
            result = record(arm, sensor, RecordConfig(out, plan))
    assert result.ended == "complete" and result.readings == 90
    written = read_samples(out)
    assert written.header[-1] == "temperature_C"
    assert [row[-1] for row in written.rows] == ["30"] * 90  # the face's 30 degC, exactly


def test_a_stream_from_the_twins_gen0_face_logs_its_temperature_column(tmp_path: Path) -> None:
    with serving() as (uri, proc):
        sensor = open_sensor(uri)
        say(proc, "go")
        with sensor, open_robot("fixed://?rate_hz=500") as robot:
            result = stream(robot, sensor, StreamConfig(0.2), tmp_path / "s.csv")
    assert result.outcome == "duration" and result.readings > 50
    lines = (tmp_path / "s.csv").read_text().splitlines()
    header = tuple(lines[0].split(","))
    assert header == stream_columns(with_pose=False, compensated=False, extras=GEN0_CHANNELS)
    assert [line.split(",")[-1] for line in lines[1:]] == ["30"] * result.readings


@pytest.mark.parametrize(
    ("fault", "says"),
    [
        ("bota-crc", "corrupted frame (bad CRC)"),
        ("bota-overrange", "status 0x0002 (overrange)"),
        ("bota-disconnect", "the serial device is gone"),
    ],
)
def test_a_gen0_fault_is_a_stop_never_a_reading(fault: str, says: str) -> None:
    with serving() as (uri, proc):
        sensor = open_sensor(uri)
        say(proc, "go")
        with sensor:
            before = wait_readings(sensor, 50)
            say(proc, fault)
            after: list = []
            deadline = time.monotonic() + 5.0
            with pytest.raises(HardwareError, match="sensor fault: " + re.escape(says)):
                while time.monotonic() < deadline:
                    after += sensor.read_new()
                    sensor.read()
                    time.sleep(0.005)
    got = np.array([r.wrench_sensor for r in before + after])
    first = int(np.argmin(np.abs(sent(4000) - got[0]).sum(axis=1)))
    assert np.array_equal(got, as_float32(sent(first + len(got))[first:]))


@pytest.mark.skipif(
    importlib.util.find_spec("bota_driver") is None,
    reason="bota-driver (Bota's binary client) has no wheel for this platform",
)
def test_bota_dummy_reads_the_vendor_drivers_simulated_sensor() -> None:
    with open_sensor("bota://dummy") as sensor:
        readings = wait_readings(sensor, 300)
        temperature = sensor.temperature_C  # type: ignore[attr-defined]
        acceleration = sensor.acceleration_m_s2  # type: ignore[attr-defined]
    assert isinstance(sensor, ReportsExtraChannels)
    assert sensor.extra_channels == DRIVER_CHANNELS
    assert len(readings) >= 300
    # Each reading's own channels: 25 degC, gravity on the accelerometer (about 0.03 m/s^2 of
    # noise per axis and reading, seen: one reading's norm spans 9.70-9.89, their mean's
    # within 0.005 of 9.807).
    extras = np.array([r.extras for r in readings])
    assert extras.shape == (len(readings), 7) and np.all(np.isfinite(extras))
    assert np.all(extras[:, 0] == 25.0)
    assert np.linalg.norm(extras[:, 1:4].mean(axis=0)) == pytest.approx(9.81, abs=0.05)
    # ... along -z: an accelerometer's specific force with the sensor's z pointing down (as a
    # tool hangs), the convention --accelerometer reads (docs/hardware.md)
    np.testing.assert_allclose(extras[:, 1:4].mean(axis=0), [0.0, 0.0, -9.81], atol=0.05)
    got = np.array([r.wrench_sensor for r in readings])
    # bota-driver 1.1.16's Bota_Dummy: (1, 2, 3) N and (0.1, 0.2, 0.3) N*m with noise of about
    # 0.1 N and 0.03 N*m per reading (seen), so the mean of n readings within 5 of its standard
    # errors; 25 degC; gravity on its accelerometer.
    mean, se = got.mean(axis=0), got.std(axis=0, ddof=1) / np.sqrt(len(got))
    assert np.all(np.abs(mean - [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]) <= 5 * se), (mean, se)
    assert temperature == 25.0
    assert np.linalg.norm(acceleration) == pytest.approx(9.81, abs=0.2)  # the newest, one reading
    stamps = [r.t_ns for r in readings]
    assert stamps == sorted(stamps)


@pytest.mark.skipif(
    importlib.util.find_spec("bota_driver") is None,
    reason="bota-driver (Bota's binary client) has no wheel for this platform",
)
def test_a_stream_of_bota_dummy_logs_its_temperature_and_imu_columns(tmp_path: Path) -> None:
    mcap = SessionMcapLog(tmp_path / "s.mcap")
    with open_sensor("bota://dummy") as sensor, open_robot("fixed://?rate_hz=500") as robot:
        result = stream(robot, sensor, StreamConfig(0.5), tmp_path / "s.csv", observers=[mcap])
    assert result.outcome == "duration" and result.readings > 50
    header = (tmp_path / "s.csv").read_text().splitlines()[0].split(",")
    assert tuple(header) == stream_columns(
        with_pose=False, compensated=False, extras=DRIVER_CHANNELS
    )
    rows = np.loadtxt(tmp_path / "s.csv", delimiter=",", skiprows=1, ndmin=2)
    assert np.all(rows[:, header.index("temperature_C")] == 25.0)
    # gravity on the accelerometer: the mean of the readings (noise as in the test above)
    accel = rows[:, header.index("accel_x_m_s2") : header.index("accel_z_m_s2") + 1]
    assert np.linalg.norm(accel.mean(axis=0)) == pytest.approx(9.81, abs=0.05)
    # the MCAP log: a Temperature and an Imu message per row, the CSV's values
    with AnyReader([tmp_path / "s.mcap"]) as reader:
        found: dict[str, list] = {"/ftcomp/temperature": [], "/ftcomp/imu": []}
        for conn, _, raw in reader.messages():
            if conn.topic in found:
                found[conn.topic].append(reader.deserialize(raw, conn.msgtype))
    assert [m.temperature for m in found["/ftcomp/temperature"]] == [25.0] * len(rows)
    imu = np.array(
        [
            [m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z]
            for m in found["/ftcomp/imu"]
        ]
    )
    np.testing.assert_allclose(imu, accel, rtol=1e-9)  # the CSV's 10 significant digits


@pytest.mark.skipif(
    importlib.util.find_spec("bota_driver") is None,
    reason="bota-driver (Bota's binary client) has no wheel for this platform",
)
def test_with_the_accelerometer_each_row_of_bota_dummy_is_compensated_by_its_own_imu(
    tmp_path: Path,
) -> None:
    # A 0.51 kg tool 5 cm down the sensor's z: each row's contact wrench is its reading less
    # the tool under the apparent gravity of that row's accelerometer (the vendor's frames).
    tool = GravityModel(
        5.0, np.array([0.0, 0.0, 0.05]), np.zeros(3), np.zeros(3), tilt_U_rad=0.0, tilt_V_rad=0.0
    )
    config = StreamConfig(0.5, accelerometer=True)
    fixed = "fixed://?rate_hz=500&rpy_deg=180,0,0"  # a pose (compensation needs one), tool down
    with open_sensor("bota://dummy") as sensor, open_robot(fixed) as robot:
        stream(robot, sensor, config, tmp_path / "s.csv", calibration=tool)
    header = (tmp_path / "s.csv").read_text().splitlines()[0].split(",")
    rows = np.loadtxt(tmp_path / "s.csv", delimiter=",", skiprows=1, ndmin=2)
    assert len(rows) > 50
    raw = rows[:, header.index("fx") : header.index("tz") + 1]
    contact = rows[:, header.index("cfx") : header.index("ctz") + 1]
    f = rows[:, header.index("accel_x_m_s2") : header.index("accel_z_m_s2") + 1]
    weight = -(5.0 / STANDARD_GRAVITY_MPS2) * f
    expected = raw - np.hstack([weight, np.cross([0.0, 0.0, 0.05], weight)])
    np.testing.assert_allclose(contact, expected, rtol=1e-8, atol=1e-8)  # 10 digits in the CSV
