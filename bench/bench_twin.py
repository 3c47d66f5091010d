"""Benchmark the twin's real time: RTDE packages at 500 Hz while ``ftcomp run`` runs beside it.

Run by hand (not a test): ``.venv/bin/python bench/bench_twin.py [--seconds 60]``.
Starts ``ftcomp twin`` (its own process), ``ftcomp run --dry-run`` against it (the compliant loop
at 500 Hz through ur_rtde and pynetft, commands computed and logged, none sent), and an RTDE
client of its own that asks for the controller's ``timestamp`` at 500 Hz and counts what
arrives. Goal: 500 +- 1 packages/s over the window; the twin's step (its final line) well inside
its 2 ms period. Prints the package rate, the largest gap, the twin's step percentiles and the
share of its period they use.
"""

from __future__ import annotations

import argparse
import os
import select
import socket
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROBOT, SENSOR = "127.0.0.41", "127.0.0.42"
PERIOD_S = 0.002
#: The client as a user runs it (its live loop sets what it needs: ftcomp.hardware.pacing).
CLIENT = "import sys; from ftcomp.cli import main; sys.exit(main())"


def _rtde_timestamps(host: str, seconds: float) -> np.ndarray:
    """Arrival times [s] of every data package of a 500 Hz ``timestamp`` recipe."""
    sock = socket.create_connection((host, 30004), timeout=5)

    def send(kind: str, payload: bytes = b"") -> None:
        sock.sendall(struct.pack(">HB", 3 + len(payload), ord(kind)) + payload)

    def receive() -> tuple[str, bytes]:
        head = b""
        while len(head) < 3:
            head += sock.recv(3 - len(head))
        size, kind = struct.unpack(">HB", head)
        body = b""
        while len(body) < size - 3:
            body += sock.recv(size - 3 - len(body))
        return chr(kind), body

    send("V", struct.pack(">H", 2))
    receive()
    send("O", struct.pack(">d", 500.0) + b"timestamp")
    receive()
    send("S")
    arrivals = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        kind, _ = receive()
        if kind == "U":
            arrivals.append(time.monotonic())
    sock.close()
    return np.array(arrivals)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="window [s] (default 20)")
    args = parser.parse_args()
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as folder:
        run_log = Path(folder) / "dry.csv"
        twin = subprocess.Popen(
            [sys.executable, "-m", "ftcomp", "twin", "--robot-host", ROBOT, "--sensor-host",
             SENSOR, "--seconds", str(args.seconds + 30)],
            stdout=subprocess.PIPE, text=True, env=env,
        )  # fmt: skip
        assert twin.stdout is not None
        select.select([twin.stdout], [], [], 30.0)
        print(twin.stdout.readline().strip())
        run = subprocess.Popen(
            [sys.executable, "-c", CLIENT, "run", "--robot", f"ur://{ROBOT}", "--sensor",
             f"netft://{SENSOR}", "-c", str(_calibration(Path(folder))), "--control",
             "admittance", "--axes", "z", "--dry-run", "--seconds", str(args.seconds + 5),
             "--max-late-cycles", "1000", "-o", str(run_log)],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
        )  # fmt: skip
        time.sleep(3.0)
        arrivals = _rtde_timestamps(ROBOT, args.seconds)
        out, _ = run.communicate(timeout=args.seconds + 60)
        twin.terminate()
        final = twin.communicate(timeout=30)[0].strip().splitlines()
    gaps_ms = np.diff(arrivals) * 1e3
    rate = (len(arrivals) - 1) / (arrivals[-1] - arrivals[0])
    print(f"ftcomp run beside it: {out.strip().splitlines()[-1]}")
    print(
        f"RTDE packages over {arrivals[-1] - arrivals[0]:.1f} s: {rate:.2f} /s "
        f"(goal 500 +- 1); gap p50 {np.percentile(gaps_ms, 50):.2f} ms, "
        f"p99 {np.percentile(gaps_ms, 99):.2f} ms, max {gaps_ms.max():.2f} ms"
    )
    served = next((line for line in final if line.startswith("twin served")), "")
    if served:  # the step in us (the timing line after it gives ms)
        print(served)
        words = served.split()
        try:
            p50 = float(words[words.index("p50") + 1])
            p99 = float(words[words.index("p99") + 1])
            print(
                f"step budget: p50 {p50 / (PERIOD_S * 1e6):.0%}, p99 {p99 / (PERIOD_S * 1e6):.0%} "
                f"of the 2 ms period"
            )
        except (ValueError, IndexError):
            pass


def _calibration(folder: Path) -> Path:
    """A calibration file of the twin's default tool (the paper's values), for the dry run."""
    path = folder / "cal.json"
    subprocess.run(
        [sys.executable, "-c",
         "import json; from ftcomp.io.calibration_json import model_to_dict; "
         "from ftcomp.sim.cell import SimCell; m = SimCell().true_gravity_model(); "
         f"d = model_to_dict(m); d.update(format='ftcomp.calibration/1', method='paper'); "
         f"open({str(path)!r}, 'w').write(json.dumps(d))"],
        check=True,
    )  # fmt: skip
    return path


if __name__ == "__main__":
    main()
