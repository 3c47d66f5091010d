"""A toy robot and a toy sensor, each a live backend and a twin face, declared in one module.

``tests/devices/test_toy_devices.py`` copies this file to a temporary folder and names it in
``FTCOMP_DEVICES``: the command line, the twin and the conformance suite then pick both up,
with no other file changed. The protocols are deliberately small, but real: TCP and UDP on the
twin's loopback addresses, the client in the session's process, the face in the twin's.

- ``toybot://HOST``: TCP port 47001, one JSON line each way. The controller sends its state
  every 4 ms (``t`` [s], ``p`` [m], ``rv`` rotation vector [rad], ``moving``, ``stopped``);
  the client sends ``{"twist": [...]}`` (held for at most 0.1 s), ``{"move": [p, rv]}`` (a
  proportional approach, capped at 0.25 m/s and 1 rad/s) or ``{"hold": 1}``.
- ``toyft://HOST``: UDP port 47002. A datagram ``start`` from the client; then each sample as
  text ``seq fx fy fz tx ty tz`` [N, N*m].
"""

from __future__ import annotations

import contextlib
import json
import socket
import threading
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from ftcomp.errors import HardwareError
from ftcomp.frames import matrix_from_rotvec, rotvec_from_matrix
from ftcomp.hardware.devices import Device, Fault, TwinFace
from ftcomp.hardware.protocols import HOST_CLOCK, PoseSample, WrenchSample

ROBOT_PORT, SENSOR_PORT = 47001, 47002
PERIOD_S = 0.004
TWIST_HOLD_S = 0.1
SILENCE_S = 0.1
#: At rest: the pose moved less than this between two state lines (0.25 mm/s, 2.5 mrad/s) ...
STILL_STEP_M, STILL_TURN_RAD = 1e-6, 1e-5
#: ... for this long [s] (a UR's rule: hardware/ur.py).
STILL_S = 0.1

DEVICES = (
    Device(
        "robot",
        "toybot",
        f"{__name__}:open_robot",
        "toybot://HOST",
        "a toy arm (JSON lines over TCP)",
        tested="the twin's toy face",
        twin=TwinFace(
            "toybot",
            f"{__name__}:ToyRobotFace",
            faults=(Fault("toybot-silent", "no more state lines", "toybot: no new state", 0.5),),
        ),
    ),
    Device(
        "sensor",
        "toyft",
        f"{__name__}:open_sensor",
        "toyft://HOST",
        "a toy F/T sensor (text over UDP)",
        tested="the twin's toy face",
        twin=TwinFace(
            "toyft",
            f"{__name__}:ToySensorFace",
            faults=(Fault("toyft-silent", "no more datagrams", "stale_sample", 0.1),),
        ),
    ),
)


# ------------------------------------------------------------------------------- twin faces
class ToyRobotFace:
    period_s = PERIOD_S

    def __init__(self, host: str, cell: Any, *, realtime: bool, seed: int) -> None:
        self.host, self.cell = host, cell
        self.listener = socket.create_server((host, ROBOT_PORT))
        self.clients: list[socket.socket] = []
        self.command: tuple[str, Any, float] = ("hold", None, 0.0)
        self.moved = False  # a client commanded a move or a twist
        self.silent = False
        self.lines = 0
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                conn, _ = self.listener.accept()
            except OSError:
                return
            self.clients.append(conn)
            threading.Thread(target=self._read, args=(conn,), daemon=True).start()

    def _read(self, conn: socket.socket) -> None:
        with contextlib.suppress(OSError, ValueError), conn.makefile("r") as lines:
            for line in lines:
                message = json.loads(line)
                kind = next(iter(message))
                self.command = (kind, message[kind], self.cell.time())
                self.moved = self.moved or kind in ("move", "twist")

    def uri(self) -> str:
        return f"toybot://{self.host}"

    def commanded(self) -> bool:
        return self.moved

    def _error(self) -> np.ndarray:
        _, (p_target, rv_target), _ = self.command
        p, R = self.cell.sensor_pose()
        R_target = matrix_from_rotvec(rv_target)
        return np.concatenate([np.subtract(p_target, p), rotvec_from_matrix(R_target @ R.T)])

    def cycle(self, contact_force_N: float) -> None:
        self.cell.command_twist(self._twist())

    def _twist(self) -> np.ndarray:
        kind, value, since = self.command
        if kind == "twist" and self.cell.time() - since <= TWIST_HOLD_S:
            return np.array(value, dtype=float)
        if kind == "move":
            twist = 10.0 * self._error()
            for part, cap in ((slice(0, 3), 0.25), (slice(3, 6), 1.0)):
                norm = float(np.linalg.norm(twist[part]))
                if norm > cap:
                    twist[part] *= cap / norm
            return twist
        return np.zeros(6)

    def publish(self, wrench_sensor: np.ndarray) -> None:
        if self.silent or not self.clients:
            return
        p, R = self.cell.sensor_pose()
        kind = self.command[0]
        error = self._error() if kind == "move" else np.zeros(6)
        moving = bool(np.linalg.norm(error[:3]) > 1e-4 or np.linalg.norm(error[3:]) > 5e-4)
        state = {"t": self.cell.time(), "p": p.tolist(), "rv": list(rotvec_from_matrix(R))}
        line = (json.dumps({**state, "moving": moving}) + "\n").encode()
        for conn in list(self.clients):
            try:
                conn.sendall(line)
                self.lines += 1
            except OSError:
                self.clients.remove(conn)

    def inject(self, fault: str) -> None:
        self.silent = True

    def safety(self) -> str:
        return "normal"

    def served(self) -> str:
        return f"{self.lines} state lines"

    def close(self) -> None:
        for sock in [self.listener, *self.clients]:
            with contextlib.suppress(OSError):
                sock.close()


