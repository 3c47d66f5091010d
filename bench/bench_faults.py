"""Stress: each robot fault of the UR twin ends ``ftcomp run`` with exit 1 and a whole log.

For each fault (``rtde-stop``, ``network-loss``, ``protective-stop``, ``script-stop``), ``--tries``
times: a fresh ``ftcomp twin --fault NAME --fault-at-s 1.5`` on its own loopback pair, ``ftcomp
run`` with admittance on z for 4 s (as tests/devices/test_conformance.py runs it), then counts
how it ended: exit 1 with the fault's message and "the robot was stopped" (the documented end),
another exit code (-6 is ur_rtde's ``terminate called without an active exception`` in its
teardown, the crash issue 34 saw once), a hang (killed after 30 s), and whether the log is whole
(every row complete, times finite and in order).

    python bench/bench_faults.py --tries 50            # all four faults, 50 each
    python bench/bench_faults.py --tries 10 --fault rtde-stop

Prints one line per fault: ``rtde-stop: 50/50 exit 1 with a valid log`` and, if any, what the
others were. Exit status 1 if any try did not end as documented.
"""

from __future__ import annotations

import argparse
import collections
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

FAULTS = ("rtde-stop", "network-loss", "protective-stop", "script-stop")
#: What run's error line says on each (ftcomp.hardware.devices' declarations).
SAYS = {
    "rtde-stop": "no new data from the controller",
    "network-loss": "stale_sample",
    "protective-stop": "the arm is in a protective stop",
    "script-stop": "the controller refused speedL",
}
CLIENT = "import sys; from ftcomp.cli import main; sys.exit(main())"
#: The fault this long after run's robot stream starts [s]: run's loop is going by then (0.3 s
#: after the connection on a quiet host, more on a loaded one; a fault before it tests nothing).
FAULT_AT_S = 1.5
#: run's stale limit [ms], as tests/devices/test_conformance.py runs it: the twin's own stream
#: stalls 20-57 ms on a shared host, which is no fault of the robot's.
STALE_MS = 75


def _calibration(truth: Path, out: Path) -> None:
    """A calibration file with the twin's true tool (the run needs a compensation only)."""
    from ftcomp.io.calibration_json import FORMAT

    doc = json.loads(truth.read_text())
    keys = ("tool_weight_N", "center_of_gravity_m", "force_bias_N", "torque_bias_Nm")
    data = {k: doc[k] for k in (*keys, "base_tilt_deg", "gravity_in_base_N")}
    out.write_text(json.dumps({"format": FORMAT, "method": "paper", **data}))


def _log_whole(path: Path) -> bool:
    try:
        with path.open() as f:
            rows = list(csv.reader(f))
    except OSError:
        return False
    if len(rows) < 2 or any(len(r) != len(rows[0]) for r in rows[1:]):
        return False
    try:
        t = [float(r[0]) for r in rows[1:]]
    except ValueError:
        return False
    return all(math.isfinite(v) for v in t) and t == sorted(t)


def one_try(fault: str, k: int, folder: Path, args_dump: Path | None = None) -> str:
    """One twin and one run; how it ended (``ok`` or what went wrong)."""
    robot, sensor = f"127.0.{134 + k % 100}.{10 + FAULTS.index(fault) * 2}", ""
    sensor = robot.rsplit(".", 1)[0] + "." + str(int(robot.rsplit(".", 1)[1]) + 1)
    truth, cal, log = folder / "truth.json", folder / "cal.json", folder / "run.csv"
    for p in (truth, cal, log):
        p.unlink(missing_ok=True)
    twin = subprocess.Popen(
        [sys.executable, "-m", "ftcomp", "twin", "--robot-host", robot, "--sensor-host", sensor,
         "--seconds", "60", "--truth", str(truth), "--fault", fault, "--fault-at-s",
         str(FAULT_AT_S)],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )  # fmt: skip
    try:
        assert twin.stdout is not None
        line = twin.stdout.readline()
        if not line.startswith("twin ready:"):
            return f"twin did not start: {line!r}"
        words = line.split()
        robot_uri, sensor_uri = words[words.index("robot") + 1], words[words.index("sensor") + 1]
        _calibration(truth, cal)
        try:
            done = subprocess.run(
                [sys.executable, "-X", "faulthandler", "-c", CLIENT, "run", "--robot", robot_uri,
                 "--sensor", sensor_uri, "-c", str(cal), "--control", "admittance", "--axes", "z",
                 "--settle-band-N", "0.0001", "--seconds", "4", "--max-late-cycles", "50",
                 "--stale-ms", str(STALE_MS), "-o", str(log)],
                capture_output=True, text=True, timeout=30.0, check=False, env=dict(os.environ),
            )  # fmt: skip
        except subprocess.TimeoutExpired:
            return "hang (killed after 30 s)"
        if done.returncode != 1:
            if args_dump is not None:
                (args_dump / f"{fault}-{k}.stderr").write_text(done.stderr)
            tail = (done.stderr.strip().splitlines() or [""])[0]
            return f"exit {done.returncode}: {tail}"
        if SAYS[fault] not in done.stderr or "the robot was stopped" not in done.stderr:
            return f"exit 1 without the documented message: {done.stderr.strip()[-200:]}"
        if not _log_whole(log):
            return "exit 1, log not whole"
        return "ok"
    finally:
        twin.terminate()
        try:
            twin.wait(timeout=5)
        except subprocess.TimeoutExpired:
            twin.kill()
            twin.wait(timeout=5)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tries", type=int, default=50)
    parser.add_argument("--fault", choices=FAULTS, action="append")
    parser.add_argument("--verbose", action="store_true", help="one line per try")
    parser.add_argument("--dump", type=Path, help="write each failed try's stderr here")
    args = parser.parse_args()
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for fault in args.fault or FAULTS:
            ends: collections.Counter[str] = collections.Counter()
            t0 = time.monotonic()
            for k in range(args.tries):
                end = one_try(fault, k, Path(tmp), args.dump)
                ends[end] += 1
                if args.verbose:
                    print(f"  {fault} try {k + 1}: {end}", flush=True)
            ok = ends.pop("ok", 0)
            failed += args.tries - ok
            others = "; ".join(f"{n}x {why}" for why, n in ends.most_common())
            print(
                f"{fault}: {ok}/{args.tries} exit 1 with a valid log "
                f"({time.monotonic() - t0:.0f} s)" + (f"; others: {others}" if others else ""),
                flush=True,
            )
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
