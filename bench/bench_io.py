"""Benchmark reading and writing recordings at real size, and calibration against pose count.

Run by hand (not a test): ``.venv/bin/python bench/bench_io.py [--rows 1000000]``.

1. ``ftcomp compensate`` on a generated sample CSV (``t,qx,qy,qz,qw,fx..tz``, about 120 bytes a
   row, like a logged Net F/T stream), run as a user runs it, beside a plain
   ``numpy.loadtxt`` + compensate + ``numpy.savetxt`` script on the same file in the same run:
   wall time, rows/s and peak memory (max RSS) of each process. Goals: peak memory under
   500 MB and the same at any row count; at least 3x faster than the baseline.
2. ``--bad-cell``: the same file with one bad cell deep inside: one ``error:`` line naming
   its row and column, exit code 2, no output file.
3. ``ftcomp calibrate`` time against pose count (9 to 10,000 poses): the library call for both
   methods, and the command end to end (``--json``, and with its printed tables).

Every file lives in a temporary directory removed at the end. ``--no-baseline`` skips the
baseline (a 25 M-row baseline needs about 10 GB and half an hour).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ftcomp.calibration.identify import calibrate
from ftcomp.model import GravityModel
from ftcomp.samples import Samples

PYTHON = sys.executable
PAPER_CSV = (
    Path(__file__).resolve().parents[1] / "src" / "ftcomp" / "data" / "huang2020_table1_2.csv"
)
TOOL = GravityModel(
    3.153,
    np.array([0.0001, -0.0003, 0.047]),
    np.array([-0.8613, 1.1015, 0.1976]),
    np.array([-0.0002, -0.0605, 0.0255]),
    tilt_U_rad=np.radians(-0.204),
    tilt_V_rad=np.radians(-0.129),
)
HEADER = "t,qx,qy,qz,qw,fx,fy,fz,tx,ty,tz\n"
BLOCK_ROWS = 100_000

BASELINE = """
import sys, numpy as np
from scipy.spatial.transform import Rotation
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.io.calibration_json import load_calibration
src, cal, out = sys.argv[1:4]
with open(src) as f:
    header = f.readline().strip()
data = np.loadtxt(src, delimiter=",", skiprows=1)
R = Rotation.from_quat(data[:, 1:5]).as_matrix()
contact = GravityCompensator(load_calibration(cal)).compensate(data[:, 5:11], R)
weight = np.linalg.norm(contact[:, :3], axis=1)
np.savetxt(out, np.column_stack([data, contact, weight]), delimiter=",", fmt="%.10g",
           header=header + ",fx_ext,fy_ext,fz_ext,tx_ext,ty_ext,tz_ext,load_weight_N", comments="")