class ToySensorFace:
    def __init__(self, host: str, *, rate_hz: float, realtime: bool) -> None:
        self.host = host
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((host, SENSOR_PORT))
        self.peer: Any = None
        self.silent = False
        self.sent = 0
        threading.Thread(target=self._listen, daemon=True).start()

    def _listen(self) -> None:
        while True:
            try:
                data, addr = self.sock.recvfrom(64)
            except OSError:
                return
            if data == b"start":
                self.peer = addr

    def uri(self) -> str:
        return f"toyft://{self.host}"

    def push(self, samples: Sequence[WrenchSample]) -> None:
        if self.peer is None or self.silent:
            return
        for sample in samples:
            text = " ".join(f"{v:.6f}" for v in sample.wrench_sensor)
            with contextlib.suppress(OSError):
                self.sock.sendto(f"{self.sent} {text}".encode(), self.peer)
                self.sent += 1

    def inject(self, fault: str) -> None:
        self.silent = True

    def served(self) -> str:
        return f"{self.sent} datagrams"

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self.sock.close()


# ------------------------------------------------------------------------------ live backends
class ToyRobot:
    """A ``toybot://`` arm; paced by its controller's state lines."""

    control_period_s = PERIOD_S
    clock_name = HOST_CLOCK
    pose_known = True

    def __init__(self, host: str) -> None:
        self.host = host
        self.ready = threading.Condition()
        self.state: dict[str, Any] | None = None
        self.t_ns = 0
        self.count = 0
        self.sock: socket.socket | None = None

    def __enter__(self) -> ToyRobot:
        try:
            self.sock = socket.create_connection((self.host, ROBOT_PORT), timeout=2.0)
        except OSError as exc:
            raise HardwareError(f"toybot://{self.host}: cannot connect: {exc}") from None
        self.sock.settimeout(None)
        threading.Thread(target=self._read, daemon=True).start()
        self._wait_new(self.count, 2.0)
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
        if self.sock is not None:
            with contextlib.suppress(OSError):
                self.sock.close()

    def _read(self) -> None:
        assert self.sock is not None
        with contextlib.suppress(OSError, ValueError), self.sock.makefile("r") as lines:
            for line in lines:
                state = json.loads(line)
                with self.ready:
                    self.state, self.t_ns = state, time.monotonic_ns()
                    self.count += 1
                    self.ready.notify_all()

    def _send(self, message: dict[str, Any]) -> None:
        assert self.sock is not None
        try:
            self.sock.sendall((json.dumps(message) + "\n").encode())
        except OSError as exc:
            raise HardwareError(f"toybot://{self.host}: {exc}") from None

    def _wait_new(self, after: int, timeout_s: float) -> dict[str, Any]:
        with self.ready:
            if not self.ready.wait_for(lambda: self.count > after, timeout_s):
                raise HardwareError(f"toybot: no new state for {timeout_s:.2f} s")
            assert self.state is not None
            return self.state

    def now_ns(self) -> int:
        return time.monotonic_ns()

    def pose(self) -> PoseSample:
        with self.ready:
            state, t_ns = self.state, self.t_ns
        assert state is not None
        return PoseSample(t_ns, np.array(state["p"]), matrix_from_rotvec(state["rv"]))

    def move_pose(self, p_base_tcp: np.ndarray, R_base_tcp: np.ndarray, duration_s: float) -> None:
        self._send({"move": [list(map(float, p_base_tcp)), list(rotvec_from_matrix(R_base_tcp))]})
        seen = self.count
        deadline = time.monotonic() + duration_s + 10.0
        self._wait_new(seen + 2, SILENCE_S * 5)  # the controller has the target
        while time.monotonic() < deadline:
            if not self._wait_new(self.count, SILENCE_S)["moving"]:
                return
        raise HardwareError("toybot: the move did not end")

    def settle(self, max_duration_s: float) -> float:
        """Hold, then wait until the reported pose has kept still for :data:`STILL_S`: a move
        ends within 0.1 mm of its target, still approaching, and a hold stops the arm through
        its servo; readings taken before it is at rest see the tool's inertia."""
        start = time.monotonic()
        self._send({"hold": 1})
        self._wait_new(self.count + 2, SILENCE_S * 5)
        still_since, last = time.monotonic(), self.pose()
        while time.monotonic() - still_since < STILL_S:
            if time.monotonic() - start > max_duration_s:
                raise HardwareError(f"toybot: still moving after {max_duration_s:g} s")
            self._wait_new(self.count, SILENCE_S)
            here = self.pose()
            step_m = float(np.linalg.norm(here.p_base_tcp - last.p_base_tcp))
            turn_rad = float(
                np.linalg.norm(rotvec_from_matrix(here.R_base_tcp @ last.R_base_tcp.T))
            )
            if step_m > STILL_STEP_M or turn_rad > STILL_TURN_RAD:
                still_since = time.monotonic()
            last = here
        return time.monotonic() - start

    def command_twist(self, twist_base: np.ndarray) -> None:
        self._send({"twist": [float(v) for v in twist_base]})

    def wait_cycle(self) -> None:
        self._wait_new(self.count, SILENCE_S)

    def stop(self) -> None:
        with contextlib.suppress(HardwareError, AssertionError):
            self._send({"hold": 1})

    def is_reachable(self, p_base_tcp: np.ndarray, R_base_tcp: np.ndarray) -> bool:
        return bool(np.linalg.norm(p_base_tcp) < 0.85)


