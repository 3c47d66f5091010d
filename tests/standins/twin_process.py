"""Start ``ftcomp twin`` in its own process and stop it: ``with running_twin(name) as twin``.

The twin gets two loopback addresses of the test's own (robot, sensor), prints
``twin ready: robot URI sensor URI`` once every socket is bound (the URIs its faces answer
on), ends by itself after ``seconds`` and is terminated (SIGTERM, then killed) when the block
ends. ``--robot FACE --sensor FACE`` among ``args`` choose the faces.
"""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from standins.launch import Drain, loopback_address

__all__ = ["Twin", "running_twin"]


@dataclass(frozen=True)
class Twin:
    """A running twin: its addresses, process and output (read all along, the last lines kept:
    :meth:`output` for a failing test's message, whole once the block has ended)."""

    robot_host: str
    sensor_host: str
    proc: subprocess.Popen[str]
    drain: Drain
    robot_uri: str
    sensor_uri: str

    def output(self) -> str:
        """The twin's last lines (its timing line at the end, late cycles on stderr)."""
        return "ftcomp twin said:\n" + self.drain.text()


@contextmanager
def running_twin(
    name: str,
    *args: str,
    seconds: float = 60.0,
    ready_timeout_s: float = 30.0,
    env: dict[str, str] | None = None,
) -> Iterator[Twin]:
    """``ftcomp twin`` with ``args`` on two addresses derived from ``name`` (in ``env``, by
    default this process's environment)."""
    robot_host = loopback_address(name, 1)
    sensor_host = loopback_address(name, 2)
    command = [
        sys.executable,
        "-m",
        "ftcomp",
        "twin",
        "--robot-host",
        robot_host,
        "--sensor-host",
        sensor_host,
        "--seconds",
        str(seconds),
        *args,
    ]
    proc = subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=dict(os.environ) if env is None else env,
    )
    drain = None
    try:
        assert proc.stdout is not None
        deadline = time.monotonic() + ready_timeout_s
        line = ""
        while time.monotonic() < deadline and proc.poll() is None:
            ready, _, _ = select.select([proc.stdout], [], [], 0.1)
            if ready:
                line = proc.stdout.readline()
                break
        if not line.startswith("twin ready:"):
            proc.kill()
            _, err = proc.communicate(timeout=5)
            raise RuntimeError(f"ftcomp twin did not start: {line!r} {err[-2000:]}")
        drain = Drain(proc)
        words = line.split()  # twin ready: robot URI sensor URI
        robot_uri, sensor_uri = words[words.index("robot") + 1], words[words.index("sensor") + 1]
        yield Twin(robot_host, sensor_host, proc, drain, robot_uri, sensor_uri)
    finally:
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout=5)
        if drain is not None:
            drain.join()
        for stream in (proc.stdout, proc.stderr):
            if stream is not None:
                stream.close()


def calibration_from_truth(truth: Path, calibration: Path) -> None:
    """A calibration file holding a twin's true tool, from its ``--truth`` file (for a run that
    needs a compensation only)."""
    from ftcomp.io.calibration_json import FORMAT

    document = json.loads(truth.read_text())
    keys = ("tool_weight_N", "center_of_gravity_m", "force_bias_N", "torque_bias_Nm")
    data = {key: document[key] for key in (*keys, "base_tilt_deg", "gravity_in_base_N")}
    calibration.write_text(json.dumps({"format": FORMAT, "method": "paper", **data}))
