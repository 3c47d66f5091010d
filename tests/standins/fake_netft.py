"""A fake ATI Net F/T on one loopback address: HTTP configuration and RDT over UDP.

Written from ATI's published Net F/T protocol:

- HTTP ``GET /netftapi2.xml``: the configuration, with ``cfgcpf`` / ``cfgcpt`` (counts per force
  and torque unit) and ``scfgfu`` / ``scfgtu`` (the units' labels).
- RDT over UDP: an 8-byte request, ``uint16 0x1234, uint16 command, uint32 sample count``
  (command 2 starts real-time streaming, 0 means without end; 0 stops; 0x42 sets the software
  bias); each reply record is 36 bytes, ``uint32 rdt_sequence, uint32 ft_sequence, uint32 status,
  int32 Fx, Fy, Fz, Tx, Ty, Tz`` in counts, all big-endian. ``rdt_sequence`` numbers the records
  of one request from 1; ``ft_sequence`` counts the sensor's own samples.

Run as ``python -m standins.fake_netft HOST RDT_PORT HTTP_PORT SCENARIO_JSON``; prints
``ready`` once it listens and exits by itself after ``scenario.max_s``.
"""

from __future__ import annotations

import socket
import struct
import sys
import threading
import time
from collections.abc import Callable

import numpy as np

from ftcomp.twin.netft import configuration_page, rdt_requests, serve_configuration
from standins.scenario import Scenario

_RECORD = struct.Struct(">III6i")
_STOP, _START, _BIAS = 0x0000, 0x0002, 0x0042
_SERIOUS_STATUS = 0x80020000


class _Rdt:
    """The UDP side: who asked for the stream, and the bias to subtract."""

    def __init__(self, sock: socket.socket, on_first_start: Callable[[], None]) -> None:
        self.sock = sock
        self.on_first_start = on_first_start
        self.peer: tuple[str, int] | None = None
        self.rdt_sequence = 0
        self.bias = [0] * 6
        self.bias_requested = False
        self.started_at: float | None = None  # when streaming was first asked for
        self.lock = threading.Lock()

    def listen(self) -> None:
        for addr, command, _count in rdt_requests(self.sock):
            with self.lock:
                if command == _START:
                    self.peer, self.rdt_sequence = addr, 0
                    if self.started_at is None:
                        self.started_at = time.monotonic()
                        self.on_first_start()
                elif command == _STOP:
                    self.peer = None
                elif command == _BIAS:
                    self.bias_requested = True


def serve(host: str, rdt_port: int, http_port: int, s: Scenario) -> None:
    """Serve until ``s.max_s`` has passed."""
    http = socket.socket()
    http.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    http.bind((host, http_port))
    page = configuration_page(s.counts_per_force, s.counts_per_torque, s.force_unit, s.torque_unit)
    serve_configuration(http, page)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind((host, rdt_port))
    rdt = _Rdt(sock, s.start_timeline)
    threading.Thread(target=rdt.listen, daemon=True).start()
    print("ready", flush=True)
    rng = np.random.default_rng(s.seed)
    period = 1.0 / s.rate_hz
    start = time.monotonic()
    ft_sequence = 0
    while True:
        ft_sequence += 1
        due = start + ft_sequence * period
        now = time.monotonic()
        if now - start > s.max_s:
            return
        if due > now:
            time.sleep(due - now)
        t = s.elapsed()
        counts, _moving = s.wrench_counts(t, rng)
        with rdt.lock:
            if rdt.bias_requested:
                rdt.bias, rdt.bias_requested = list(counts), False
            peer = rdt.peer
            if peer is None:
                continue
            rdt.rdt_sequence += 1
            seq = rdt.rdt_sequence
            bias = rdt.bias
            streaming_s = time.monotonic() - (rdt.started_at or 0.0)
        if s.silent_after_s is not None and streaming_s >= s.silent_after_s:
            continue
        if s.lose_every and seq % s.lose_every == 0:
            continue  # lost on the way
        faulty = s.fault_after_s is not None and streaming_s >= s.fault_after_s
        status = _SERIOUS_STATUS if faulty else 0
        biased = [c - b for c, b in zip(counts, bias, strict=True)]
        sock.sendto(_RECORD.pack(seq, ft_sequence, status, *biased), peer)


if __name__ == "__main__":
    serve(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), Scenario.from_json(sys.argv[4]))
