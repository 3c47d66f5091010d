"""The ``robotiq://`` backend: a Robotiq FT 300(-S) through its stream, two ways.

URIs::

    robotiq://HOST[:63351]            the URCap's stream on a UR controller (TCP, ASCII lines)
    robotiq:///dev/ttyUSB0            the sensor's own USB/RS-485 line: Modbus RTU stream mode
          ?timeout_s=0.1              silence longer than this is a fault [s]
          &connect_timeout_s=2        longest wait for the first reading [s]

**Modbus RTU** (Robotiq's FT 300 manual): 19200 baud, 8N1, slave 9. Writing 0x0200 to holding
register 410 (function 6) starts the stream: 16-byte frames at 100 Hz, ``0x20 0x4E``, six
little-endian int16 (Fx, Fy, Fz in 1/100 N; Mx, My, Mz in 1/1000 N*m) and the Modbus CRC-16
(low byte first). About 50 bytes of 0xFF stop it. This backend checks every frame's CRC: bytes
before the first whole frame are skipped (the reply to the write, a stream already running),
and after it a frame whose CRC is wrong, or a header out of place, ends the stream with a fault
(fail-stop, as ``netft://``): a corrupted reading is a stop, never a reading.

**URCap stream**: with Robotiq's URCap installed, the UR controller serves the sensor's
readings on TCP port 63351 as ASCII lines ``(fx , fy , fz , mx , my , mz)`` [N, N*m] at the
sensor's 100 Hz. This is documented by users' drivers (ROS ``robotiq_ft_sensor``, community
clients), not by Robotiq; a line that is not six finite numbers ends the stream with a fault.

Both: values in N and N*m at the protocol's resolution (0.01 N, 0.001 N*m), the sensor's own
frame, as the sensor reports them (whether its signs match ftcomp's convention, tool on
sensor, is *not* verified against a device: check with a known weight, docs/hardware.md). A
reading beyond the FT 300's rated range (300 N per force axis, 30 N*m per torque axis) is an
overrange and ends the stream. Each reading is stamped on arrival (the host's monotonic
clock); at 19200 baud a frame takes 8.3 ms on the wire, so a real sensor's stamp is that much
later than its sample. Silence beyond ``timeout_s`` and a closed connection or vanished serial
device are faults too. The next :meth:`RobotiqSensor.read` raises
:class:`~ftcomp.errors.HardwareError` naming the fault.

Serial I/O goes through ``pyserial`` (``pip install 'ftcomp[robotiq]'``); the URCap stream
needs nothing beyond the standard library.
"""

from __future__ import annotations

import contextlib
import math
import socket
import struct
import time
from collections.abc import Iterator
from typing import Any, Final

import numpy as np

from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.arrival_stream import ArrivalStream, import_serial
from ftcomp.hardware.pacing import on_host_clock
from ftcomp.hardware.protocols import Robot, WrenchSensor
from ftcomp.hardware.registry import Uri

__all__ = [
    "BAUD_RATE",
    "FORCE_N_PER_COUNT",
    "FRAME_HEADER",
    "FRAME_SIZE",
    "RATED_RANGE",
    "SLAVE_ID",
    "STOP_BYTES",
    "STREAM_REGISTER",
    "STREAM_START",
    "TORQUE_NM_PER_COUNT",
    "URCAP_PORT",
    "FrameDecoder",
    "RobotiqSensor",
    "crc16_modbus",
    "open_sensor",
    "parse_urcap_line",
    "stream_frame",
    "urcap_line",
    "write_register_request",
]

#: The FT 300's serial line: 19200 baud, 8N1.
BAUD_RATE: Final = 19200
#: Its Modbus slave address.
SLAVE_ID: Final = 9
#: The holding register that starts stream mode, and the value that starts it.
STREAM_REGISTER: Final = 410
STREAM_START: Final = 0x0200
#: A stream frame: header, six int16, CRC-16.
FRAME_HEADER: Final = b"\x20\x4e"
FRAME_SIZE: Final = 16
#: The bytes that stop stream mode (the manual: "about 50 bytes of 0xFF").
STOP_BYTES: Final = b"\xff" * 50
#: N per force count and N*m per torque count.
FORCE_N_PER_COUNT: Final = 0.01
TORQUE_NM_PER_COUNT: Final = 0.001
#: The FT 300's rated range per axis: force [N], torque [N*m].
RATED_RANGE: Final = (300.0, 30.0)
#: The URCap's stream port on a UR controller.
URCAP_PORT: Final = 63351

_SCALE: Final = np.repeat([FORCE_N_PER_COUNT, TORQUE_NM_PER_COUNT], 3)
_RANGE: Final = np.repeat(RATED_RANGE, 3)
_WRITE_SINGLE_REGISTER: Final = 6


