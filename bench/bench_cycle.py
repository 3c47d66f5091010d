"""Time one whole live control cycle by part, and its total against another commit's.

Run by hand (not a test), from the repository root::

    .venv/bin/python bench/bench_cycle.py                       # against HEAD~1
    .venv/bin/python bench/bench_cycle.py --baseline-rev 9237642
    .venv/bin/python bench/bench_cycle.py --baseline-rev none   # this tree only

A cycle is what ``ftcomp run`` does each period: :class:`ftcomp.control.loop.ControlCycle`
around the admittance step, with a log row per cycle. Its parts, timed one after the other in
each cycle:

=============  =====================================================================
read           ``sensor.read()``
pose           ``robot.pose()`` and ``Mount.sensor_pose`` (a mount with an offset)
compensate     the cycle's ``WrenchPipeline.contact`` (``GravityCompensator.compensate``) and
               its ``Reading`` record
step           ``AdmittanceController.step`` (combined law on z, 20 Hz low-pass, base frame,
               the raw reading passed for the frozen-value and range checks)
settle         the settle rule of ``ftcomp run``: the error the step acted on through a 2 Hz
               first-order low-pass (``LowPassFilter.step`` on 6 channels), its z within a band
log            one row of ``ftcomp run``'s columns: ``format_row`` and a ``csv.writer`` on
               ``/dev/null``
command        ``ControlCycle.command``: ``Mount.tcp_twist`` and ``robot.command_twist``
=============  =====================================================================

The backends cost nothing themselves, so what is timed is ftcomp's own code: the robot is
``fixed://`` (its pose on the host's clock) taking any twist, the sensor a fake that returns a
recorded-like ramp (a hanging load set down, with sensor noise), stamped on the host's clock.
The whole cycle is also timed end to end (``cycle.read()``, step, log, ``cycle.command()``).

Against another commit: that commit's ``src`` is exported (``git archive REV src``) into a
temporary directory, and this same file runs as a worker process on each tree (``PYTHONPATH``;
the worker only uses names both trees have). The two workers take turns every ``--block``
cycles, in alternating order, so that the machine's noise hits both alike; the medians are over
all the cycles of each tree. Both first run one whole ramp untimed (the warm-up), whose twists
are compared: the two trees must compute the same commands. A tree against itself
(``--baseline-rev HEAD`` on a clean tree) gives a ratio within about 1 % of 1 on this
project's shared 2-core machine.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

PARTS = ("read", "pose", "compensate", "step", "settle", "log", "command")
DT = 1e-3
REPO = Path(__file__).resolve().parent.parent


# --- The worker: one tree's cycle ---------------------------------------------------------------


def _ramp(n: int) -> np.ndarray:
    """Raw readings (n, 6) [N, N*m], sensor frame: tool and a 0.5 kg load set down, with noise."""
    rng = np.random.default_rng(0)
    w = np.zeros((n, 6))
    w[:, 2] = 3.153 + 0.5 * 9.81 * np.linspace(1.0, 0.0, n)  # hanging along sensor +z
    w[:, 3] = 0.02 * w[:, 2]
    w += np.array([-0.8613, 1.1015, 0.1976, -0.0002, -0.0605, 0.0255])  # the bias
    return w + rng.normal(scale=[0.05, 0.05, 0.05, 0.003, 0.003, 0.003], size=(n, 6))


class _Sensor:
    """A sensor that costs nothing: the next row of a recorded-like ramp, stamped now."""

    def __init__(self, wrenches: np.ndarray) -> None:
        from ftcomp.hardware.protocols import WrenchSample

        self._rows = [row.copy() for row in wrenches]
        self._k = 0
        self._sample = WrenchSample.owning

    def rewind(self) -> None:
        """Start the ramp again."""
        self._k = 0

    def read(self) -> Any:
        row = self._rows[self._k % len(self._rows)]
        self._k += 1
        return self._sample(time.monotonic_ns(), row)

    def __enter__(self) -> _Sensor:
        return self

    def __exit__(self, *exc: object) -> None:
        return None


class _Robot:
    """``fixed://`` that accepts any twist (the real one refuses to move) and never waits."""

    def __init__(self, fixed: Any) -> None:
        self._fixed = fixed
        self.control_period_s = DT
        self.twist: Any = None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._fixed, name)

    def pose(self) -> Any:
        return self._fixed.pose()

    def command_twist(self, twist_base: Any) -> None:
        self.twist = twist_base

    def wait_cycle(self) -> None:
        return None

    def stop(self) -> None:
        return None


