"""The twin's Robotiq FT 300 faces: the URCap's TCP stream and the sensor's Modbus RTU stream.

- :class:`RobotiqUrcapFace` (``--sensor ft300-urcap``): what a UR controller with Robotiq's
  URCap serves on TCP port 63351 of its address: ASCII lines ``(fx , fy , fz , mx , my , mz)``
  [N, N*m], one per reading, to every client connected.
- :class:`RobotiqRtuFace` (``--sensor ft300-rtu``): the sensor on its serial line, a pty pair
  (:class:`~ftcomp.twin.serial_pty.PtyPair`) whose slave path the client opens. It answers a
  Modbus RTU "write single register" to 410 with 0x0200 (slave 9, CRC checked, echoed as the
  sensor does) by streaming 16-byte frames (:func:`~ftcomp.hardware.robotiq.stream_frame`),
  and stops on a run of 0xFF bytes.

Both send each of the wrist sensor's samples at the face's rate (the FT 300's 100 Hz), rounded
to the protocol's resolution (0.01 N, 0.001 N*m), as the twin's loop pushes them.

Faults (declared in :mod:`ftcomp.hardware.devices`): ``ft300-frozen`` (the last reading
repeated), ``ft300-overrange`` (Fz beyond the rated 300 N), ``urcap-garbled`` (a line cut
short), ``urcap-disconnect`` (the controller closes the stream), ``network-loss`` (the URCap's
stream goes silent with the robot's), ``rtu-crc`` (a frame with a wrong CRC), ``rtu-disconnect``
(the USB adapter unplugged).
"""

from __future__ import annotations

import contextlib
import socket
import threading
from collections.abc import Sequence
from typing import Final

import numpy as np

from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import WrenchSample
from ftcomp.hardware.robotiq import (
    FORCE_N_PER_COUNT,
    SLAVE_ID,
    STREAM_REGISTER,
    STREAM_START,
    TORQUE_NM_PER_COUNT,
    URCAP_PORT,
    crc16_modbus,
    stream_frame,
    urcap_line,
    write_register_request,
)
from ftcomp.twin.serial_pty import PtyPair

__all__ = ["RobotiqRtuFace", "RobotiqUrcapFace"]

_COUNTS_PER_UNIT: Final = np.repeat([1.0 / FORCE_N_PER_COUNT, 1.0 / TORQUE_NM_PER_COUNT], 3)
#: The overrange fault's Fz [N]: beyond the rated 300 N, within int16's 327.67 N.
_OVERRANGE_FZ_N: Final = 310.0
#: A run of this many 0xFF bytes stops the stream (the manual asks for about 50).
_STOP_RUN: Final = 16


def _counts(samples: Sequence[WrenchSample]) -> list[list[int]]:
    """The samples in the protocol's counts (rint halves to even), clipped to int16."""
    wrenches = np.reshape([s.wrench_sensor for s in samples], (-1, 6))
    counts = np.clip(np.rint(wrenches * _COUNTS_PER_UNIT), -32768, 32767)
    return counts.astype(np.int64).tolist()


class _Faults:
    """What a fault changes in the readings sent: frozen values, an overrange."""

    def __init__(self) -> None:
        self.frozen: list[int] | None = None
        self.overrange = False
        self.last: list[int] = [0] * 6

    def apply(self, counts: list[list[int]]) -> list[list[int]]:
        out = []
        for c in counts:
            if self.frozen is not None:
                c = self.frozen
            elif self.overrange:
                c = [*c[:2], round(_OVERRANGE_FZ_N / FORCE_N_PER_COUNT), *c[3:]]
            self.last = c
            out.append(c)
        return out


