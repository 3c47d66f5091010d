"""The ``bota://`` backend: Bota Systems sensors (Rokubi, SensONE, MiniONE).

URIs::

    bota:///dev/ttyUSB0               a Gen0 sensor's serial stream, read by ftcomp (pyserial)
          ?baud=460800                the line's rate
    bota://dummy                      bota-driver's built-in simulated sensor (Bota_Dummy)
    bota://HOST                       a Gen A sensor over Ethernet through bota-driver (Bota_Socket)
          &timeout_s=0.1              (any of them) silence longer than this is a fault [s]
          &connect_timeout_s=5        longest wait for the first reading [s]

**Gen0 serial frames** (as Bota's open serial drivers declare them): ``0xAA``, then a u16
status (bit 0 the sensor skipped measurements, bit 1 overrange, bit 2 invalid measurements,
bit 3 raw, uncalibrated measurements), six float32 (Fx, Fy, Fz [N], Mx, My, Mz [N*m]), a u32
timestamp [us] and a float32 temperature [degC], all little-endian, then the CRC-16/X-25 of
the 34 bytes after the header. Bytes before the first whole frame are skipped; after it a frame
whose CRC or header is wrong ends the stream (a stop, never a reading), and so does a frame
with the overrange, invalid or raw bit set. A frame with only the skipped-measurements bit is
read and counted (:attr:`BotaSerialSensor.skipped_flags`). ftcomp sends the sensor no
configuration command: it reads a sensor that streams (configure its filter and rate with
Bota's tools beforehand).

**bota-driver** (``pip install 'ftcomp[bota]'``, Bota's closed binary client): its
``Bota_Dummy`` interface serves a simulated sensor at 270 Hz, and ``Bota_Socket`` a Gen A
sensor on the network. Each frame's status (``DataStatus``: throttled, overrange, invalid,
raw) is judged as above.

Every reading: N and N*m in the sensor's own frame, as the sensor reports it (its sign
convention against ftcomp's, tool on sensor, is not verified against a device), stamped on
arrival on the host's monotonic clock. Each reading carries the sensor's other channels of the
same frame (:class:`~ftcomp.hardware.protocols.ReportsExtraChannels`, so the logs have them
beside the wrench): its temperature (``temperature_C`` [degC]) and, through bota-driver, its
IMU's acceleration (``accel_x_m_s2``.. [m/s^2]) and angular rate (``gyro_x_rad_s``.. [rad/s]),
in the sensor's frame as it reports them; the newest are kept too
(:attr:`BotaSerialSensor.temperature_C`, :attr:`BotaDriverSensor.acceleration_m_s2`).
"""

from __future__ import annotations

import contextlib
import struct
import time
from collections.abc import Iterator
from typing import Any, Final

import numpy as np

from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.arrival_stream import ArrivalStream, import_serial
from ftcomp.hardware.pacing import on_host_clock
from ftcomp.hardware.protocols import IMU_CHANNELS, TEMPERATURE_CHANNEL, Robot, WrenchSensor
from ftcomp.hardware.registry import Uri

__all__ = [
    "DRIVER_CHANNELS",
    "GEN0_BAUD_RATE",
    "GEN0_CHANNELS",
    "GEN0_FRAME_SIZE",
    "GEN0_HEADER",
    "STATUS_BITS",
    "BotaDriverSensor",
    "BotaSerialSensor",
    "Gen0Decoder",
    "crc16_x25",
    "gen0_frame",
    "open_sensor",
]

#: A Gen0 sensor's serial line rate [baud].
GEN0_BAUD_RATE: Final = 460800
GEN0_HEADER: Final = 0xAA
#: Header, status, six float32, timestamp, temperature, CRC.
GEN0_FRAME_SIZE: Final = 1 + 2 + 24 + 4 + 4 + 2
#: The status word's bits, by name (bit 0 first).
STATUS_BITS: Final = ("skipped", "overrange", "invalid", "raw")
#: The extra channels of a Gen0 serial frame (:class:`BotaSerialSensor`).
GEN0_CHANNELS: Final = (TEMPERATURE_CHANNEL,)
#: The extra channels of a bota-driver frame (:class:`BotaDriverSensor`), sensor frame.
DRIVER_CHANNELS: Final = (TEMPERATURE_CHANNEL, *IMU_CHANNELS)
#: The bits that end the stream: the values are not a calibrated measurement.
_FAULT_MASK: Final = 0b1110
_PAYLOAD: Final = struct.Struct("<H6fIf")


