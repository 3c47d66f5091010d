"""The ``robotiq://`` backend against the twin's FT 300 faces: the URCap's TCP stream and the
Modbus RTU stream on a pty, each served from a process of its own that streams a known,
seeded sequence of wrenches at 100 Hz, so every reading is checked against what was sent."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest

from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.protocols import ReportsRate
from ftcomp.hardware.registry import open_sensor
from ftcomp.hardware.robotiq import (
    FRAME_HEADER,
    SLAVE_ID,
    STREAM_REGISTER,
    STREAM_START,
    FrameDecoder,
    crc16_modbus,
    parse_urcap_line,
    stream_frame,
    urcap_line,
    write_register_request,
)

pytest.importorskip("serial")

#: The protocol's resolution: forces in 1/100 N, torques in 1/1000 N*m. A reading is the sent
#: value rounded to it: within half a count (and float rounding).
RESOLUTION = np.repeat([0.01, 0.001], 3)
SEED = 36
#: The sent wrenches' spread: within the FT 300's rated 300 N / 30 N*m.
SPREAD = np.array([40.0, 40.0, 80.0, 3.0, 3.0, 2.0])

#: The stand-in: one face serving ``SPREAD * normal(seed)`` samples at 100 Hz for at most
#: 20 s; prints the face's URI, injects each fault named on its stdin.
SERVE = """
import sys, threading, time
import numpy as np
from ftcomp.hardware.protocols import WrenchSample
from ftcomp.twin.robotiq_face import RobotiqRtuFace, RobotiqUrcapFace
kind, host, seed = sys.argv[1], sys.argv[2], int(sys.argv[3])
Face = RobotiqUrcapFace if kind == "urcap" else RobotiqRtuFace
face = Face(host, rate_hz=100.0, realtime=False)
spread = np.array([40.0, 40.0, 80.0, 3.0, 3.0, 2.0])
rng = np.random.default_rng(seed)
print(face.uri(), flush=True)
def faults():
    for line in sys.stdin:
        face.inject(line.strip())
threading.Thread(target=faults, daemon=True).start()
start = time.monotonic()
k = 0
while time.monotonic() - start < 20.0:
    if kind == "urcap" and not face.clients or kind == "rtu" and not face.streaming:
        time.sleep(0.005)  # the sequence starts with the first client's stream
        continue
    face.push([WrenchSample(time.monotonic_ns(), spread * rng.standard_normal(6))])
    k += 1
    time.sleep(max(0.0, start + k * 0.01 - time.monotonic()))
face.close()
"""


pytestmark = pytest.mark.live


@contextmanager
def serving(kind: str, host: str) -> Iterator[tuple[str, subprocess.Popen[str]]]:
    proc = subprocess.Popen(
        [sys.executable, "-c", SERVE, kind, host, str(SEED)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        uri = proc.stdout.readline().strip()
        assert uri.startswith("robotiq://"), uri
        yield uri, proc
    finally:
        proc.kill()
        proc.wait(10)


def inject(proc: subprocess.Popen[str], fault: str) -> None:
    assert proc.stdin is not None
    proc.stdin.write(fault + "\n")
    proc.stdin.flush()


def sent(count: int) -> np.ndarray:
    """The stand-in's first ``count`` wrenches."""
    rng = np.random.default_rng(SEED)
    return np.array([SPREAD * rng.standard_normal(6) for _ in range(count)])


def wait_readings(sensor: object, count: int, timeout_s: float = 10.0) -> list:
    readings: list = []
    deadline = time.monotonic() + timeout_s
    while len(readings) < count and time.monotonic() < deadline:
        readings += sensor.read_new()  # type: ignore[attr-defined]
        time.sleep(0.02)
    return readings


def test_crc16_modbus_matches_the_standard_check_value() -> None:
    # The CRC catalogue's check value of CRC-16/MODBUS over "123456789", and the textbook
    # request "read one holding register at 0 from slave 1", whose CRC bytes are 84 0A.
    assert crc16_modbus(b"123456789") == 0x4B37
    assert crc16_modbus(bytes.fromhex("010300000001")) == 0x0A84


def test_the_stream_start_request_is_write_single_register_410_of_slave_9() -> None:
    request = write_register_request(SLAVE_ID, STREAM_REGISTER, STREAM_START)
    assert request[:6] == bytes.fromhex("0906019a0200")
    assert int.from_bytes(request[6:], "little") == crc16_modbus(request[:6])


def test_decoder_skips_bytes_before_the_first_frame_and_reads_frames_split_anywhere() -> None:
    counts = [(1, -2, 3000, -400, 5, 32767), (-32768, 0, 1, 2, 3, 4)]
    stream = b"\x09\x06\x01\x9a\x02\x00\x00" + b"".join(stream_frame(c) for c in counts)
    decoder = FrameDecoder()
    found = [c for at in range(0, len(stream), 5) for c in decoder.feed(stream[at : at + 5])]
    assert found == counts