def crc16_modbus(data: bytes) -> int:
    """The Modbus CRC-16 of ``data`` (polynomial 0xA001 reflected, initial 0xFFFF)."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def write_register_request(slave: int, register: int, value: int) -> bytes:
    """A Modbus RTU "write single register" request (function 6), CRC appended low byte first."""
    body = struct.pack(">BBHH", slave, _WRITE_SINGLE_REGISTER, register, value)
    return body + struct.pack("<H", crc16_modbus(body))


def stream_frame(counts: Any) -> bytes:
    """One stream frame of six counts (Fx, Fy, Fz [1/100 N], Mx, My, Mz [1/1000 N*m])."""
    body = FRAME_HEADER + struct.pack("<6h", *counts)
    return body + struct.pack("<H", crc16_modbus(body))


class FrameDecoder:
    """Splits a byte stream into stream frames, checking each one's CRC.

    Until the first whole frame (header and CRC right) bytes are skipped one by one; after it
    frames follow back to back, and a frame whose header or CRC is wrong raises
    :class:`~ftcomp.errors.HardwareError`: the stream can no longer be trusted.
    """

    def __init__(self) -> None:
        self.synced = False
        self.frames = 0
        self._buffer = bytearray()

    def feed(self, data: bytes) -> Iterator[tuple[int, ...]]:
        """The whole frames ``data`` completes, as six counts each."""
        buffer = self._buffer
        buffer += data
        while len(buffer) >= FRAME_SIZE:
            frame = bytes(buffer[:FRAME_SIZE])
            good_header = frame[:2] == FRAME_HEADER
            good_crc = struct.unpack_from("<H", frame, 14)[0] == crc16_modbus(frame[:14])
            if not (good_header and good_crc):
                if self.synced:
                    what = "bad CRC" if good_header else "no frame header"
                    raise HardwareError(
                        f"corrupted frame ({what}) after {self.frames} frames: {frame.hex(' ')}"
                    )
                del buffer[0]
                continue
            self.synced = True
            self.frames += 1
            del buffer[:FRAME_SIZE]
            yield struct.unpack_from("<6h", frame, 2)


def urcap_line(wrench: Any) -> bytes:
    """One URCap stream line of a wrench [N, N*m] at the protocol's resolution."""
    fx, fy, fz, mx, my, mz = (float(v) for v in wrench)
    return f"({fx:.2f} , {fy:.2f} , {fz:.2f} , {mx:.3f} , {my:.3f} , {mz:.3f})\n".encode()


def parse_urcap_line(line: bytes) -> tuple[float, ...]:
    """The six numbers of a URCap stream line.

    Raises:
        ValueError: not ``(a , b , c , d , e , f)`` of six finite numbers.
    """
    text = line.decode("ascii").strip()
    if not (text.startswith("(") and text.endswith(")")):
        raise ValueError("not in parentheses")
    values = tuple(float(v) for v in text[1:-1].split(","))
    if len(values) != 6 or not all(math.isfinite(v) for v in values):
        raise ValueError("not six finite numbers")
    return values


class _Transport:
    """One way of reaching the sensor: connect, read bytes (b"" on silence), close."""

    def open(self, timeout_s: float) -> None:
        raise NotImplementedError

    def read(self) -> bytes:
        raise NotImplementedError

    def close(self) -> None:
        raise NotImplementedError


class _UrcapTransport(_Transport):
    def __init__(self, host: str, port: int) -> None:
        self.address = (host, port)
        self.sock: socket.socket | None = None

    def open(self, timeout_s: float) -> None:
        try:
            self.sock = socket.create_connection(self.address, timeout=timeout_s)
        except OSError as exc:
            host, port = self.address
            raise HardwareError(f"cannot connect to {host}:{port}: {exc}") from None
        self.sock.settimeout(0.05)

    def read(self) -> bytes:
        assert self.sock is not None
        try:
            data = self.sock.recv(4096)
        except TimeoutError:
            return b""
        except OSError as exc:
            raise HardwareError(f"the URCap stream ended: {exc}") from None
        if not data:
            raise HardwareError("the URCap stream ended (closed by the controller)")
        return data

    def close(self) -> None:
        if self.sock is not None:
            with contextlib.suppress(OSError):
                self.sock.close()