"""


def _block_text(rng: np.random.Generator, start_row: int = 0, bad_row: int | None = None) -> str:
    """BLOCK_ROWS rows of a recording at 1 kHz, the tool turning slowly, with sensor noise."""
    t = (start_row + np.arange(BLOCK_ROWS)) / 1000.0
    R = Rotation.from_rotvec(np.outer(np.sin(t / 7.0), [0.9, 0.4, 0.2])) * Rotation.from_euler(
        "x", 180, degrees=True
    )
    wrench = TOOL.predict(R.as_matrix()) + rng.normal(size=(BLOCK_ROWS, 6)) * np.repeat(
        [0.05, 0.002], 3
    )
    rows = np.column_stack([t, R.as_quat(canonical=True), wrench])
    fmt = "%.3f,%.8f,%.8f,%.8f,%.8f,%.5f,%.5f,%.5f,%.6f,%.6f,%.6f\n"
    lines = [fmt % tuple(r) for r in rows.tolist()]
    if bad_row is not None:
        cells = lines[bad_row].split(",")
        cells[7] = "3_3445"  # fz
        lines[bad_row] = ",".join(cells)
    return "".join(lines)


def write_recording(path: Path, rows: int, bad_row: int | None = None) -> None:
    """A sample CSV of ``rows`` rows: one generated block, repeated (t repeats with it)."""
    rng = np.random.default_rng(0)
    block = _block_text(rng)
    with open(path, "w") as f:
        f.write(HEADER)
        for start in range(0, rows, BLOCK_ROWS):
            n = min(BLOCK_ROWS, rows - start)
            if bad_row is not None and start <= bad_row < start + BLOCK_ROWS:
                text = _block_text(np.random.default_rng(0), 0, bad_row - start)
            else:
                text = block
            f.write(text if n == BLOCK_ROWS else "".join(text.splitlines(True)[:n]))


def run_measured(argv: list[str]) -> tuple[float, float, int, str]:
    """Run a process; its wall time [s], peak memory [MB], exit code and stderr."""
    with tempfile.TemporaryFile() as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        err.seek(0)
        return (
            wall,
            usage.ru_maxrss / 1024.0,
            os.waitstatus_to_exitcode(status),
            err.read().decode(),
        )


def bench_compensate(tmp: Path, rows: int, baseline: bool, repeats: int) -> None:
    src, cal = tmp / "rec.csv", tmp / "cal.json"
    t0 = time.perf_counter()
    write_recording(src, rows)
    print(
        f"generated {rows:,} rows ({src.stat().st_size / 1e6:.0f} MB) in "
        f"{time.perf_counter() - t0:.1f} s"
    )
    subprocess.run(
        [
            PYTHON,
            "-m",
            "ftcomp",
            "calibrate",
            str(PAPER_CSV),
            "--method",
            "paper",
            "-o",
            str(cal),
            "--json",
        ],
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    ours_argv = [PYTHON, "-m", "ftcomp", "compensate", str(src), "-c", str(cal), "-o"]
    results: dict[str, list[tuple[float, float]]] = {"ftcomp compensate": [], "numpy baseline": []}
    for _ in range(repeats):
        out = tmp / "out.csv"
        wall, mem, code, err = run_measured([*ours_argv, str(out), "--force"])
        if code:
            raise SystemExit(f"compensate failed: {err}")
        results["ftcomp compensate"].append((wall, mem))
        out.unlink()
        if baseline:
            wall, mem, code, err = run_measured(
                [PYTHON, "-c", BASELINE, str(src), str(cal), str(out)]
            )
            if code:
                raise SystemExit(f"baseline failed: {err}")
            results["numpy baseline"].append((wall, mem))
            out.unlink()
    print(f"\n{'':20s} {'time [s]':>9s} {'rows/s':>12s} {'peak MB':>8s}")
    for name, runs in results.items():
        for wall, mem in runs:
            print(f"{name:20s} {wall:9.2f} {rows / wall:12,.0f} {mem:8.0f}")
    if baseline:
        ours = min(w for w, _ in results["ftcomp compensate"])
        base = min(w for w, _ in results["numpy baseline"])
        print(
            f"speed-up (best of each) x{base / ours:.1f}; goal >= 3: "
            f"{'met' if base / ours >= 3 else 'NOT met'}"
        )
    peak = max(m for _, m in results["ftcomp compensate"])
    print(f"peak memory {peak:.0f} MB; goal < 500 MB: {'met' if peak < 500 else 'NOT met'}")
    src.unlink()


def bench_bad_cell(tmp: Path, rows: int) -> None:
    src, cal, out = tmp / "bad.csv", tmp / "cal.json", tmp / "out.csv"
    bad_row = int(rows * 0.78)
    write_recording(src, rows, bad_row=bad_row)
    if not cal.exists():
        subprocess.run(
            [PYTHON, "-m", "ftcomp", "calibrate", str(PAPER_CSV), "-o", str(cal), "--json"],
            check=True,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    wall, mem, code, err = run_measured(
        [PYTHON, "-m", "ftcomp", "compensate", str(src), "-c", str(cal), "-o", str(out)]
    )
    print(
        f"\none bad cell at data row {bad_row + 1:,} of {rows:,}: exit {code} after {wall:.1f} s, "
        f"{mem:.0f} MB; output file {'EXISTS' if out.exists() else 'absent'}; "
        f"leftover files: {sorted(p.name for p in tmp.iterdir() if p.name.startswith('.'))}"
    )
    print(f"stderr ({err.count(chr(10))} line): {err.strip()}")
    src.unlink()


def bench_calibrate(tmp: Path, pose_counts: list[int], readings: int) -> None:
    from ftcomp.io.samples_csv import write_samples

    print(f"\ncalibration, {readings} readings per pose [s]")
    print(
        f"{'poses':>7s} {'paper':>8s} {'joint':>8s} {'CLI paper':>10s} {'CLI joint':>10s} "
        f"{'CLI joint, tables':>18s}"
    )
    rng = np.random.default_rng(1)
    for poses in pose_counts:
        R = np.repeat(Rotation.random(poses, rng=rng).as_matrix(), readings, axis=0)
        wrench = TOOL.predict(R) + rng.normal(size=(len(R), 6)) * np.repeat([0.08, 0.006], 3)
        pose = np.repeat(np.arange(1, poses + 1), readings).astype(str)
        samples = Samples(wrench_sensor=wrench, R_base_sensor=R, encoding="quaternion", pose=pose)
        times = []
        for method in ("paper", "joint"):
            t0 = time.perf_counter()
            calibrate(samples, method=method)  # type: ignore[arg-type]
            times.append(time.perf_counter() - t0)
        path = tmp / f"poses{poses}.csv"
        write_samples(path, wrench, Rotation.from_matrix(R), encoding="quaternion", pose=pose)
        for method, extra in (("paper", ["--json"]), ("joint", ["--json"]), ("joint", [])):
            argv = [
                PYTHON,
                "-m",
                "ftcomp",
                "calibrate",
                str(path),
                "--method",
                method,
                "-o",
                str(tmp / "c.json"),
                "--force",
                *extra,
            ]
            wall, _, code, _err = run_measured(argv)
            times.append(wall if code == 0 else float("nan"))
        print(
            f"{poses:7d} {times[0]:8.2f} {times[1]:8.2f} {times[2]:10.2f} {times[3]:10.2f} "
            f"{times[4]:18.2f}"
        )
        path.unlink()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--no-baseline", action="store_true")
    parser.add_argument("--bad-cell", action="store_true", help="also run the bad-cell check")
    parser.add_argument("--poses", default="9,100,1000,10000", help="pose counts; '' skips")
    parser.add_argument("--readings", type=int, default=10, help="readings per pose")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="ftcomp-bench-") as name:
        tmp = Path(name)
        if args.rows:
            bench_compensate(tmp, args.rows, not args.no_baseline, args.repeats)
        if args.bad_cell:
            bench_bad_cell(tmp, args.rows or 1_000_000)
        if args.poses:
            bench_calibrate(tmp, [int(p) for p in args.poses.split(",")], args.readings)


if __name__ == "__main__":
    main()