class RobotiqUrcapFace:
    """A UR controller's URCap stream of an FT 300 (module docstring; a
    :class:`~ftcomp.twin.faces.SensorFace`).

    Args:
        host: the controller's loopback address (TCP 63351).
        rate_hz: the readings' rate [Hz] (the wrist sensor's samples arrive at it).
        realtime: unused (no sender of its own: lines are sent as the loop pushes them).

    Raises:
        ParameterError: the port cannot be bound.
    """

    def __init__(self, host: str, *, rate_hz: float, realtime: bool) -> None:
        self.host = host
        try:
            self.listener = socket.create_server((host, URCAP_PORT))
        except OSError as exc:
            raise ParameterError(f"sensor_host: cannot bind {host}:{URCAP_PORT}: {exc}") from None
        self.clients: list[socket.socket] = []
        self.lock = threading.Lock()
        self.faults = _Faults()
        self.silent = False
        self.garble = False
        self.lines = 0
        threading.Thread(target=self._accept, name="urcap-accept", daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                conn, _ = self.listener.accept()
            except OSError:
                return
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            with self.lock:
                self.clients.append(conn)

    def uri(self) -> str:
        return f"robotiq://{self.host}"

    def push(self, samples: Sequence[WrenchSample]) -> None:
        if not samples or self.silent:
            return
        with self.lock:
            clients = list(self.clients)
        if not clients:
            return
        counts = self.faults.apply(_counts(samples))
        data = b"".join(urcap_line(np.multiply(c, 1.0 / _COUNTS_PER_UNIT)) for c in counts)
        if self.garble:
            self.garble = False
            data = data[: len(data) // 2] + b"\n" + data
        for conn in clients:
            try:
                conn.sendall(data)
            except OSError:
                with self.lock:
                    self.clients.remove(conn)
        self.lines += len(counts)

    def inject(self, fault: str) -> None:
        if fault == "ft300-frozen":
            self.faults.frozen = self.faults.last
        elif fault == "ft300-overrange":
            self.faults.overrange = True
        elif fault == "urcap-garbled":
            self.garble = True
        elif fault == "urcap-disconnect":
            self.close()
        else:  # network-loss
            self.silent = True

    def served(self) -> str:
        return f"{self.lines} URCap lines"

    def close(self) -> None:
        with self.lock:
            socks, self.clients = [self.listener, *self.clients], []
        for sock in socks:
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            with contextlib.suppress(OSError):
                sock.close()


class RobotiqRtuFace:
    """An FT 300 on its serial line, Modbus RTU stream mode over a pty pair (module docstring;
    a :class:`~ftcomp.twin.faces.SensorFace`).

    Args:
        host: unused (a serial device has no address; the twin's sensor host stays unbound).
        rate_hz: the frames' rate [Hz] (the wrist sensor's samples arrive at it).
        realtime: unused (frames are written as the loop pushes them).
    """

    def __init__(self, host: str, *, rate_hz: float, realtime: bool) -> None:
        self.pty = PtyPair()
        self.faults = _Faults()
        self.streaming = False
        self.corrupt = False
        self.frames = 0
        self.requests = 0
        self._reader = threading.Thread(target=self._listen, name="ft300-rtu", daemon=True)
        self._reader.start()

    def _listen(self) -> None:
        """The device's side of the line: a start request streams, a run of 0xFF stops."""
        request = write_register_request(SLAVE_ID, STREAM_REGISTER, STREAM_START)
        pending = b""
        while not self.pty.closed:
            data = self.pty.read(0.05)
            if not data:
                continue
            pending = (pending + data)[-64:]
            if b"\xff" * _STOP_RUN in pending:
                self.streaming = False
                pending = pending.rsplit(b"\xff", 1)[1]
            at = pending.find(request[:6])
            if at >= 0 and len(pending) >= at + 8:
                frame = pending[at : at + 8]
                if int.from_bytes(frame[6:], "little") == crc16_modbus(frame[:6]):
                    self.requests += 1
                    self.pty.write(frame)  # the sensor echoes a write single register
                    self.streaming = True
                pending = pending[at + 8 :]

    def uri(self) -> str:
        return f"robotiq://{self.pty.path}"

    def push(self, samples: Sequence[WrenchSample]) -> None:
        if not samples or not self.streaming:
            return
        counts = self.faults.apply(_counts(samples))
        frames = [stream_frame(c) for c in counts]
        if self.corrupt:
            self.corrupt = False
            bad = bytearray(frames[0])
            bad[-1] ^= 0x5A
            frames[0] = bytes(bad)
        self.pty.write(b"".join(frames))
        self.frames += len(frames)

    def inject(self, fault: str) -> None:
        if fault == "ft300-frozen":
            self.faults.frozen = self.faults.last
        elif fault == "ft300-overrange":
            self.faults.overrange = True
        elif fault == "rtu-crc":
            self.corrupt = True
        else:  # rtu-disconnect
            self.pty.close()

    def served(self) -> str:
        return f"{self.frames} FT 300 frames ({self.pty.dropped} bytes dropped)"

    def close(self) -> None:
        self.pty.close()
        self._reader.join(1.0)