def crc16_x25(data: bytes) -> int:
    """The CRC-16/X-25 of ``data`` (CCITT polynomial reflected, 0xFFFF in, complemented out)."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0x8408 if crc & 1 else crc >> 1
    return crc ^ 0xFFFF


def gen0_frame(status: int, wrench: Any, timestamp_us: int, temperature_C: float) -> bytes:
    """One Gen0 serial frame (the module docstring's layout)."""
    payload = _PAYLOAD.pack(status, *(float(v) for v in wrench), timestamp_us, temperature_C)
    return bytes([GEN0_HEADER]) + payload + struct.pack("<H", crc16_x25(payload))


def _status_names(status: int) -> str:
    return ", ".join(name for bit, name in enumerate(STATUS_BITS) if status >> bit & 1)


class Gen0Decoder:
    """Splits a Gen0 byte stream into frames, checking each one's CRC (as
    :class:`~ftcomp.hardware.robotiq.FrameDecoder`: skip to the first whole frame, then any
    bad frame raises :class:`~ftcomp.errors.HardwareError`)."""

    def __init__(self) -> None:
        self.synced = False
        self.frames = 0
        self._buffer = bytearray()

    def feed(self, data: bytes) -> Iterator[tuple[int, tuple[float, ...], int, float]]:
        """The whole frames ``data`` completes: ``(status, wrench, timestamp_us, temp_C)``."""
        buffer = self._buffer
        buffer += data
        while len(buffer) >= GEN0_FRAME_SIZE:
            frame = bytes(buffer[:GEN0_FRAME_SIZE])
            payload = frame[1:-2]
            good_header = frame[0] == GEN0_HEADER
            good_crc = int.from_bytes(frame[-2:], "little") == crc16_x25(payload)
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
            del buffer[:GEN0_FRAME_SIZE]
            status, fx, fy, fz, mx, my, mz, stamp_us, temperature = _PAYLOAD.unpack(payload)
            yield status, (fx, fy, fz, mx, my, mz), stamp_us, temperature


class BotaSerialSensor(ArrivalStream):
    """A Bota Gen0 sensor's serial stream (module docstring); its readings carry the frame's
    temperature (:data:`GEN0_CHANNELS`).

    Args:
        uri: the parsed URI (for messages).
        path: the serial device.
        baud: the line's rate [baud].
        timeout_s: silence longer than this ends the stream with a fault [s].
        connect_timeout_s: longest wait for the first reading [s].
    """

    def __init__(
        self, uri: Uri, path: str, *, baud: int, timeout_s: float, connect_timeout_s: float
    ) -> None:
        super().__init__(uri, timeout_s=timeout_s, connect_timeout_s=connect_timeout_s)
        self.path = path
        self.baud = baud
        self._serial = import_serial("bota:///DEVICE", "bota")
        self._port: Any = None
        #: The newest reading's temperature [degC] (NaN before the first).
        self.temperature_C = float("nan")
        #: The newest reading's sensor timestamp [us].
        self.sensor_timestamp_us = 0
        #: Frames that carried the "skipped measurements" bit.
        self.skipped_flags = 0

    @property
    def extra_channels(self) -> tuple[str, ...]:
        """:data:`GEN0_CHANNELS` (:class:`~ftcomp.hardware.protocols.ReportsExtraChannels`)."""
        return GEN0_CHANNELS

    def _open(self) -> None:
        serial = self._serial
        try:
            self._port = serial.Serial(
                self.path, self.baud, bytesize=8, parity="N", stopbits=1, timeout=0.05
            )
            self._port.reset_input_buffer()  # frames queued before we came are old
        except (serial.SerialException, OSError) as exc:
            raise HardwareError(f"cannot open {self.path}: {exc}") from None

    def _shutdown(self) -> None:
        with contextlib.suppress(Exception):
            self._port.close()

    def _receive(self) -> None:
        serial, decoder = self._serial, Gen0Decoder()
        while self.running:
            try:
                data = self._port.read(max(GEN0_FRAME_SIZE, self._port.in_waiting))
            except (serial.SerialException, OSError) as exc:
                raise HardwareError(f"the serial device is gone: {exc}") from None
            if not data:
                continue
            stamp = time.monotonic_ns()
            for status, wrench, stamp_us, temperature in decoder.feed(data):
                if status & _FAULT_MASK:
                    raise HardwareError(
                        f"status 0x{status:04x} ({_status_names(status)}) after "
                        f"{decoder.frames - 1} frames"
                    )
                self.skipped_flags += status & 1
                self.temperature_C, self.sensor_timestamp_us = temperature, stamp_us
                self._keep(stamp, np.array(wrench, dtype=float), (temperature,))


def _import_driver() -> Any:
    try:
        import bota_driver
    except ImportError:
        raise ParameterError(
            "bota://dummy and bota://HOST need Bota's client: pip install 'ftcomp[bota]' "
            "(bota-driver, a binary wheel for Linux x86-64 and a few others)"
        ) from None
    return bota_driver


class BotaDriverSensor(ArrivalStream):
    """A Bota sensor through Bota's ``bota-driver`` (module docstring): its simulated sensor
    (``host="dummy"``) or a Gen A sensor over Ethernet; its readings carry the frame's
    temperature, acceleration and angular rate (:data:`DRIVER_CHANNELS`).

    Args:
        uri: the parsed URI (for messages).
        host: ``"dummy"`` or the sensor's address.
        timeout_s: silence longer than this ends the stream with a fault [s].
        connect_timeout_s: longest wait for the first reading [s].
    """

    def __init__(self, uri: Uri, host: str, *, timeout_s: float, connect_timeout_s: float) -> None:
        super().__init__(uri, timeout_s=timeout_s, connect_timeout_s=connect_timeout_s)
        bd = self._bd = _import_driver()
        config = bd.BotaDriverConfig()
        # The client compares these with the sensor's metadata and only warns on a mismatch.
        config.product_name = "any"
        config.serial_number = "any"
        if host == "dummy":
            config.communication_interface_name = "Bota_Dummy"
            config.dummy_communication_interface_params = bd.BotaDummyCommunicationInterfaceConfig()
        else:
            config.communication_interface_name = "Bota_Socket"
            socket_params = bd.BotaSocketCommunicationInterfaceConfig()
            socket_params.sensor_ip_address = host
            config.socket_communication_interface_params = socket_params
        # The operation mode of Bota's own example (app mode 2, submode 7).
        operation = bd.GenASensorOperationConfig()
        operation.app_mode, operation.app_submode = 2, 7
        config.genA_sensor_operation_params = operation
        driver_params = bd.DriverOperationConfig()
        driver_params.runtime_verbosity = False
        driver_params.register_with_daemon = False
        config.driver_operation_params = driver_params
        self._config = config
        self._driver: Any = None
        #: The newest reading's temperature [degC], acceleration [m/s^2] and angular rate
        #: [rad/s], sensor frame (NaN before the first).
        self.temperature_C = float("nan")
        self.acceleration_m_s2 = np.full(3, np.nan)
        self.angular_rate_rad_s = np.full(3, np.nan)
        #: The newest reading's sensor timestamp [us].
        self.sensor_timestamp_us = 0
        #: Frames whose status said the sensor throttled (skipped measurements).
        self.skipped_flags = 0

    @property
    def extra_channels(self) -> tuple[str, ...]:
        """:data:`DRIVER_CHANNELS` (:class:`~ftcomp.hardware.protocols.ReportsExtraChannels`)."""
        return DRIVER_CHANNELS

    def _open(self) -> None:
        try:
            driver = self._bd.BotaDriver(self._config)
        except (ValueError, RuntimeError) as exc:
            raise HardwareError(f"bota-driver refused the configuration: {exc}") from None
        if not driver.configure():
            raise HardwareError("bota-driver could not configure the sensor (see its log above)")
        if not driver.activate():
            driver.shutdown()
            raise HardwareError("bota-driver could not start the sensor's stream")
        self._driver = driver

    def _shutdown(self) -> None:
        driver, self._driver = self._driver, None
        if driver is not None:
            with contextlib.suppress(Exception):
                driver.deactivate()
            with contextlib.suppress(Exception):
                driver.shutdown()

    def _receive(self) -> None:
        driver = self._driver
        while self.running:
            frame = driver.read_frame_blocking()
            stamp = time.monotonic_ns()
            status = frame.status
            if status.overrange or status.invalid or status.raw:
                names = [n for n in ("overrange", "invalid", "raw") if getattr(status, n)]
                raise HardwareError(f"status {', '.join(names)}")
            self.skipped_flags += bool(status.throttled)
            temperature = float(frame.temperature)
            acceleration = np.array(frame.acceleration, dtype=float)
            angular_rate = np.array(frame.angular_rate, dtype=float)
            self.temperature_C = temperature
            self.acceleration_m_s2, self.angular_rate_rad_s = acceleration, angular_rate
            self.sensor_timestamp_us = int(frame.timestamp)
            extras = (temperature, *acceleration.tolist(), *angular_rate.tolist())
            self._keep(stamp, np.array([*frame.force, *frame.torque], dtype=float), extras)


def open_sensor(uri: Uri, robot: Robot | None) -> WrenchSensor:
    """A Bota sensor from its URI (not connected until entered).

    Raises:
        ParameterError: neither a host nor a device path, both, a bad option, a client not
            installed, or a robot on another clock (simulation).
    """
    if bool(uri.host) == bool(uri.path not in ("", "/")):
        raise ParameterError(
            f"{uri.text!r}: give the serial device (bota:///dev/ttyUSB0), the sensor's address "
            "(bota://192.168.1.9) or bota://dummy, one of them"
        )
    if robot is not None and not on_host_clock(robot):
        raise ParameterError(
            f"{uri.text!r}: a Bota sensor is stamped on the host's monotonic clock and cannot "
            "share a session with this robot (simulated time); use it with ur:// or alone"
        )
    options = uri.reader()
    baud = options.integer("baud", GEN0_BAUD_RATE) if not uri.host else GEN0_BAUD_RATE
    timeout_s = options.positive("timeout_s", 0.1)
    connect_s = options.positive("connect_timeout_s", 5.0)
    options.done()
    if uri.host:
        return BotaDriverSensor(uri, uri.host, timeout_s=timeout_s, connect_timeout_s=connect_s)
    if baud <= 0:
        raise ParameterError(f"{uri.text!r}: baud must be > 0, got {baud}")
    return BotaSerialSensor(
        uri, uri.path, baud=baud, timeout_s=timeout_s, connect_timeout_s=connect_s
    )
