"""The twin's other sockets: UR's dashboard server and script ports, and the Net F/T.

- Dashboard (TCP 29999): one text line per request, one line per answer, as PolyScope 5
  answers them (``PolyscopeVersion``, ``get serial number``, ``is in remote control``,
  ``robotmode``, ``safetystatus``, ``programState``, ``running``, ``stop``,
  ``unlock protective stop``, ``close safety popup``, ``quit``).
- Script ports (TCP 30001, 30002, 30003): a URScript program sent as text; a complete
  top-level ``def ... end`` program starts at once.
- Net F/T, written from ATI's published protocol: HTTP ``GET /netftapi2.xml`` (counts per force
  and torque unit, the units) and RDT over UDP 49152: an 8-byte request ``uint16 0x1234,
  uint16 command, uint32 sample count`` (2 starts real-time streaming, 3 buffered streaming,
  0 stops, 0x42 sets the software bias); records of 36 bytes ``uint32 rdt_sequence,
  uint32 ft_sequence, uint32 status, int32 Fx, Fy, Fz, Tx, Ty, Tz`` in counts, big-endian.
"""

from __future__ import annotations

import socket
import struct
import threading
import time
from collections.abc import Callable, Sequence
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Final

from ftcomp.twin.controller import UrController

__all__ = [
    "COUNTS_PER_FORCE",
    "COUNTS_PER_TORQUE",
    "DASHBOARD_PORT",
    "NETFT_HTTP_PORT",
    "RDT_PORT",
    "SCRIPT_PORTS",
    "NetFtServer",
    "serve_dashboard",
    "serve_script",
]

DASHBOARD_PORT: Final = 29999
SCRIPT_PORTS: Final = (30001, 30002, 30003)
RDT_PORT: Final = 49152
NETFT_HTTP_PORT: Final = 80
#: The Net F/T's calibration as its configuration page reports it (counts per N, per N*m).
COUNTS_PER_FORCE: Final = 1_000_000.0
COUNTS_PER_TORQUE: Final = 1_000_000.0
_POLYSCOPE: Final = "URSoftware 5.11.1.108318 (Mar 22 2021)"
_RECORD: Final = struct.Struct(">III6i")
_REQUEST: Final = struct.Struct(">HHI")
_STOP, _START, _BUFFERED, _BIAS = 0x0000, 0x0002, 0x0003, 0x0042
#: Status word of a frozen or failing sensor (ATI: a serious fault, bit 31, plus the
#: gauge-saturation bit).
SERIOUS_STATUS: Final = 0x80020000


def _dashboard_answer(controller: UrController, line: str) -> str:
    request = line.strip()
    key = request.lower()
    running = controller.script_running
    stopped = controller.safety.protective_stop
    if key == "polyscopeversion":
        return _POLYSCOPE
    if key == "get serial number":
        return "20205500001"
    if key == "get robot model":
        return "UR5"
    if key == "is in remote control":
        return "true"
    if key == "robotmode":
        return "Robotmode: RUNNING"
    if key in ("safetystatus", "safetymode"):
        name = "Safetystatus" if key == "safetystatus" else "Safetymode"
        return f"{name}: {'PROTECTIVE_STOP' if stopped else 'NORMAL'}"
    if key == "programstate":
        return "PLAYING rtde_control" if running else "STOPPED <unnamed>"
    if key == "running":
        return f"Program running: {'true' if running else 'false'}"
    if key == "stop":
        controller.stop_program()
        return "Stopped"
    if key == "unlock protective stop":
        controller.unlock_protective_stop()
        return "Protective stop releasing"
    if key == "close safety popup":
        return "closing safety popup"
    if key.startswith("popup") or key == "close popup":
        return "showing popup" if key.startswith("popup") else "closing popup"
    return f"could not understand: '{request}'"


def serve_dashboard(listener: socket.socket, controller: UrController) -> None:
    """Accept dashboard clients forever (run on a daemon thread)."""

    def session(conn: socket.socket) -> None:
        with conn:
            conn.sendall(b"Connected: Universal Robots Dashboard Server\n")
            for raw in conn.makefile("rb"):
                line = raw.decode(errors="replace")
                if line.strip().lower() == "quit":
                    conn.sendall(b"Disconnected\n")
                    return
                conn.sendall((_dashboard_answer(controller, line) + "\n").encode())

    _accept_forever(listener, session)