def _setup(cycles: int) -> tuple[Any, Any]:
    """(cycle, controller) as ``ftcomp run`` builds them, on costless backends."""
    import ftcomp
    from bench_compensate import MODEL  # this folder is on the path: the script's own
    from ftcomp.control import (
        AdmittanceController,
        CombinedLaw,
        LowPassFilter,
        SafetyLimits,
        selection_matrix,
    )
    from ftcomp.control.loop import ControlCycle

    robot = _Robot(ftcomp.open_robot("fixed://?rpy_deg=180,3,15&xyz_mm=400,0,300"))
    mount = ftcomp.Mount.from_xyz_rpy((0.0, 0.0, 0.03), (0.0, 0.0, 90.0))
    cycle = ControlCycle(
        robot, _Sensor(_ramp(cycles + 1)), mount=mount, compensator=ftcomp.GravityCompensator(MODEL)
    )
    limits = SafetyLimits(
        max_twist=[0.05, 0.05, 0.05, 0.5, 0.5, 0.5],
        max_twist_rate=[0.5, 0.5, 0.5, 5.0, 5.0, 5.0],
        max_travel=10.0,  # never stops: a stopped step returns early and times nothing
        max_force_N=100.0,
        max_torque_Nm=10.0,
        stale_after_s=0.5,
    )
    controller = AdmittanceController(
        law=CombinedLaw(1e-4, 1e-3, selection_matrix("z")),
        wrench_filter=LowPassFilter(20.0, DT),
        limits=limits,
        frame="base",
    )
    return cycle, controller


def _step(controller: Any, state: Any, r: Any) -> tuple[Any, Any]:
    """The controller's step on a cycle's reading, as ``ftcomp run`` calls it."""
    return controller.step(
        state,
        r.t_sample_ns * 1e-9,
        r.wrench_contact_sensor,
        r.R_base_sensor,
        r.now_ns * 1e-9,
        DT,
        wrench_raw_sensor=r.wrench_raw_sensor,
    )


def _row(t0_ns: int, r: Any, state: Any, twist: Any) -> list[float]:
    """A row of ``ftcomp run``'s log: time, raw, contact, the force error the step acted on
    (``state.law.wrench_error``), twist, sensor position, the "sent" flag."""
    return [
        (r.now_ns - t0_ns) * 1e-9,
        *r.wrench_raw_sensor.tolist(),
        *r.wrench_contact_sensor.tolist(),
        *state.law.wrench_error[:3].tolist(),
        *twist.tolist(),
        *r.p_base_sensor.tolist(),
        1.0,
    ]


