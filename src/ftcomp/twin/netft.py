"""The twin's ATI Net F/T, in a process of its own (a device of its own, with its own clock).

Written from ATI's published Net F/T protocol: HTTP ``GET /netftapi2.xml`` (counts per force
and torque unit, the units' labels) and RDT over UDP 49152: an 8-byte request ``uint16 0x1234,
uint16 command, uint32 sample count`` (2 starts real-time streaming, 3 buffered streaming,
0 stops, 0x42 sets the software bias; a count of 0 streams without end); records of 36 bytes
``uint32 rdt_sequence, uint32 ft_sequence, uint32 status, int32 Fx, Fy, Fz, Tx, Ty, Tz`` in
counts, big-endian. ``rdt_sequence`` numbers the records of one request from 1,
``ft_sequence`` counts the sensor's own samples.

The cell's loop (:mod:`ftcomp.twin.serve`) hands the wrist sensor's samples to
:class:`NetFtProcess` every cycle; the process sends them one record each, evenly spaced at
the sensor's rate, from its own interpreter, so the records keep their period however busy the
physics and the RTDE clients keep the cell's process: each at the time the cell made it plus
:data:`_DELAY_S` (a jitter buffer for the cell's stalls), a sample later than
:data:`_MAX_LATE_S` past its time dropped (never a backlog).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import socket
import struct
import threading
import time
from collections.abc import Iterator, Sequence
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from multiprocessing.connection import Connection
from typing import Final

from ftcomp.errors import ParameterError
from ftcomp.hardware.pacing import LOOP_PRIORITY

__all__ = [
    "COUNTS_PER_FORCE",
    "COUNTS_PER_TORQUE",
    "NETFT_HTTP_PORT",
    "RDT_PORT",
    "RT_PRIORITY",
    "SERIOUS_STATUS",
    "NetFtProcess",
    "NetFtServer",
    "bind_socket",
    "configuration_page",
    "rdt_requests",
    "realtime_priority",
    "serve_configuration",
]

RDT_PORT: Final = 49152
NETFT_HTTP_PORT: Final = 80
#: The Net F/T's calibration as its configuration page reports it (counts per N, per N*m).
COUNTS_PER_FORCE: Final = 1_000_000.0
COUNTS_PER_TORQUE: Final = 1_000_000.0
#: Status word of a failing sensor (ATI: bit 31, a serious fault, plus the gauge-saturation bit).
SERIOUS_STATUS: Final = 0x80020000
_RECORD: Final = struct.Struct(">III6i")
_REQUEST: Final = struct.Struct(">HHI")
_STOP, _START, _BUFFERED, _BIAS = 0x0000, 0x0002, 0x0003, 0x0042
#: Each sample is sent this long after the cell made it [s]: a jitter buffer that hides a
#: stall of the cell's loop shorter than it (a real Net F/T has no stalls to hide).
_DELAY_S: Final = 0.003
#: A sample later than this past its time is dropped, not sent [s].
_MAX_LATE_S: Final = 0.010
#: How often the Net F/T's HTTP server looks for a shutdown [s].
_HTTP_POLL_S: Final = 0.02


def configuration_page(
    counts_per_force: float, counts_per_torque: float, force_unit: str, torque_unit: str
) -> bytes:
    """The Net F/T's ``netftapi2.xml``: counts per force and torque unit, the units' labels."""
    return (
        '<?xml version="1.0" encoding="utf-8"?>\n<netft>'
        "<prodname>ftcomp Net F/T</prodname>"
        f"<cfgcpf>{counts_per_force:g}</cfgcpf><cfgcpt>{counts_per_torque:g}</cfgcpt>"
        f"<scfgfu>{force_unit}</scfgfu><scfgtu>{torque_unit}</scfgtu></netft>\n"
    ).encode()


def serve_configuration(http: socket.socket, page: bytes) -> ThreadingHTTPServer:
    """Serve ``GET /netftapi2.xml`` on a bound TCP socket, on a daemon thread; returns the
    server (``shutdown()`` and ``server_close()`` end it)."""

    class Handler(BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            if self.path != "/netftapi2.xml":
                self.send_error(404)
                return
            self.send_response(200)
            self.send_header("Content-Type", "text/xml")
            self.send_header("Content-Length", str(len(page)))
            self.end_headers()
            self.wfile.write(page)

        def log_message(self, *args: object) -> None:
            pass

    class Server(ThreadingHTTPServer):
        def server_bind(self) -> None:  # the socket is bound already
            self.server_address = http.getsockname()

    server = Server(http.getsockname(), Handler, bind_and_activate=False)
    server.socket.close()
    server.socket = http
    http.listen(8)
    # serve_forever looks for a shutdown every poll_interval: at its default, 0.5 s, closing the
    # Net F/T took half a second of every twin's stop (about 35 s of a test run's 97 twins).
    threading.Thread(
        target=server.serve_forever, kwargs={"poll_interval": _HTTP_POLL_S}, daemon=True
    ).start()
    return server


class NetFtServer:
    """The Net F/T's RDT side: who streams, the software bias, and one record per sample.

    Args:
        sock: the bound UDP socket (port 49152).
        http: the bound TCP socket for the configuration page (port 80).
    """

    def __init__(
        self, sock: socket.socket, http: socket.socket, rate_hz: float, realtime: bool = False
    ) -> None:
        self.sock = sock
        self.realtime = realtime
        self.rate_hz = rate_hz
        self.lock = threading.Lock()
        self.ready = threading.Condition()
        self.queue: list[tuple[list[int], int, float]] = []
        self.closed = False
        self.peer: tuple[str, int] | None = None
        self.remaining = 0  # records left of a finite request (0: without end)
        self.rdt_sequence = 0
        self.ft_sequence = 0
        self.bias = [0] * 6
        self.bias_requested = False
        self.buffered = False
        self.batch: list[bytes] = []
        self.lose_next = 0
        self.silent = False
        self.frozen: list[int] | None = None
        self.last: list[int] | None = None
        self.sent = 0
        self.http = serve_configuration(
            http, configuration_page(COUNTS_PER_FORCE, COUNTS_PER_TORQUE, "N", "Nm")
        )
        threading.Thread(target=self._listen, daemon=True).start()
        threading.Thread(target=self._sender, daemon=True).start()

    def inject(self, fault: str) -> None:
        """``sensor-frozen``: repeat the last reading from now on (status healthy);
        ``rdt-loss``: lose the next 200 records on the way; ``network-loss``: lose them all."""
        with self.lock:
            if fault == "sensor-frozen":
                self.frozen = self.last
            elif fault == "rdt-loss":
                self.lose_next = 200
            elif fault == "network-loss":
                self.silent = True

    def _listen(self) -> None:
        for addr, command, count in rdt_requests(self.sock):
            with self.lock:
                if command in (_START, _BUFFERED):
                    self.peer, self.rdt_sequence, self.remaining = addr, 0, count
                    self.buffered = command == _BUFFERED
                    self.batch = []
                elif command == _STOP:
                    self.peer = None
                elif command == _BIAS:
                    self.bias_requested = True

    def push(
        self, counts: Sequence[Sequence[int]], status: int = 0, made_at: float | None = None
    ) -> None:
        """Queue the new sensor samples (counts, before the software bias), the newest made
        at ``made_at`` (host monotonic clock [s]; default now), the others one sensor period
        apart before it. The sender thread sends each one record at its time plus
        :data:`_DELAY_S`, so evenly spaced at the sensor's rate as the device does (not in
        bursts of a physics cycle)."""
        period = 1.0 / self.rate_hz
        newest = time.monotonic() if made_at is None else made_at
        n = len(counts)
        with self.ready:
            self.queue.extend(
                (list(c), status, newest - (n - 1 - i) * period + _DELAY_S)
                for i, c in enumerate(counts)
            )
            self.ready.notify()

    def _sender(self) -> None:
        if self.realtime:
            realtime_priority(RT_PRIORITY + 1)
        while not self.closed:
            with self.ready:
                while not self.queue and not self.closed:
                    self.ready.wait(0.1)
                if self.closed:
                    return
                # A sample more than _MAX_LATE_S past its time (the cell or this sender was
                # held back) is not sent: a real Net F/T sends the sample it has now, never a
                # backlog. Sending every queued sample at the rate kept each later record as
                # late (0.8 s seen on a loaded host: run pressed the book with 59 N).
                now = time.monotonic()
                skipped = 0
                while len(self.queue) > 1 and now - self.queue[0][2] > _MAX_LATE_S:
                    del self.queue[0]
                    skipped += 1
                sample, status, due = self.queue.pop(0)
            wait = due - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            self._send_sample(sample, status, skipped)

    def _send_sample(self, sample: list[int], status: int, skipped: int = 0) -> None:
        """One record to the streaming client (with the bias, losses and freezes applied);
        ``skipped`` samples were dropped before it (``ft_sequence`` counts them)."""
        with self.lock:
            self.ft_sequence += 1 + skipped
            if self.frozen is None:
                self.last = list(sample)
            if self.bias_requested:
                self.bias, self.bias_requested = list(sample), False
            if self.peer is None:
                return
            self.rdt_sequence += 1
            values = self.frozen if self.frozen is not None else sample
            record = _RECORD.pack(
                self.rdt_sequence,
                self.ft_sequence,
                status,
                *(c - b for c, b in zip(values, self.bias, strict=True)),
            )
            if self.silent:
                return
            if self.lose_next > 0:
                self.lose_next -= 1
                return
            if self.buffered:
                self.batch.append(record)
                if len(self.batch) >= 40:
                    self._send(b"".join(self.batch))
                    self.batch = []
            else:
                self._send(record)
            if self.remaining:
                self.remaining -= 1
                if self.remaining == 0:
                    self.peer = None

    def _send(self, data: bytes) -> None:
        if self.peer is None:
            return
        try:
            self.sock.sendto(data, self.peer)
            self.sent += 1
        except OSError:
            self.peer = None

    def close(self) -> None:
        """Stop serving."""
        with self.ready:
            self.closed = True
            self.ready.notify()
        self.http.shutdown()
        self.http.server_close()
        self.sock.close()


#: The SCHED_FIFO priority the twin's cell loop asks for; its Net F/T sender asks for one more.
#: Both stay below a live loop's (:data:`ftcomp.hardware.pacing.LOOP_PRIORITY`, 5) and above
#: every ordinary process: the twin stands for hardware outside the machine, which never takes
#: the CPU from the loop that controls it (at 12 and 11, above the loop, the twin's bursts
#: showed in the loop's compute time), yet a busy machine's ordinary processes cannot hold the
#: twin off its own rates.
RT_PRIORITY: Final = LOOP_PRIORITY - 2


def realtime_priority(priority: int) -> bool:
    """Ask for SCHED_FIFO at ``priority`` for the calling thread (as ur_rtde does for its
    loops); whether it was granted (not without the privilege, nor off Linux)."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except (AttributeError, OSError):
        return False
    return True


