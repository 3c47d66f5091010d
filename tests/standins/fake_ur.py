"""A fake UR controller's RTDE output side on one loopback address (TCP port 30004), serving a
scripted scenario instead of the simulated cell.

The wire protocol is the twin's own (:class:`ftcomp.twin.rtde.RtdeSession`, written from
Universal Robots' published RTDE protocol, version 2): there is one RTDE server in ftcomp, and
this stand-in only decides what each data package holds. Every 2 ms a package goes to every
client that started its stream: the scenario's TCP pose on its timeline, joints that follow
it, and ``ft_raw_wrench`` / ``actual_TCP_force`` from the scenario's tool model (identity
mount) with seeded noise. With ``silent_after_s`` the data stops that long after a client
started its stream (0: the controller answers the handshake but never sends data). The
URScript interface (what ``RTDEControlInterface`` needs) is not served: the control path is
tested against the twin (``tests/devices``) and URSim (docs/hardware.md).

Run as ``python -m standins.fake_ur HOST SCENARIO_JSON``; prints ``ready`` once it listens and
exits by itself after ``scenario.max_s``.
"""

from __future__ import annotations

import socket
import sys
import threading
import time

import numpy as np

from ftcomp.twin.rtde import RtdeSession
from standins.scenario import Scenario

PORT = 30004
VERSION = (5, 11, 0, 0)
_PERIOD_S = 0.002
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


def _serve_sessions(server: socket.socket, sessions: list[RtdeSession], until: float) -> None:
    server.settimeout(0.2)
    while time.monotonic() < until:
        try:
            conn, _ = server.accept()
        except TimeoutError:
            continue
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        session = RtdeSession(conn, VERSION, lambda package: None)
        sessions.append(session)
        threading.Thread(target=session.serve, daemon=True).start()


def serve(host: str, s: Scenario) -> None:
    """Accept RTDE clients and stream the scenario to them until ``s.max_s`` has passed."""
    server = socket.socket()
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind((host, PORT))
    server.listen(4)
    print("ready", flush=True)
    start = time.monotonic()
    rng = np.random.default_rng(s.seed + 1)
    sessions: list[RtdeSession] = []
    threading.Thread(
        target=_serve_sessions, args=(server, sessions, start + s.max_s), daemon=True
    ).start()
    streaming_since: float | None = None
    due = start
    while time.monotonic() - start < s.max_s:
        due += _PERIOD_S
        time.sleep(max(0.0, due - time.monotonic()))
        live = [session for session in list(sessions) if session.started]
        if not live:
            continue
        now = time.monotonic()
        streaming_since = now if streaming_since is None else streaming_since
        if s.silent_after_s is not None and now - streaming_since >= s.silent_after_s:
            continue  # the controller hangs: nothing more is sent
        t = s.elapsed()
        state = {name: _values(s, name, t, rng) for name in TYPES}
        for session in live:
            session.publish(state, {})


if __name__ == "__main__":
    serve(sys.argv[1], Scenario.from_json(sys.argv[2]))
