"""Missed periods of ``ftcomp run`` at 500 Hz with and without ``--log`` and ``--view``.

Run by hand (not a test), from the repository root::

    .venv/bin/python bench/bench_view.py                  # 4 rounds of 10 s per variant
    .venv/bin/python bench/bench_view.py --seconds 5 --rounds 2

Each variant is :func:`ftcomp.session.run.run_compliant` (a dry run: the command is computed
and logged, a zero twist sent) on ``fixed://?rate_hz=500`` (its loop paced on the host's clock,
reporting every cycle that overran its period) with a sensor that costs nothing (a ramp stamped
on the host's clock), the CSV log written as ``ftcomp run`` writes it, and:

- ``none``: nothing else;
- ``log``: ``--log`` (the MCAP writer on the observer thread);
- ``view``: ``--view 127.0.0.1:PORT`` with a client (another process on the same machine,
  competing for the cores as a viewer would) subscribed to every channel;
- ``both``.

The variants take turns, in rotating order, so that the machine's noise hits them alike; the
table gives, per variant, the cycles, the periods missed (cycles that overran their 2 ms; the
first 10 cycles of each run left out: the pacer starts when the robot opens), the worst
overrun, summed over the rounds, and percentiles of each cycle's own work (from the pacer's
return to its next wait): what an observer could slow through the interpreter's lock, and
less at the mercy of the other programs on the machine than the missed periods are.
"""

from __future__ import annotations

import argparse
import json
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

VARIANTS = ("none", "log", "view", "both")


class _Sensor:
    """A sensor that costs nothing: the next row of a recorded-like ramp, stamped now."""

    def __init__(self) -> None:
        from ftcomp.hardware.protocols import WrenchSample

        rng = np.random.default_rng(0)
        w = np.zeros((5000, 6))
        w[:, 2] = 3.153 + 0.05 * rng.normal(size=5000)
        self._rows = [row + np.array([-0.8613, 1.1015, 0.1976, 0, -0.0605, 0.0255]) for row in w]
        self._k = 0
        self._sample = WrenchSample.owning

    def read(self) -> Any:
        row = self._rows[self._k % len(self._rows)]
        self._k += 1
        return self._sample(time.monotonic_ns(), row)

    def read_new(self) -> list[Any]:
        return [self.read()]


class _Robot:
    """``fixed://`` that notes the slack of every period it waits for [s] (< 0: missed)."""

    def __init__(self, fixed: Any) -> None:
        self._fixed = fixed
        self.slack_s: list[float] = []
        self.busy_s: list[float] = []
        self._woke = time.perf_counter()

    def __getattr__(self, name: str) -> Any:
        return getattr(self._fixed, name)

    def wait_cycle(self) -> None:
        self.busy_s.append(time.perf_counter() - self._woke)  # the cycle's own work
        self._fixed.wait_cycle()
        self._woke = time.perf_counter()
        self.slack_s.append(self._fixed.pacer.slack_s)


#: Cycles at the start left out: the pacer starts when the robot opens, before the session.
SKIP = 10


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def client(port: int) -> None:
    """Subscribe to every channel of the view; print the messages received when it closes."""
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    protocols = ["foxglove.websocket.v1", "foxglove.sdk.v1"]
    count = 0
    deadline = time.monotonic() + 10.0
    while True:
        try:
            ws = connect(f"ws://127.0.0.1:{port}", subprotocols=protocols, close_timeout=1)
            break
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.05)
    subscribed = 0
    print("connected", flush=True)
    while True:
        try:
            message = ws.recv()
        except ConnectionClosed:
            print(count, flush=True)
            return
        if isinstance(message, bytes):
            count += 1
            continue
        op = json.loads(message)
        if op["op"] == "advertise":
            subs = [
                {"id": subscribed + k, "channelId": c["id"]} for k, c in enumerate(op["channels"])
            ]
            subscribed += len(subs)
            ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))


