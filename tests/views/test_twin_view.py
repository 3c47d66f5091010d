"""``ftcomp twin --view HOST:PORT``: a client written from the Foxglove WebSocket protocol spec
(as in test_foxglove_view.py) subscribes to the twin's contact wrench and gets its contact log's
rows, same stamps, same values; the TCP pose and the safety state are advertised beside it."""

from __future__ import annotations

import csv
import itertools
import json
import socket
import struct
import time
from pathlib import Path

import pytest

websockets_client = pytest.importorskip("websockets.sync.client")
pytest.importorskip("foxglove")
pytest.importorskip("mujoco")

from standins.twin_process import running_twin  # noqa: E402

SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]
WANTED = 200  # 0.4 s of the twin's 500 Hz rows


pytestmark = pytest.mark.live


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_a_spec_client_receives_the_twins_contact_wrench_rows(tmp_path: Path) -> None:
    port, contact = _free_port(), tmp_path / "contact.csv"
    options = ("--load-kg", "0.5", "--surface", "sponge", "--clearance-mm", "0")
    view = ("--view", f"127.0.0.1:{port}", "--contact-log", str(contact))
    received: list[tuple[int, dict]] = []
    with running_twin("twin_view", *options, *view) as twin:
        deadline = time.monotonic() + 30.0
        with websockets_client.connect(
            f"ws://127.0.0.1:{port}", subprotocols=SUBPROTOCOLS, open_timeout=10
        ) as ws:
            assert json.loads(ws.recv(timeout=10))["op"] == "serverInfo"
            channels: dict[str, dict] = {}
            wanted = {"/twin/contact_wrench", "/twin/safety", "/tf"}
            while not wanted <= channels.keys():  # advertised in one message or several
                message = ws.recv(timeout=max(0.1, deadline - time.monotonic()))
                op = json.loads(message)
                if op["op"] == "advertise":
                    channels.update({c["topic"]: c for c in op["channels"]})
            wrench = channels["/twin/contact_wrench"]
            subscribe = [{"id": 3, "channelId": wrench["id"]}]
            ws.send(json.dumps({"op": "subscribe", "subscriptions": subscribe}))
            while len(received) < WANTED:
                message = ws.recv(timeout=max(0.1, deadline - time.monotonic()))
                if isinstance(message, str):
                    continue
                opcode, subscription, log_ns = struct.unpack_from("<BIQ", message)
                assert opcode == 0x01 and subscription == 3
                received.append((log_ns, json.loads(message[13:])))
        twin.proc.terminate()  # SIGTERM: the twin ends and writes its contact log
        twin.proc.wait(timeout=30)
    assert wrench["schemaName"] == "ftcomp.WrenchStamped"
    with contact.open() as f:
        rows = {round(float(r["t_s"]) * 1e9): r for r in csv.DictReader(f)}
    stamps = [m["timestamp"]["sec"] * 10**9 + m["timestamp"]["nsec"] for _, m in received]
    assert [t for t, _ in received] == stamps
    assert all(t in rows for t in stamps)  # every message is a row of the log ...
    period_ns = round(0.002 * 1e9)
    assert all(b - a == period_ns for a, b in itertools.pairwise(stamps))  # none lost
    for t, message in zip(stamps, (m for _, m in received), strict=True):
        row = rows[t]  # ... with its values, in the base frame
        sent = [message[k][a] for k in ("force", "torque") for a in "xyz"]
        assert sent == [float(row[c]) for c in ("fx", "fy", "fz", "tx", "ty", "tz")]
        assert message["frame_id"] == "base"
    assert any(m["force"]["z"] > 0.0 for _, m in received)  # the sponge carries the load
