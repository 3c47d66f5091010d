"""Every ROS 2 participant of the live tests on loopback, on a domain of its test's own.

The ``ros2_graph`` fixture puts ftcomp's loopback environment
(:func:`ftcomp.ros2.rclpy_runtime.loopback_environment`: ``ROS_AUTOMATIC_DISCOVERY_RANGE=
LOCALHOST``, a Fast DDS profile whitelisting 127.0.0.1 without the built-in transports) and a
``ROS_DOMAIN_ID`` into this process's environment, which the peer processes inherit; and it
checks that no non-loopback interface sent a packet during the test (the kernel's counters in
``/proc/net/dev`` before and after). Without the profile, Fast DDS's discovery announces itself
by multicast on every interface and the check fails (tried: eth0 sent 9 packets in 1.3 s).
Unrelated traffic of the same machine in the same seconds would fail it too; the message says
which interface moved. Under ``-n 2`` no headless browser runs beside it (tests/offhost.py).
"""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from offhost import off_host_turn

HERE = Path(__file__).parent
_tests = itertools.count()


@pytest.fixture(name="ros2_graph")
def ros2_graph_fixture(
    monkeypatch: pytest.MonkeyPatch, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[int]:
    """The test's ROS_DOMAIN_ID, loopback pinned, nothing sent elsewhere (see the module)."""
    pytest.importorskip("rclpy")
    from ftcomp.ros2.rclpy_runtime import loopback_environment, transmitted_packets

    for key, value in loopback_environment(tmp_path_factory.mktemp("dds")).items():
        monkeypatch.setenv(key, value)
    domain = 10 + (os.getpid() * 7 + next(_tests)) % 200
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
    with off_host_turn():  # no browser beside it under -n 2 (tests/offhost.py)
        before = transmitted_packets()
        yield domain
        after = transmitted_packets()
    moved = {k: after[k] - before.get(k, 0) for k in after if after[k] != before.get(k, 0)}
    assert not moved, f"packets sent on non-loopback interfaces during the test: {moved}"


def peer(*args: object) -> subprocess.Popen[bytes]:
    """``rclpy_peer.py ARGS`` in its own process, in this process's (pinned) environment."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE), *sys.path])}
    return subprocess.Popen(
        [sys.executable, str(HERE / "rclpy_peer.py"), *map(str, args)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )


def stop(*procs: subprocess.Popen[bytes]) -> None:
    """Kill and reap peer processes."""
    for proc in procs:
        proc.kill()
        proc.wait(timeout=10)