def one_run(variant: str, seconds: float, folder: Path) -> tuple[int, int, float, int, list[float]]:
    """(cycles, missed periods, worst overrun [s], messages the client got, each cycle's work
    [s]) of one variant."""
    import ftcomp
    from bench_compensate import MODEL
    from ftcomp.control.safety import SafetyLimits
    from ftcomp.session.run import AdmittanceConfig, RunConfig, run_compliant
    from ftcomp.views.live import session_observers

    fixed = ftcomp.open_robot("fixed://?rpy_deg=180,0,0&rate_hz=500")
    robot = _Robot(fixed)
    # ftcomp run's default envelope (never reached: a dry run of a still sensor)
    twist, rate, travel = np.repeat([0.02, 0.5], 3), np.repeat([0.5, 5.0], 3), np.full(6, 0.02)
    limits = SafetyLimits(twist, rate, travel, 40.0, 8.0, stale_after_s=0.02)
    config = RunConfig(
        AdmittanceConfig(limits), duration_s=seconds, dry_run=True, max_late_cycles=10**6
    )
    log = folder / f"{variant}.mcap" if variant in ("log", "both") else None
    port = _free_port()
    view = f"127.0.0.1:{port}" if variant in ("view", "both") else None
    watcher = None
    sensor = _Sensor()
    with session_observers(log, view, overwrite=True) as observers, fixed:
        if view is not None:
            watcher = subprocess.Popen(
                [sys.executable, __file__, "--client", str(port)], stdout=subprocess.PIPE, text=True
            )
            assert watcher.stdout is not None and watcher.stdout.readline().strip() == "connected"
            time.sleep(0.3)  # subscribed before the run starts
        result = run_compliant(
            robot, sensor, MODEL, config, folder / f"{variant}.csv", observers=observers
        )
        slack = np.array(robot.slack_s[SKIP:])
        late, worst = int(np.sum(slack < 0.0)), max(0.0, -float(slack.min()))
    messages = 0
    if watcher is not None:  # the view has closed: the client prints its count and ends
        out, _ = watcher.communicate(timeout=30)
        messages = int(out.split()[-1])
    return result.cycles, late, worst, messages, robot.busy_s[SKIP:]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="each run [s] (10)")
    parser.add_argument("--rounds", type=int, default=4, help="runs per variant (4)")
    parser.add_argument("--client", type=int, metavar="PORT", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.client is not None:
        client(args.client)
        return
    totals = {v: [0, 0, 0.0, 0] for v in VARIANTS}
    busy: dict[str, list[float]] = {v: [] for v in VARIANTS}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            order = VARIANTS[r % 4 :] + VARIANTS[: r % 4]
            for variant in order:
                cycles, late, worst, messages, work = one_run(variant, args.seconds, Path(tmp))
                busy[variant] += work
                t = totals[variant]
                t[0] += cycles
                t[1] += late
                t[2] = max(t[2], worst)
                t[3] += messages
                worst_ms = worst * 1e3
                what = f"{cycles} cycles, {late} missed, worst {worst_ms:.2f} ms"
                print(f"round {r + 1} {variant:>5}: {what}", flush=True)
    head = (
        "variant",
        "cycles",
        "missed",
        "missed %",
        "worst ms",
        "view msgs",
        "work p50",
        "p99",
        "p99.9",
    )
    print("\n" + " ".join(f"{h:>9}" for h in head) + "  (work: the cycle's own time, us)")
    for variant, (cycles, late, worst, messages) in totals.items():
        share = 100.0 * late / cycles if cycles else float("nan")
        p50, p99, p999 = np.percentile(np.array(busy[variant]) * 1e6, [50, 99, 99.9])
        print(
            f"{variant:>9} {cycles:9d} {late:9d} {share:9.3f} {worst * 1e3:9.2f} {messages:9d} "
            f"{p50:9.0f} {p99:9.0f} {p999:9.0f}"
        )


if __name__ == "__main__":
    main()
