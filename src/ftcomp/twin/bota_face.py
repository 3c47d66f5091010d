"""The twin's Bota Gen0 face (``--sensor bota-gen0``): a Rokubi-style serial stream on a pty.

The sensor streams Gen0 frames (:func:`~ftcomp.hardware.bota.gen0_frame`: status, the wrench
as float32, a microsecond timestamp, the temperature, CRC-16/X-25) on a pty pair
(:class:`~ftcomp.twin.serial_pty.PtyPair`) whose slave path the client opens, one frame per
sample of the wrist sensor at the face's rate, as a Gen0 sensor in run mode streams from
power-up. The twin has no thermal model: the temperature is a constant 30 degC. The timestamp
is the sample's time on the twin's clock, in microseconds (wrapping at 2^32 as the sensor's).

Faults (declared in :mod:`ftcomp.hardware.devices`): ``bota-frozen`` (the last reading
repeated, status clean), ``bota-crc`` (one frame with a wrong CRC), ``bota-overrange`` (the
overrange bit set), ``bota-disconnect`` (the USB adapter unplugged).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

from ftcomp.hardware.bota import gen0_frame
from ftcomp.hardware.protocols import WrenchSample
from ftcomp.twin.serial_pty import PtyPair

__all__ = ["BotaGen0Face"]

#: The twin sensor's temperature [degC] (no thermal model).
TEMPERATURE_C: Final = 30.0
_OVERRANGE: Final = 0b10


class BotaGen0Face:
    """A Bota Gen0 sensor on its serial line (module docstring; a
    :class:`~ftcomp.twin.faces.SensorFace`).

    Args:
        host: unused (a serial device has no address).
        rate_hz: the frames' rate [Hz] (the wrist sensor's samples arrive at it).
        realtime: unused (frames are written as the loop pushes them).
    """

    def __init__(self, host: str, *, rate_hz: float, realtime: bool) -> None:
        self.pty = PtyPair()
        self.status = 0
        self.frozen: tuple[float, ...] | None = None
        self.last: tuple[float, ...] = (0.0,) * 6
        self.corrupt = False
        self.frames = 0

    def uri(self) -> str:
        return f"bota://{self.pty.path}"

    def push(self, samples: Sequence[WrenchSample]) -> None:
        if not samples or self.pty.closed:
            return
        frames = []
        for sample in samples:
            wrench = self.frozen if self.frozen is not None else tuple(sample.wrench_sensor)
            self.last = wrench
            stamp_us = (sample.t_ns // 1000) & 0xFFFFFFFF
            frame = gen0_frame(self.status, wrench, stamp_us, TEMPERATURE_C)
            if self.corrupt:
                self.corrupt = False
                frame = frame[:-1] + bytes([frame[-1] ^ 0x5A])
            frames.append(frame)
        self.pty.write(b"".join(frames))
        self.frames += len(frames)

    def inject(self, fault: str) -> None:
        if fault == "bota-frozen":
            self.frozen = self.last
        elif fault == "bota-crc":
            self.corrupt = True
        elif fault == "bota-overrange":
            self.status |= _OVERRANGE
        else:  # bota-disconnect
            self.pty.close()

    def served(self) -> str:
        return f"{self.frames} Gen0 frames ({self.pty.dropped} bytes dropped)"

    def close(self) -> None:
        self.pty.close()
