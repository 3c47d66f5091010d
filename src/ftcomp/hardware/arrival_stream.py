"""A sensor stream read by a thread of its own, each reading stamped on arrival, fail-stop.

The serial and socket sensors (``robotiq://``, ``bota://``) share this: a reader thread turns
the device's bytes (or its client's frames) into readings, stamps each on the host's monotonic
clock as it arrives and keeps it for :meth:`ArrivalStream.read_new`. The first fault the reader
meets (a corrupted frame, a status bit, a closed connection) ends the stream, and the next
:meth:`ArrivalStream.read` or :meth:`ArrivalStream.read_new` raises
:class:`~ftcomp.errors.HardwareError` naming it (``sensor fault: ...``); so does silence longer
than ``timeout_s``. A reading is never made from a frame that failed its check.
"""

from __future__ import annotations

import collections
import math
import threading
import time
from types import TracebackType
from typing import Any, Final, Self

import numpy as np

from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.protocols import WrenchSample
from ftcomp.hardware.registry import Uri

__all__ = ["RATE_MIN_READINGS", "RATE_MIN_SPAN_S", "ArrivalStream", "import_serial", "mean_rate_hz"]

#: Readings kept for :meth:`ArrivalStream.read_new` between two calls.
_BACKLOG: Final = 20_000
#: Readings a mean rate needs (:func:`mean_rate_hz`).
RATE_MIN_READINGS: Final = 10
#: The time a mean rate spans at least [s] (:func:`mean_rate_hz`): a stream's first readings
#: come late by a few milliseconds (a socket's or a serial port's first wake-up; a sensor on an
#: absolute schedule then catches up), which over ten readings of a 250 Hz Net F/T stand-in read
#: 279.5 Hz (a clean clone's test, 2026-12-02); over 0.2 s the same 4 ms is 2 %.
RATE_MIN_SPAN_S: Final = 0.2


def mean_rate_hz(count: int, first_ns: int, last_ns: int) -> float:
    """The mean rate of ``count`` samples stamped from ``first_ns`` to ``last_ns`` [Hz]; NaN
    with fewer than :data:`RATE_MIN_READINGS` or over less than :data:`RATE_MIN_SPAN_S`."""
    span_ns = last_ns - first_ns
    if count < RATE_MIN_READINGS or span_ns < RATE_MIN_SPAN_S * 1e9:
        return math.nan
    return (count - 1) * 1e9 / span_ns


def import_serial(what: str, extra: str) -> Any:
    """The ``serial`` module (pyserial), or a ParameterError naming the extra to install."""
    try:
        import serial
    except ImportError:
        raise ParameterError(
            f"{what} needs the pyserial package: pip install 'ftcomp[{extra}]'"
        ) from None
    return serial


class ArrivalStream:
    """The reading machinery of a streaming sensor (module docstring). A subclass implements
    :meth:`_open` (connect and start streaming), :meth:`_receive` (the reader thread's loop
    while :attr:`running`: call :meth:`_keep` per reading, raise HardwareError on a fault) and
    :meth:`_shutdown` (stop streaming and disconnect).

    Args:
        uri: the parsed URI (for messages).
        timeout_s: silence longer than this ends the stream with a fault [s].
        connect_timeout_s: longest wait for the first reading [s].
    """

    def __init__(self, uri: Uri, *, timeout_s: float, connect_timeout_s: float) -> None:
        self.uri = uri
        self._timeout_ns = round(timeout_s * 1e9)
        self._connect_timeout_s = connect_timeout_s
        self._lock = threading.Lock()
        self._arrived = threading.Event()
        self._backlog: collections.deque[WrenchSample] = collections.deque(maxlen=_BACKLOG)
        self._newest: WrenchSample | None = None
        self._fault: str | None = None
        self._thread: threading.Thread | None = None
        #: Whether the stream runs (the reader thread loops while it does).
        self.running = False
        #: Readings received since the stream started.
        self.received = 0
        self._first_ns: int | None = None

    # ------------------------------------------------------------ for subclasses
    def _open(self) -> None:
        raise NotImplementedError

    def _receive(self) -> None:
        raise NotImplementedError

    def _shutdown(self) -> None:
        raise NotImplementedError

    def _keep(self, stamp_ns: int, wrench: np.ndarray, extras: tuple[float, ...] = ()) -> None:
        """Keep one reading (a fresh float (6,) array, N and N*m, owned from now on) and the
        values of the sensor's extra channels in the same frame
        (:class:`~ftcomp.hardware.protocols.ReportsExtraChannels`)."""
        sample = WrenchSample.owning(stamp_ns, wrench, extras)
        with self._lock:
            self._backlog.append(sample)
            self._newest = sample
            self.received += 1
            if self._first_ns is None:
                self._first_ns = stamp_ns
        self._arrived.set()

    @property
    def sample_rate_hz(self) -> float:
        """The readings' mean rate since the stream started [Hz]; NaN before
        :data:`RATE_MIN_READINGS` have come over :data:`RATE_MIN_SPAN_S`
        (:class:`~ftcomp.hardware.protocols.ReportsRate`)."""
        with self._lock:
            first, newest, received = self._first_ns, self._newest, self.received
        if first is None or newest is None:
            return math.nan
        return mean_rate_hz(received, first, newest.t_ns)

    # ------------------------------------------------------------ lifecycle
    def __enter__(self) -> Self:
        """Connect, start the stream and wait for its first reading."""
        try:
            self._open()
        except HardwareError as exc:
            raise HardwareError(f"{self.uri.text!r}: {exc}") from None
        self.running = True
        self._thread = threading.Thread(target=self._reader, name=self.uri.scheme, daemon=True)
        self._thread.start()
        if not self._arrived.wait(self._connect_timeout_s) or self._newest is None:
            fault = self._fault
            self.close()
            raise HardwareError(
                f"{self.uri.text!r}: no reading within {self._connect_timeout_s:g} s"
                + (f" ({fault})" if fault else "; is the sensor powered and streaming?")
            )
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Stop the stream and close."""
        self.close()

    def close(self) -> None:
        """Stop the stream and disconnect (idempotent)."""
        if self.running:
            self.running = False
            if self._thread is not None:
                self._thread.join(1.0)
            self._shutdown()

    def _reader(self) -> None:
        try:
            self._receive()
        except HardwareError as exc:
            with self._lock:
                self._fault = str(exc)
            self._arrived.set()

    # ------------------------------------------------------------ reading
    def _raise_if_faulted(self) -> None:
        if self._fault is not None:
            raise HardwareError(f"{self.uri.text!r}: sensor fault: {self._fault}")
        if not self.running:
            raise HardwareError(f"{self.uri.text!r}: the stream is closed")

    def read(self) -> WrenchSample:
        """The newest reading (the same again until a newer one arrives).

        Raises:
            HardwareError: the stream faulted, or has been silent for longer than
                ``timeout_s``.
        """
        with self._lock:
            self._raise_if_faulted()
            newest = self._newest
        assert newest is not None  # __enter__ waited for the first
        silent_ns = time.monotonic_ns() - newest.t_ns
        if silent_ns > self._timeout_ns:
            raise HardwareError(
                f"{self.uri.text!r}: sensor fault: no reading for {silent_ns * 1e-9:.2f} s"
            )
        return newest

    def read_new(self) -> list[WrenchSample]:
        """Every reading since the previous call, oldest first.

        Raises:
            HardwareError: the stream faulted.
        """
        with self._lock:
            self._raise_if_faulted()
            new = list(self._backlog)
            self._backlog.clear()
        return new
