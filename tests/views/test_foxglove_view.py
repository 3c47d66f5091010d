"""``--view HOST:PORT``: a client written from the Foxglove WebSocket protocol spec (not the SDK)
subscribes to the compensated wrench of a live ``ftcomp stream`` and gets the CSV log's rows.

The protocol (foxglove/ws-protocol, ``docs/spec.md``): subprotocol ``foxglove.websocket.v1``,
which foxglove-sdk's server names ``foxglove.sdk.v1`` (the same protocol under a new name: the
client offers both, as recent Lichtblick and Foxglove do, and the server picks its own); the
server sends ``serverInfo`` and ``advertise`` (JSON text); the client sends ``subscribe`` with
its own subscription id per channel id; the server sends each message as binary: opcode ``0x01``,
the subscription id (uint32 LE), the log time (uint64 LE, ns), the payload (here JSON).
"""

from __future__ import annotations

import json
import os
import signal
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import ftcomp
from ftcomp.cli import main
from ftcomp.errors import ParameterError

websockets_client = pytest.importorskip("websockets.sync.client")
pytest.importorskip("foxglove")

#: The protocol's names, old and new.
SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]
#: Messages to receive before the stream is stopped (about 0.3 s of the simulated sensor).
WANTED = 300
#: Every wait in the test ends by then [s].
DEADLINE_S = 60.0


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _csv(path: Path) -> dict[str, np.ndarray]:
    header = path.read_text().splitlines()[0].split(",")
    data = np.genfromtxt(path, delimiter=",", skip_header=1, ndmin=2, dtype=str)
    return {name: data[:, i] for i, name in enumerate(header)}


def _connect(url: str, deadline: float):  # type: ignore[no-untyped-def]
    while True:
        try:
            return websockets_client.connect(
                url, subprotocols=SUBPROTOCOLS, open_timeout=5, close_timeout=1, max_size=None
            )
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.05)


def _subscribe_and_receive(
    url: str, topic: str, deadline: float, stop: Callable[[], None]
) -> tuple[dict, list]:
    """Connect, read serverInfo and the advertisements, subscribe to ``topic``, receive
    :data:`WANTED` messages, then ``stop`` the server's session (before closing)."""
    received: list[tuple[int, dict]] = []
    with _connect(url, deadline) as ws:
        assert ws.subprotocol in SUBPROTOCOLS
        info = json.loads(ws.recv(timeout=10))
        assert info["op"] == "serverInfo", info
        channel = None
        while channel is None:
            message = ws.recv(timeout=max(0.1, deadline - time.monotonic()))
            if isinstance(message, bytes):
                continue
            op = json.loads(message)
            if op["op"] == "advertise":
                channel = next((c for c in op["channels"] if c["topic"] == topic), None)
        assert channel["encoding"] == "json"
        ws.send(
            json.dumps(
                {"op": "subscribe", "subscriptions": [{"id": 7, "channelId": channel["id"]}]}
            )
        )
        while len(received) < WANTED:
            message = ws.recv(timeout=max(0.1, deadline - time.monotonic()))
            if isinstance(message, str):
                continue  # more advertisements, status
            opcode, subscription, log_ns = struct.unpack_from("<BIQ", message)
            assert opcode == 0x01 and subscription == 7
            received.append((log_ns, json.loads(message[13:])))
        stop()
    return channel, received


def test_a_spec_client_receives_the_compensated_wrench_rows_of_a_live_stream(
    tmp_path: Path,
) -> None:
    samples, cal = tmp_path / "s.csv", tmp_path / "cal.json"
    record = ["record", "--robot", "sim://?seed=4", "--sensor", "sim://", "--poses", "paper"]
    assert main([*record, "--samples-per-pose", "100", "--move-s", "1", "-o", str(samples)]) == 0
    assert main(["calibrate", str(samples), "-o", str(cal), "--json"]) == 0
    port, out = _free_port(), tmp_path / "stream.csv"
    argv = ["stream", "--robot", "sim://", "--sensor", "sim://", "-c", str(cal)]
    argv += ["--seconds", "60", "-o", str(out), "--view", f"127.0.0.1:{port}"]
    # Ctrl-C raises KeyboardInterrupt even where the test runs with SIGINT ignored (a batch job).
    code = (
        "import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
        "from ftcomp.cli import main; sys.exit(main(sys.argv[1:]))"
    )
    env = {**os.environ, "PYTHONPATH": str(Path(ftcomp.__file__).parents[1])}
    process = subprocess.Popen([sys.executable, "-c", code, *argv], env=env)
    deadline = time.monotonic() + DEADLINE_S
    interrupted: list[bool] = []

    def ctrl_c() -> None:  # once: a second Ctrl-C would cut the stream's tidy end short
        interrupted.append(True)
        process.send_signal(signal.SIGINT)

    try:
        channel, received = _subscribe_and_receive(
            f"ws://127.0.0.1:{port}", "/ftcomp/wrench_compensated", deadline, ctrl_c
        )  # Ctrl-C: the stream keeps its log
    finally:
        if not interrupted and process.poll() is None:
            ctrl_c()
        returncode = process.wait(timeout=DEADLINE_S)
    assert returncode == 130
    assert channel["schemaName"] == "ftcomp.WrenchStamped"
    log = _csv(out)
    t_ns = [round(float(t) * 1e9) for t in log["t"]]
    stamps = [m["timestamp"]["sec"] * 10**9 + m["timestamp"]["nsec"] for _, m in received]
    first = t_ns.index(stamps[0])
    # Every row from the subscription on, none dropped (the stream's rate), same stamps ...
    assert stamps == t_ns[first : first + len(stamps)]
    assert [t for t, _ in received] == stamps
    # ... and the values the CSV has (it writes 10 significant digits).
    rows = slice(first, first + len(stamps))
    csv_contact = np.column_stack(
        [log[c][rows].astype(float) for c in ("cfx", "cfy", "cfz", "ctx", "cty", "ctz")]
    )
    sent = np.array([[m[k][a] for k in ("force", "torque") for a in "xyz"] for _, m in received])
    np.testing.assert_allclose(sent, csv_contact, rtol=1e-9, atol=1e-12)
    assert {m["frame_id"] for _, m in received} == {"ft_sensor"}


def test_a_bad_view_address_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["stream", "--robot", "sim://", "--sensor", "sim://", "--seconds", "0.1"]
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "-o", str(tmp_path / "s.csv"), "--view", "127.0.0.1:http"])
    assert exit_info.value.code == 2
    assert "expected HOST:PORT" in capsys.readouterr().err


def test_the_view_refuses_a_port_without_a_host() -> None:
    from ftcomp.cli.live_status import view_address
    from ftcomp.views.foxglove_view import parse_address

    assert view_address("8765") == "127.0.0.1:8765"  # --view PORT: loopback only

    assert parse_address("127.0.0.2:9000") == ("127.0.0.2", 9000)
    with pytest.raises(ParameterError, match="HOST:PORT"):
        parse_address(":9000")