@pytest.mark.parametrize(
    ("byte", "what"), [(15, "bad CRC"), (8, "bad CRC"), (0, "no frame header")]
)
def test_decoder_raises_on_a_corrupted_frame_after_the_first(byte: int, what: str) -> None:
    decoder = FrameDecoder()
    good = stream_frame((1, 2, 3, 4, 5, 6))
    bad = bytearray(good)
    bad[byte] ^= 0x01
    assert list(decoder.feed(good)) == [(1, 2, 3, 4, 5, 6)]
    with pytest.raises(HardwareError, match=rf"corrupted frame \({what}\) after 1 frames"):
        list(decoder.feed(bytes(bad)))
    assert good[:2] == FRAME_HEADER


def test_urcap_lines_round_trip_and_garbage_is_refused() -> None:
    line = urcap_line([1.234, -5.0, 300.0, 0.0015, -2.0, 29.9994])
    assert line == b"(1.23 , -5.00 , 300.00 , 0.002 , -2.000 , 29.999)\n"
    assert parse_urcap_line(line) == (1.23, -5.0, 300.0, 0.002, -2.0, 29.999)
    for garbage in (b"(1 , 2 , 3)", b"1 , 2 , 3 , 4 , 5 , 6", b"(1 , 2 , 3 , 4 , 5 , nan)"):
        with pytest.raises(ValueError):
            parse_urcap_line(garbage)


@pytest.mark.parametrize(
    ("uri", "match"),
    [
        ("robotiq://", "give the UR controller's address"),
        ("robotiq://10.0.0.1/dev/ttyUSB0", "one of them"),
        ("robotiq://127.0.0.1?timeout_s=0", "timeout_s must be > 0"),
        ("robotiq://127.0.0.1?rate=1", "unknown option 'rate'"),
    ],
)
def test_bad_uris_are_one_line_naming_the_uri(uri: str, match: str) -> None:
    with pytest.raises(ParameterError, match=match):
        open_sensor(uri)


@pytest.mark.parametrize(("kind", "host"), [("urcap", "127.0.0.71"), ("rtu", "127.0.0.72")])
def test_both_streams_are_read_within_the_protocols_resolution(kind: str, host: str) -> None:
    with serving(kind, host) as (uri, _), open_sensor(uri) as sensor:
        readings = wait_readings(sensor, 50)
        newest = sensor.read()
        # The rate its readings came at, which sets run's wrench filter (the stand-in paces
        # 100 Hz on an absolute schedule; a loaded host delays a few, it sends no more)
        assert isinstance(sensor, ReportsRate)
        assert sensor.sample_rate_hz == pytest.approx(100.0, rel=0.3)
    assert len(readings) >= 50
    got = np.array([r.wrench_sensor for r in readings])
    expected = sent(len(got))
    # Every reading in order, none lost, each the sent value rounded to a count.
    assert np.all(np.abs(got - expected) <= RESOLUTION / 2 + 1e-9), np.abs(got - expected).max(0)
    assert np.all(np.diff([r.t_ns for r in readings]) >= 0)
    assert newest.t_ns >= readings[-1].t_ns


@pytest.mark.parametrize(
    ("kind", "host", "fault", "says"),
    [
        ("rtu", "127.0.0.73", "rtu-crc", "corrupted frame (bad CRC)"),
        ("rtu", "127.0.0.74", "rtu-disconnect", "the serial device is gone"),
        ("rtu", "127.0.0.75", "ft300-overrange", "overrange"),
        ("urcap", "127.0.0.76", "urcap-garbled", "a line that is not six numbers"),
        ("urcap", "127.0.0.77", "urcap-disconnect", "the URCap stream ended"),
        ("urcap", "127.0.0.78", "network-loss", "no reading for"),
    ],
)
def test_a_fault_is_a_stop_never_a_reading(kind: str, host: str, fault: str, says: str) -> None:
    with serving(kind, host) as (uri, proc), open_sensor(uri) as sensor:
        before = wait_readings(sensor, 10)
        inject(proc, fault)
        deadline = time.monotonic() + 5.0
        after: list = []
        with pytest.raises(HardwareError, match="sensor fault: " + re.escape(says)):
            while time.monotonic() < deadline:
                after += sensor.read_new()
                sensor.read()
                time.sleep(0.005)
    got = np.array([r.wrench_sensor for r in before + after])
    # What was read before the stop is what was sent: the corrupted one never a reading.
    expected = sent(len(got))
    assert np.all(np.abs(got - expected) <= RESOLUTION / 2 + 1e-9)


def test_silence_at_connect_is_an_error_naming_the_uri() -> None:
    sensor = open_sensor("robotiq://127.0.0.79?connect_timeout_s=0.2")
    with pytest.raises(HardwareError, match=r"'robotiq://127.0.0.79\?connect_timeout_s=0.2'"):
        sensor.__enter__()