def rdt_requests(sock: socket.socket) -> Iterator[tuple[tuple[str, int], int, int]]:
    """Every well-formed RDT request arriving on ``sock``: ``(sender, command, sample count)``
    (a request that is too short or lacks the 0x1234 header is ignored); ends when the socket
    closes."""
    while True:
        try:
            data, addr = sock.recvfrom(64)
        except OSError:
            return
        if len(data) < _REQUEST.size:
            continue
        header, command, count = _REQUEST.unpack(data[: _REQUEST.size])
        if header == 0x1234:
            yield addr, command, count


def bind_socket(host: str, port: int, kind: int = socket.SOCK_STREAM) -> socket.socket:
    """A socket bound to ``host:port`` (TCP with SO_REUSEADDR, or UDP).

    Raises:
        ParameterError: the port cannot be bound (busy, or the address is not local).
    """
    sock = socket.socket(socket.AF_INET, kind)
    if kind == socket.SOCK_STREAM:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as exc:
        sock.close()
        raise ParameterError(f"cannot bind {host}:{port}: {exc.strerror}") from None
    return sock


def _child(host: str, rate_hz: float, realtime: bool, conn: Connection) -> None:
    """The Net F/T process: bind, say so, then serve what the cell's loop sends."""
    if realtime:
        # This thread reads the cell's samples from the pipe, and the server's threads
        # inherit its priority: held off by an ordinary process (or holding the interpreter's
        # lock when one preempted it), it let the pipe fill and the cell's loop block on it.
        realtime_priority(RT_PRIORITY + 1)
    try:
        rdt = bind_socket(host, RDT_PORT, socket.SOCK_DGRAM)
        try:
            http = bind_socket(host, NETFT_HTTP_PORT, socket.SOCK_STREAM)
        except ParameterError:
            rdt.close()
            raise
    except ParameterError as exc:
        conn.send(("error", str(exc)))
        return
    server = NetFtServer(rdt, http, rate_hz, realtime)
    conn.send(("bound", ""))
    try:
        while True:
            kind, payload = conn.recv()
            if kind == "samples":
                counts, status, made_at = payload
                server.push(counts, status, made_at)
            elif kind == "fault":
                server.inject(payload)
            elif kind == "stop":
                break
    except (EOFError, OSError):
        pass
    finally:
        sent = server.sent
        server.close()
        with contextlib.suppress(OSError):
            conn.send(("sent", sent))