class ToySensor:
    """A ``toyft://`` sensor; each datagram stamped on arrival (host clock)."""

    def __init__(self, host: str) -> None:
        self.host = host
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.lock = threading.Lock()
        self.new: list[WrenchSample] = []
        self.last: WrenchSample | None = None
        self.arrived = threading.Event()

    def __enter__(self) -> ToySensor:
        self.sock.connect((self.host, SENSOR_PORT))
        self.sock.send(b"start")
        threading.Thread(target=self._read, daemon=True).start()
        if not self.arrived.wait(2.0):
            self.sock.close()
            raise HardwareError(f"toyft://{self.host}: no data")
        return self

    def __exit__(self, *exc: object) -> None:
        with contextlib.suppress(OSError):
            self.sock.close()

    def _read(self) -> None:
        while True:
            try:
                data = self.sock.recv(256)
            except OSError:
                return
            values = np.array([float(v) for v in data.split()[1:]])
            sample = WrenchSample(time.monotonic_ns(), values)
            with self.lock:
                self.new.append(sample)
                self.last = sample
            self.arrived.set()

    def read(self) -> WrenchSample:
        with self.lock:
            assert self.last is not None
            return self.last

    def read_new(self) -> list[WrenchSample]:
        with self.lock:
            new, self.new = self.new, []
        return new


def open_robot(uri: Any) -> ToyRobot:
    uri.reader().done()
    return ToyRobot(uri.host)


def open_sensor(uri: Any, robot: Any) -> ToySensor:
    uri.reader().done()
    return ToySensor(uri.host)