class _Run:
    """One tree's cycle, run block by block over the ramp (rewound, bumpless, at its end)."""

    def __init__(self, ramp_cycles: int) -> None:
        from ftcomp.control import LowPassFilter
        from ftcomp.control.loop import Reading

        try:  # where the log row's formatting lives (io.timestamps since the layered io)
            from ftcomp.io.timestamps import format_row
        except ImportError:
            from ftcomp.io.numtext import format_row  # type: ignore[attr-defined, no-redef]

        self.cycle, self.controller = _setup(ramp_cycles)
        self.settle_filter = LowPassFilter(2.0, DT, order=1, channels=6)
        self.ramp_cycles = ramp_cycles
        self.reading, self.format_row = Reading, format_row
        self.sink = open(os.devnull, "w", newline="")  # noqa: SIM115 (closed with the process)
        self.writer = csv.writer(self.sink)
        self._restart()

    def _restart(self) -> None:
        self.cycle.sensor.rewind()
        first = self.cycle.read()
        w0, R0 = first.wrench_contact_sensor, first.R_base_sensor
        self.state = self.controller.initial_state(w0, R0)
        self.settle_state = self.settle_filter.initial_state(self.controller.wrench_error(w0, R0))
        self.t0_ns, self.left = first.now_ns, self.ramp_cycles

    def _next(self) -> None:
        """Before each cycle: the ramp starts again at its end, and the controller still runs."""
        if self.state.stop_reason is not None:  # a stopped step returns early: nothing timed
            raise RuntimeError(f"the controller stopped ({self.state.stop_reason}): fix the bench")
        if self.left == 0:
            self._restart()
        self.left -= 1

    def _settled(self) -> bool:
        """The settle rule's cycle: filter the error the step acted on, check its z (0.5 N)."""
        self.settle_state, error = self.settle_filter.step(
            self.settle_state, self.state.law.wrench_error
        )
        return bool(abs(error[2]) <= 0.5)

    def _log(self, r: Any, twist: Any) -> None:
        self.writer.writerow(self.format_row(_row(self.t0_ns, r, self.state, twist)))

    def by_part(self, n: int) -> tuple[list[list[int]], list[Any]]:
        """``n`` cycles timed by part: per cycle the durations of PARTS [ns]; and the twists."""
        cycle, controller = self.cycle, self.controller
        sensor, robot, mount = cycle.sensor, cycle.robot, cycle.mount
        # The cycle's compensation: its wrench pipeline (from b1f8e00 on), else its compensator.
        pipeline = getattr(cycle, "pipeline", None)
        comp = cycle.compensator if pipeline is None else None
        Reading, clock = self.reading, time.perf_counter_ns
        times, twists = [], []
        for _ in range(n):
            self._next()
            a = clock()
            sample = sensor.read()
            b = clock()
            pose = robot.pose()
            p, R = mount.sensor_pose(pose.p_base_tcp, pose.R_base_tcp)
            c = clock()
            raw = sample.wrench_sensor
            if pipeline is not None:
                contact = pipeline.contact(sample.t_ns, raw, R)
            else:
                contact = comp.compensate(raw, R)
            r = Reading(sample.t_ns, pose.t_ns, raw, contact, p, R, pose.R_base_tcp)
            d = clock()
            self.state, twist = _step(controller, self.state, r)
            e = clock()
            self._settled()
            f = clock()
            self._log(r, twist)
            g = clock()
            cycle.command(twist, r)
            h = clock()
            times.append([b - a, c - b, d - c, e - d, f - e, g - f, h - g])
            twists.append(twist.tolist())
        return times, twists

    def whole(self, n: int) -> list[int]:
        """``n`` cycles timed end to end, as ``run_loop`` runs them [ns]."""
        cycle, controller, clock = self.cycle, self.controller, time.perf_counter_ns
        times = []
        for _ in range(n):
            self._next()
            a = clock()
            r = cycle.read()
            self.state, twist = _step(controller, self.state, r)
            self._settled()
            self._log(r, twist)
            cycle.command(twist, r)
            times.append(clock() - a)
        return times


def worker(ramp_cycles: int) -> None:
    """Serve the parent: read ``part N``, ``whole N``, ``twists`` or ``quit`` lines on stdin and
    answer each with one JSON line (durations [ns], or the twists of one whole ramp)."""
    import ftcomp

    run = _Run(ramp_cycles)
    print(json.dumps({"ftcomp": str(Path(ftcomp.__file__).parent)}), flush=True)
    for line in sys.stdin:
        command, *arg = line.split()
        if command == "part":
            answer: Any = run.by_part(int(arg[0]))[0]
        elif command == "whole":
            answer = run.whole(int(arg[0]))
        elif command == "twists":  # one whole ramp from its start: also the warm-up
            run._restart()
            answer = run.by_part(ramp_cycles)[1]
            run._restart()
        else:
            return
        print(json.dumps(answer), flush=True)


# --- The parent: both trees block by block, and the table ---------------------------------------