class NetFtProcess:
    """The Net F/T in its own process, bound to ``host`` (UDP 49152, TCP 80).

    Args:
        host: its loopback address.
        rate_hz: the sensor's output rate [Hz].
        realtime: ask for SCHED_FIFO for the sender.

    Raises:
        ParameterError: a port cannot be bound (nothing is left bound).
    """

    def __init__(self, host: str, rate_hz: float, realtime: bool) -> None:
        context = multiprocessing.get_context("spawn")
        self.conn, child_conn = context.Pipe()
        self.proc = context.Process(
            target=_child, args=(host, rate_hz, realtime, child_conn), daemon=True
        )
        self.proc.start()
        child_conn.close()
        if not self.conn.poll(30.0):
            self.proc.kill()
            raise ParameterError(f"the Net F/T on {host} did not start")
        kind, message = self.conn.recv()
        if kind != "bound":
            self.proc.join(5)
            raise ParameterError(message)
        self.sent = 0

    def push(self, counts: Sequence[Sequence[int]], status: int) -> None:
        """Hand the cycle's new samples (counts, before bias), made now, to the sensor."""
        if counts:
            self.conn.send(("samples", ([list(c) for c in counts], status, time.monotonic())))

    def inject(self, fault: str) -> None:
        """A sensor fault from now on: ``sensor-frozen``, ``rdt-loss`` or ``network-loss``."""
        self.conn.send(("fault", fault))

    def close(self) -> None:
        """Stop the process; :attr:`sent` holds the records it sent."""
        try:
            self.conn.send(("stop", None))
            if self.conn.poll(5.0):
                kind, value = self.conn.recv()
                if kind == "sent":
                    self.sent = int(value)
        except (OSError, EOFError):
            pass
        self.proc.join(5)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join(5)
        self.conn.close()