class _RtuTransport(_Transport):
    def __init__(self, path: str) -> None:
        self.path = path
        self.serial = import_serial("robotiq:///DEVICE", "robotiq")
        self.port: Any = None

    def open(self, timeout_s: float) -> None:
        serial = self.serial
        try:
            self.port = serial.Serial(
                self.path, BAUD_RATE, bytesize=8, parity="N", stopbits=1, timeout=0.05
            )
        except (serial.SerialException, OSError) as exc:
            raise HardwareError(f"cannot open {self.path}: {exc}") from None
        try:
            # Stop a stream another program left running, drop what it sent, start ours.
            self.port.write(STOP_BYTES)
            self.port.flush()
            time.sleep(0.02)
            self.port.reset_input_buffer()
            self.port.write(write_register_request(SLAVE_ID, STREAM_REGISTER, STREAM_START))
        except (serial.SerialException, OSError) as exc:
            self.close()
            raise HardwareError(f"cannot write to {self.path}: {exc}") from None

    def read(self) -> bytes:
        serial = self.serial
        try:
            return bytes(self.port.read(max(FRAME_SIZE, self.port.in_waiting)))
        except (serial.SerialException, OSError) as exc:
            raise HardwareError(f"the serial device is gone: {exc}") from None

    def close(self) -> None:
        if self.port is not None:
            with contextlib.suppress(Exception):
                self.port.write(STOP_BYTES)
                self.port.flush()
            with contextlib.suppress(Exception):
                self.port.close()


class RobotiqSensor(ArrivalStream):
    """A Robotiq FT 300 streaming through the URCap or Modbus RTU (see the module docstring).

    Args:
        uri: the parsed URI (for messages).
        transport: ``"urcap"`` (``host``, ``port``) or ``"rtu"`` (``path``).
        host: the UR controller's address (URCap).
        port: the URCap's port.
        path: the serial device (Modbus RTU).
        timeout_s: silence longer than this ends the stream with a fault [s].
        connect_timeout_s: longest wait for the first reading [s].
    """

    def __init__(
        self,
        uri: Uri,
        transport: str,
        *,
        host: str = "",
        port: int = URCAP_PORT,
        path: str = "",
        timeout_s: float = 0.1,
        connect_timeout_s: float = 2.0,
    ) -> None:
        super().__init__(uri, timeout_s=timeout_s, connect_timeout_s=connect_timeout_s)
        self.kind = transport
        self._transport: _Transport = (
            _UrcapTransport(host, port) if transport == "urcap" else _RtuTransport(path)
        )

    def _open(self) -> None:
        self._transport.open(self._connect_timeout_s)

    def _shutdown(self) -> None:
        self._transport.close()

    def _receive(self) -> None:
        if self.kind == "urcap":
            self._receive_lines()
        else:
            self._receive_frames()

    def _receive_lines(self) -> None:
        pending = b""
        while self.running:
            data = self._transport.read()
            if not data:
                continue
            stamp = time.monotonic_ns()
            *lines, pending = (pending + data).split(b"\n")
            for line in lines:
                try:
                    values = parse_urcap_line(line)
                except (ValueError, UnicodeDecodeError):
                    raise HardwareError(f"a line that is not six numbers: {line[:80]!r}") from None
                self._keep_checked(stamp, np.array(values))
            if len(pending) > 256:
                raise HardwareError(f"no line end in {len(pending)} bytes")

    def _receive_frames(self) -> None:
        decoder = FrameDecoder()
        while self.running:
            data = self._transport.read()
            if not data:
                continue
            stamp = time.monotonic_ns()
            for counts in decoder.feed(data):
                self._keep_checked(stamp, np.array(counts, dtype=float) * _SCALE)

    def _keep_checked(self, stamp: int, wrench: np.ndarray) -> None:
        if (np.abs(wrench) > _RANGE).any():
            raise HardwareError(
                "overrange: a reading beyond the FT 300's rated 300 N / 30 N*m: "
                + " ".join(f"{v:g}" for v in wrench)
            )
        self._keep(stamp, wrench)


def open_sensor(uri: Uri, robot: Robot | None) -> WrenchSensor:
    """A Robotiq FT 300 from its URI (not connected until entered).

    Raises:
        ParameterError: neither a host nor a device path, both, a bad option, or a robot on
            another clock (simulation).
    """
    if bool(uri.host) == bool(uri.path not in ("", "/")):
        raise ParameterError(
            f"{uri.text!r}: give the UR controller's address (robotiq://192.168.1.10, the "
            "URCap's stream) or the serial device (robotiq:///dev/ttyUSB0), one of them"
        )
    if robot is not None and not on_host_clock(robot):
        raise ParameterError(
            f"{uri.text!r}: an FT 300 is stamped on the host's monotonic clock and cannot share "
            "a session with this robot (simulated time); use it with ur:// or alone"
        )
    options = uri.reader()
    timeout_s = options.positive("timeout_s", 0.1)
    connect_s = options.positive("connect_timeout_s", 2.0)
    options.done()
    if uri.host:
        port = uri.port if uri.port is not None else URCAP_PORT
        if not 1 <= port <= 65535:
            raise ParameterError(f"{uri.text!r}: the port must be in 1..65535, got {port}")
        return RobotiqSensor(
            uri, "urcap", host=uri.host, port=port, timeout_s=timeout_s, connect_timeout_s=connect_s
        )
    import_serial("robotiq:///DEVICE", "robotiq")
    return RobotiqSensor(
        uri, "rtu", path=uri.path, timeout_s=timeout_s, connect_timeout_s=connect_s
    )