class _Worker:
    """This file running as a worker on one tree's ``src`` (``PYTHONPATH``)."""

    def __init__(self, src: Path, ramp_cycles: int) -> None:
        env = {**os.environ, "PYTHONPATH": str(src)}
        self.process = subprocess.Popen(
            [sys.executable, __file__, "--worker", f"--cycles={ramp_cycles}"],
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        imported = Path(self._answer()["ftcomp"]).resolve()
        if imported != (src / "ftcomp").resolve():
            raise RuntimeError(f"the worker imported {imported}, not {src / 'ftcomp'}")
        self.parts: list[list[int]] = []
        self.whole: list[int] = []

    def ask(self, command: str) -> Any:
        assert self.process.stdin is not None
        self.process.stdin.write(command + "\n")
        self.process.stdin.flush()
        return self._answer()

    def _answer(self) -> Any:
        assert self.process.stdout is not None
        line = self.process.stdout.readline()
        if not line:
            raise RuntimeError(f"the worker ended (exit code {self.process.wait()})")
        return json.loads(line)

    def close(self) -> None:
        assert self.process.stdin is not None
        self.process.stdin.close()  # the worker's loop over stdin ends
        self.process.wait()


def _export(rev: str, into: Path) -> str:
    """``git archive REV src | tar -x -C into``; returns the short hash."""
    short = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", "--short", rev],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    archive = subprocess.run(
        ["git", "-C", str(REPO), "archive", rev, "src"], check=True, capture_output=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    return short


def _medians(worker: _Worker) -> dict[str, float]:
    """Median of each part, of their sum per cycle, and of the whole cycle, p99 too [us]."""
    parts = np.array(worker.parts) * 1e-3
    whole = np.array(worker.whole) * 1e-3
    out = {name: float(np.median(parts[:, i])) for i, name in enumerate(PARTS)}
    out["sum"] = float(np.median(parts.sum(axis=1)))
    out["whole"] = float(np.median(whole))
    out["whole p99"] = float(np.percentile(whole, 99))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    parser.add_argument("--baseline-rev", default="HEAD~1", help="a git rev, or 'none'")
    parser.add_argument("--cycles", type=int, default=20_000, help="timed cycles per mode")
    parser.add_argument("--block", type=int, default=200, help="cycles per turn of a tree")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    ramp_cycles = 3000  # 3 s at 1 kHz, then the ramp starts again
    if args.worker:
        worker(args.cycles)
        return

    with tempfile.TemporaryDirectory(prefix="bench_cycle_") as tmp:
        labels, workers = ["this tree"], [_Worker(REPO / "src", ramp_cycles)]
        if args.baseline_rev != "none":
            short = _export(args.baseline_rev, Path(tmp))
            labels.append(f"{args.baseline_rev} ({short})")
            workers.append(_Worker(Path(tmp) / "src", ramp_cycles))
        twists = [np.array(w.ask("twists")) for w in workers]  # warms both up
        for k in range(max(1, args.cycles // args.block)):
            # Take turns block by block, in alternating order, so the noise hits both trees.
            order = workers if k % 2 == 0 else workers[::-1]
            for w in order:
                w.parts += w.ask(f"part {args.block}")
            for w in order[::-1]:
                w.whole += w.ask(f"whole {args.block}")
        for w in workers:
            w.close()

    ours = _medians(workers[0])
    base = _medians(workers[1]) if len(workers) > 1 else None
    print(
        f"one live cycle by part, {len(workers[0].parts)} cycles per tree, taking turns every "
        f"{args.block} cycles; medians [us]"
    )
    header = f"{'part':<12}{'median us':>10}{'share':>7}"
    print(header + (f"{labels[1]:>22}{'ratio':>7}" if base else ""))
    for name, us in ours.items():
        share = f"{us / ours['sum']:7.0%}" if name in (*PARTS, "sum") else " " * 7
        line = f"{name:<12}{us:>10.2f}{share}"
        if base:
            line += f"{base[name]:>22.2f}{us / base[name]:>7.2f}"
        print(line)
    print("sum: the parts added per cycle; whole: the cycle timed end to end (as run_loop runs it)")
    if base:
        diff = float(np.max(np.abs(twists[0] - twists[1])))
        change = ours["whole"] / base["whole"] - 1.0
        print(
            f"whole cycle: this tree {ours['whole']:.2f} us, {labels[1]} {base['whole']:.2f} us, "
            f"ratio {ours['whole'] / base['whole']:.3f} (this / baseline): this tree's cycle "
            f"is {abs(change):.1%} {'shorter' if change < 0 else 'longer'}"
        )
        print(f"largest |twist difference| between the trees over one ramp: {diff:.1e}")


if __name__ == "__main__":
    main()
