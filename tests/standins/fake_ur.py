"""A fake UR controller's RTDE output side on one loopback address (TCP port 30004).

Written from Universal Robots' published RTDE protocol (version 2). Every package is
``uint16 size`` (header included), ``uint8 type``, payload, big-endian. The stand-in answers:

- ``V`` request protocol version (uint16) -> ``V`` uint8 accepted;
- ``v`` get controller version -> ``v`` uint32 major, minor, bugfix, build (here 5.11.0.0);
- ``O`` output setup (double frequency, comma-separated names) -> ``O`` uint8 recipe id and
  the comma-separated types, ``NOT_FOUND`` for a name it does not serve;
- ``S`` start -> ``S`` uint8 accepted, then a ``U`` data package (uint8 recipe id, the values
  in recipe order) every 1/frequency seconds; ``P`` pause -> ``P`` uint8 accepted.

With ``silent_after_s`` the data stops that long after a client started its stream (0: the
controller answers the handshake but never sends data). The input side and the URScript
interface (what ``RTDEControlInterface`` needs) are not
served: the control path is tested against URSim (docs/hardware.md). The arm follows the
scenario's TCP poses; ``ft_raw_wrench`` is the scenario's tool model in the sensor frame.

Run as ``python -m standins.fake_ur HOST SCENARIO_JSON``; prints ``ready`` once it listens and
exits by itself after ``scenario.max_s``.
"""

from __future__ import annotations

import socket
import struct
import sys
import threading
import time

import numpy as np

from standins.scenario import Scenario

PORT = 30004
VERSION = (5, 11, 0, 0)
TYPES = {
    "timestamp": "DOUBLE",
    "actual_TCP_pose": "VECTOR6D",
    "actual_q": "VECTOR6D",
    "actual_qd": "VECTOR6D",
    "actual_TCP_force": "VECTOR6D",
    "ft_raw_wrench": "VECTOR6D",
    "robot_mode": "INT32",
    "safety_mode": "INT32",
    "safety_status_bits": "UINT32",
    "robot_status_bits": "UINT32",
    "runtime_state": "UINT32",
}
_STARTED = time.monotonic()
_FORMATS = {"DOUBLE": "d", "VECTOR6D": "6d", "INT32": "i", "UINT32": "I"}


def _recv(conn: socket.socket, n: int) -> bytes:
    data = b""
    while len(data) < n:
        chunk = conn.recv(n - len(data))
        if not chunk:
            raise ConnectionError("closed")
        data += chunk
    return data


def _send(conn: socket.socket, lock: threading.Lock, kind: str, payload: bytes) -> None:
    with lock:
        conn.sendall(struct.pack(">HB", 3 + len(payload), ord(kind)) + payload)


def _values(s: Scenario, name: str, t: float, rng: np.random.Generator) -> list[float]:
    p, R_tcp, moving = s.tcp_pose(t)
    if name == "timestamp":  # the controller's uptime
        return [time.monotonic() - _STARTED]
    if name == "actual_TCP_pose":
        return [*p.tolist(), *R_tcp.as_rotvec().tolist()]
    if name == "actual_q":
        return [0.0, -1.2, 1.5, *R_tcp.as_rotvec().tolist()]
    if name == "actual_qd":
        return [0.3 if moving else 0.0] * 6
    if name in ("ft_raw_wrench", "actual_TCP_force"):
        R_base_sensor = s.mount().sensor_pose(p, R_tcp.as_matrix())[1]
        w = s.gravity_model().predict(R_base_sensor) + rng.normal(size=6) * np.repeat(s.noise, 3)
        if name == "actual_TCP_force":  # the base frame, at the TCP (identity mount here)
            w = np.concatenate([R_base_sensor @ w[:3], R_base_sensor @ w[3:]])
        return w.tolist()
    return [{"robot_mode": 7, "safety_mode": 1, "safety_status_bits": 1}.get(name, 1)]


def _session(conn: socket.socket, s: Scenario, rng: np.random.Generator) -> None:
    lock = threading.Lock()
    names: list[str] = []
    period = 0.002
    streaming = threading.Event()

    def stream() -> None:
        fmt = ">B" + "".join(_FORMATS[TYPES[n]] for n in names)
        k = 0
        start = time.monotonic()
        while streaming.is_set():
            if s.silent_after_s is not None and time.monotonic() - start >= s.silent_after_s:
                time.sleep(period)  # the controller hangs: nothing more is sent
                continue
            k += 1
            due = start + k * period
            now = time.monotonic()
            if due > now:
                time.sleep(due - now)
            t = s.elapsed()
            values: list[float] = []
            for name in names:
                values += _values(s, name, t, rng)
            try:
                _send(conn, lock, "U", struct.pack(fmt, 1, *values))
            except OSError:
                return

    try:
        while True:
            size, kind = struct.unpack(">HB", _recv(conn, 3))
            payload = _recv(conn, size - 3)
            if kind == ord("V"):
                _send(conn, lock, "V", b"\x01")
            elif kind == ord("v"):
                _send(conn, lock, "v", struct.pack(">IIII", *VERSION))
            elif kind == ord("O"):
                period = 1.0 / struct.unpack(">d", payload[:8])[0]
                names = [n for n in payload[8:].decode().split(",") if n]
                types = ",".join(TYPES.get(n, "NOT_FOUND") for n in names)
                _send(conn, lock, "O", b"\x01" + types.encode())
            elif kind == ord("S"):
                _send(conn, lock, "S", b"\x01")
                streaming.set()
                threading.Thread(target=stream, daemon=True).start()
            elif kind == ord("P"):
                streaming.clear()
                _send(conn, lock, "P", b"\x01")
            else:
                _send(conn, lock, chr(kind), b"\x00")
    except (ConnectionError, OSError):
        streaming.clear()
    finally:
        conn.close()


def serve(host: str, s: Scenario) -> None:
    """Accept RTDE clients until ``s.max_s`` has passed."""
    server = socket.socket()
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind((host, PORT))
    server.listen(4)
    server.settimeout(0.2)
    print("ready", flush=True)
    start = time.monotonic()
    rng = np.random.default_rng(s.seed + 1)
    while time.monotonic() - start < s.max_s:
        try:
            conn, _ = server.accept()
        except TimeoutError:
            continue
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        threading.Thread(target=_session, args=(conn, s, rng), daemon=True).start()


if __name__ == "__main__":
    serve(sys.argv[1], Scenario.from_json(sys.argv[2]))
