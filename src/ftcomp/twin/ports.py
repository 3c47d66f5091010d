"""The twin's other robot sockets: UR's dashboard server and its script ports.

- Dashboard (TCP 29999): one text line per request, one line per answer, as PolyScope 5
  answers them (``PolyscopeVersion``, ``get serial number``, ``is in remote control``,
  ``robotmode``, ``safetystatus``, ``programState``, ``running``, ``stop``,
  ``unlock protective stop``, ``close safety popup``, ``quit``).
- Script ports (TCP 30001, 30002, 30003): a URScript program sent as text; a complete
  top-level ``def ... end`` program starts at once.

The Net F/T is :mod:`ftcomp.twin.netft` (a process of its own).
"""

from __future__ import annotations

import socket
import threading
from collections.abc import Callable
from typing import Final

from ftcomp.twin.controller import UrController

__all__ = [
    "DASHBOARD_PORT",
    "SCRIPT_PORTS",
    "accept_forever",
    "serve_dashboard",
    "serve_script",
]

DASHBOARD_PORT: Final = 29999
SCRIPT_PORTS: Final = (30001, 30002, 30003)
_POLYSCOPE: Final = "URSoftware 5.11.1.108318 (Mar 22 2021)"


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

    accept_forever(listener, session)


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

    accept_forever(listener, session)


def accept_forever(listener: socket.socket, session: Callable[[socket.socket], None]) -> None:
    """Accept TCP clients until the listener closes; each one (``TCP_NODELAY``) is served by
    ``session`` on a daemon thread of its own."""
    while True:
        try:
            conn, _ = listener.accept()
        except OSError:
            return
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        threading.Thread(target=session, args=(conn,), daemon=True).start()
