"""The twin's RTDE session applies a client's input package whole, as a UR controller does."""

from __future__ import annotations

import socket
import struct
import threading

import pytest

from ftcomp.twin.rtde import RtdeSession


def _package(kind: str, payload: bytes) -> bytes:
    return struct.pack(">HB", 3 + len(payload), ord(kind)) + payload


def _reply(conn: socket.socket) -> tuple[str, bytes]:
    size, kind = struct.unpack(">HB", conn.recv(3, socket.MSG_WAITALL))
    return chr(kind), conn.recv(size - 3, socket.MSG_WAITALL)


def test_an_input_package_reaches_the_controller_as_one_whole_dict() -> None:
    server, client = socket.socketpair()
    packages: list[dict[str, object]] = []
    arrived = threading.Event()

    def write_inputs(package: dict[str, object]) -> None:
        packages.append(dict(package))
        if len(packages) == 2:
            arrived.set()

    session = RtdeSession(server, (5, 15, 0, 0), write_inputs)
    thread = threading.Thread(target=session.serve, daemon=True)
    thread.start()
    try:
        names = "input_int_register_0,input_double_register_0,input_double_register_1"
        client.sendall(_package("I", names.encode()))
        kind, answer = _reply(client)
        assert kind == "I" and answer[0] == 1, answer
        assert answer[1:].decode() == "INT32,DOUBLE,DOUBLE"
        client.sendall(_package("U", struct.pack(">Bidd", 1, 61, 0.45, -0.1)))
        client.sendall(_package("U", struct.pack(">Bidd", 1, 1, 1.5, 2.5)))
        assert arrived.wait(10.0), f"two packages sent, {len(packages)} arrived"
    finally:
        client.close()
        thread.join(10.0)
    assert packages == [
        {
            "input_int_register_0": 61,
            "input_double_register_0": 0.45,
            "input_double_register_1": -0.1,
        },
        {"input_int_register_0": 1, "input_double_register_0": 1.5, "input_double_register_1": 2.5},
    ]


def test_write_inputs_waits_while_a_controller_cycle_holds_the_lock() -> None:
    pytest.importorskip("mujoco")
    from ftcomp.twin.controller import UrController
    from ftcomp.twin.serve import TwinConfig

    controller = UrController(TwinConfig("127.0.0.1", "127.0.0.2", 1.0).open_cell())
    applied = threading.Event()
    with controller.lock:  # a cycle in progress
        writer = threading.Thread(
            target=lambda: (controller.write_inputs({"input_int_register_0": 61}), applied.set()),
            daemon=True,
        )
        writer.start()
        assert not applied.wait(0.2), "the package was applied inside a running cycle"
        assert "input_int_register_0" not in controller.inputs
    assert applied.wait(10.0)
    assert controller.inputs["input_int_register_0"] == 61
