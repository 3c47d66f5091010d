"""Bias drift and re-bias on simulated recordings: held-out errors against the noise floor.

Run by hand (not a test): ``.venv/bin/python bench/bench_drift.py [--seeds 5] [--walk-N 0.05]``.

Each seed runs :func:`ftcomp.huang2020.drift_sim.run_drift_experiment` (the MuJoCo cell by
URI with a drifting sensor, recorded as ``ftcomp record`` does): 12 D-optimal orientations
visited twice in shuffled passes (500 readings each), a few tenths of a newton of drift over
the recording; leave-one-orientation-out errors of the ``none``, ``linear`` and ``quadratic``
drift fits in units of the noise floor (a visit mean's noise); then 30 s more drift, a fresh
calibration against ``rebias`` from 2 s at one pose, judged on 12 new orientations recorded
right after. Prints one row per seed and the mean of each column:

- ``none/floor`` .. ``quad/floor``: held-out force error of each drift fit / the floor;
- ``fresh/floor``, ``rebias/floor``, ``rebias/fresh``: the check error of the fresh calibration
  and of the re-bias, the drift since each bias was measured removed (the simulator's rate);
  ``stale/floor``: the first calibration without re-bias, judged the same way;
- ``fresh raw``: the fresh calibration applying its drift model from ``t`` (no truth used);
  ``rebias raw``: the re-bias as a constant, the drift during the check poses left in;
- ``time ratio``: re-bias collection time / fresh calibration's (simulated seconds);
- ``linear T``, ``rebias/fresh T``: the same for the torques.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from ftcomp.huang2020.drift_sim import DriftSetup, run_drift_experiment

COLUMNS = (
    "none/floor",
    "linear/floor",
    "quad/floor",
    "fresh/floor",
    "rebias/floor",
    "rebias/fresh",
    "stale/floor",
    "fresh raw",
    "rebias raw",
    "time ratio",
    "linear T",
    "rebias/fresh T",
)


def row(seed: int, walk_N: float) -> list[float]:
    """One seed's ratios (force; the last two torque), in the order of :data:`COLUMNS`."""
    fits, c = run_drift_experiment(DriftSetup(seed=seed, drift_walk_N=walk_N))
    f = fits.floor.force_N
    return [
        fits.held_out["none"].force_N / f,
        fits.held_out["linear"].force_N / f,
        fits.held_out["quadratic"].force_N / f,
        c.fresh.over(c.floor)[0],
        c.rebiased.over(c.floor)[0],
        c.rebiased.force_N / c.fresh.force_N,
        c.stale.over(c.floor)[0],
        c.fresh_raw.over(c.floor)[0],
        c.rebiased_raw.over(c.floor)[0],
        c.time_ratio,
        fits.held_out["linear"].over(fits.floor)[1],
        c.rebiased.torque_Nm / c.fresh.torque_Nm,
    ]


def main() -> None:
    """Run the seeds and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5, help="seeds 0..N-1 (default 5)")
    parser.add_argument(
        "--walk-N", type=float, default=0.0, help="bias random walk, std after 1 min [N]"
    )
    args = parser.parse_args()
    setup = DriftSetup(drift_walk_N=args.walk_N)
    print(f"robot: {setup.robot_uri}")
    print("errors in units of the noise floor (RMS of a visit mean's noise); force, T: torque")
    print("seed " + " ".join(f"{c:>12}" for c in COLUMNS))
    rows = []
    start = time.perf_counter()
    for seed in range(args.seeds):
        rows.append(row(seed, args.walk_N))
        print(f"{seed:4d} " + " ".join(f"{v:12.3f}" for v in rows[-1]), flush=True)
    mean = np.mean(rows, axis=0)
    print("mean " + " ".join(f"{v:12.3f}" for v in mean))
    print(f"({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
