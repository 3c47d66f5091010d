"""A serial device of the twin: a pseudo-terminal pair, the face on its master side.

A client opens the slave's path (``/dev/pts/N``) as it opens a USB serial adapter
(``/dev/ttyUSB0``), with the same library and settings; the baud rate of a pty is only a
setting (bytes pass as fast as both sides move them), framing, CRCs and commands are the
device's. The face keeps the slave open too, raw, so the master never sees a hang-up before a
client comes; :meth:`PtyPair.close` closes both, which the client sees as a device unplugged
(its reads fail).
"""

from __future__ import annotations

import contextlib
import os
import select
import threading
import tty

__all__ = ["PtyPair"]


class PtyPair:
    """A pty pair: the device's side (:meth:`read`, :meth:`write`) and the client's path."""

    def __init__(self) -> None:
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        #: The path a client opens.
        self.path = os.ttyname(self._slave)
        self._closed = threading.Event()
        #: Bytes dropped because the client did not read them (its input buffer full).
        self.dropped = 0

    def read(self, timeout_s: float) -> bytes:
        """What the client wrote, waiting up to ``timeout_s`` [s]; b"" when nothing came or
        the pair is closed."""
        if self._closed.is_set():
            return b""
        try:
            ready, _, _ = select.select([self._master], [], [], timeout_s)
            return os.read(self._master, 4096) if ready else b""
        except (OSError, ValueError):
            return b""

    def write(self, data: bytes) -> int:
        """Send ``data`` to the client; what does not fit its buffer is dropped (as a serial
        line's receiver overruns) and counted. The bytes written."""
        if self._closed.is_set():
            return 0
        try:
            written = os.write(self._master, data)
        except BlockingIOError:
            written = 0
        except OSError:
            return 0
        self.dropped += len(data) - written
        return written

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` was called."""
        return self._closed.is_set()

    def close(self) -> None:
        """Close both sides (idempotent): the device is gone."""
        if self._closed.is_set():
            return
        self._closed.set()
        for fd in (self._slave, self._master):
            with contextlib.suppress(OSError):
                os.close(fd)