def serve_script(listener: socket.socket, controller: UrController) -> None:
    """Accept URScript programs forever (run on a daemon thread)."""

    def session(conn: socket.socket) -> None:
        text = ""
        with conn:
            while True:
                try:
                    chunk = conn.recv(65536)
                except OSError:
                    return
                if not chunk:
                    return
                text += chunk.decode(errors="replace")
                lines = text.splitlines()
                if text.lstrip().startswith("def ") and "end" in (ln.rstrip() for ln in lines):
                    controller.start_program(text)
                    text = ""

    _accept_forever(listener, session)


def _accept_forever(listener: socket.socket, session: Callable[[socket.socket], None]) -> None:
    while True:
        try:
            conn, _ = listener.accept()
        except OSError:
            return
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        threading.Thread(target=session, args=(conn,), daemon=True).start()


def _configuration_page() -> bytes:
    return (
        '<?xml version="1.0" encoding="utf-8"?>\n<netft>'
        "<prodname>ftcomp twin Net F/T</prodname>"
        f"<cfgcpf>{COUNTS_PER_FORCE:g}</cfgcpf><cfgcpt>{COUNTS_PER_TORQUE:g}</cfgcpt>"
        "<scfgfu>N</scfgfu><scfgtu>Nm</scfgtu></netft>\n"
    ).encode()


class NetFtServer:
    """The Net F/T's RDT side: who streams, the software bias, and one record per sample.

    Args:
        sock: the bound UDP socket (port 49152).
        http: the bound TCP socket for the configuration page (port 80).
    """

    def __init__(self, sock: socket.socket, http: socket.socket, rate_hz: float) -> None:
        self.sock = sock
        self.rate_hz = rate_hz
        self.lock = threading.Lock()
        self.ready = threading.Condition()
        self.queue: list[tuple[list[int], int]] = []
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
        self.frozen: list[int] | None = None
        self.sent = 0
        page = _configuration_page()

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

        self.http = Server(http.getsockname(), Handler, bind_and_activate=False)
        self.http.socket.close()
        self.http.socket = http
        http.listen(8)
        threading.Thread(target=self.http.serve_forever, daemon=True).start()
        threading.Thread(target=self._listen, daemon=True).start()
        threading.Thread(target=self._sender, daemon=True).start()

    def _listen(self) -> None:
        while True:
            try:
                data, addr = self.sock.recvfrom(64)
            except OSError:
                return
            if len(data) < _REQUEST.size:
                continue
            header, command, count = _REQUEST.unpack(data[: _REQUEST.size])
            if header != 0x1234:
                continue
            with self.lock:
                if command in (_START, _BUFFERED):
                    self.peer, self.rdt_sequence, self.remaining = addr, 0, count
                    self.buffered = command == _BUFFERED
                    self.batch = []
                elif command == _STOP:
                    self.peer = None
                elif command == _BIAS:
                    self.bias_requested = True

    def push(self, counts: Sequence[Sequence[int]], status: int = 0) -> None:
        """Queue the new sensor samples (counts, before the software bias): the sender thread
        sends them one record each, evenly spaced at the sensor's rate, as the device does
        (not in bursts of a physics cycle)."""
        with self.ready:
            self.queue.extend((list(c), status) for c in counts)
            self.ready.notify()

    def _sender(self) -> None:
        period = 1.0 / self.rate_hz
        due = time.monotonic()
        while not self.closed:
            with self.ready:
                while not self.queue and not self.closed:
                    self.ready.wait(0.1)
                if self.closed:
                    return
                sample, status = self.queue.pop(0)
                if len(self.queue) > 8:  # far behind: drop the backlog's pacing
                    due = time.monotonic()
            self._send_sample(sample, status)
            due = max(due + period, time.monotonic() - 4 * period)
            wait = due - time.monotonic()
            if wait > 0:
                time.sleep(wait)

    def _send_sample(self, sample: list[int], status: int) -> None:
        """One record to the streaming client (with the bias, losses and freezes applied)."""
        with self.lock:
            self.ft_sequence += 1
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
