"""Monte Carlo of pose design: how much a designed pose set and the joint method gain.

Run by hand (not a test): ``.venv/bin/python bench/bench_design.py [--trials 200]``.

Each seeded trial draws 500 readings per pose with the paper's noise (Gaussian, one resolution
count: 0.125 N, 0.003 N*m per reading) for the paper's tool, bias and tilt, and identifies:

- the paper's method at the paper's nine poses (the baseline);
- the joint method at the paper's nine poses;
- the joint method at nine poses designed by ``ftcomp poses design`` (D-optimal, greedy plus
  exchange, on the joint model's Fisher information), for several ``--max-tilt-deg``.

It prints the RMS error over trials of G, F0, M0 and P (vectors by their norm) and the ratio of
the baseline's to each. Then the search check: the design's predicted errors (the Fisher
information's, no noise) against the best nine-pose set a large random-restart exchange search
finds on the same candidate grid (``RESTARTS`` random starts, each exchanged to a local optimum).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from ftcomp import paper
from ftcomp.calibration.design import (
    _exchange,
    _logdet,
    candidate_orientations,
    design_poses,
    fisher_blocks,
    nominal_theta,
    predicted_std_errors,
)
from ftcomp.calibration.identify import calibrate
from ftcomp.model import GravityModel
from ftcomp.samples import Samples

NOISE_6 = np.repeat([0.125, 0.003], 3)
PER_POSE = 500
RESTARTS = 100

TRUTH = GravityModel(
    paper.TOOL_WEIGHT_N,
    np.array(paper.CENTER_OF_GRAVITY_M),
    np.array(paper.FORCE_BIAS_N),
    np.array(paper.TORQUE_BIAS_Nm),
    tilt_U_rad=np.radians(paper.TILT_DEG[0]),
    tilt_V_rad=np.radians(paper.TILT_DEG[1]),
)


def errors(R: np.ndarray, method: str, rng: np.random.Generator) -> np.ndarray:
    """``|estimate - truth|`` of G, F0, M0, P for one trial at poses ``R``."""
    pose = np.repeat(np.arange(len(R)), PER_POSE)
    w = TRUTH.predict(R[pose]) + rng.standard_normal((len(pose), 6)) * NOISE_6
    samples = Samples(w, R[pose], "quaternion", pose=pose.astype(str), source="monte carlo")
    m = calibrate(samples, method=method, leave_one_out=False).model  # type: ignore[arg-type]
    return np.array(
        [
            abs(m.weight_N - TRUTH.weight_N),
            np.linalg.norm(m.force_bias_N - TRUTH.force_bias_N),
            np.linalg.norm(m.torque_bias_Nm - TRUTH.torque_bias_Nm),
            np.linalg.norm(m.center_of_gravity_m - TRUTH.center_of_gravity_m),
        ]
    )


def rms(R: np.ndarray, method: str, trials: int, seed: int) -> np.ndarray:
    """RMS over seeded trials of the errors of G, F0, M0, P."""
    e = np.array([errors(R, method, np.random.default_rng([seed, k])) for k in range(trials)])
    return np.sqrt(np.mean(e**2, axis=0))


def best_by_search(candidates: np.ndarray, theta: np.ndarray, count: int, seed: int) -> float:
    """The largest log det F a random-restart exchange search finds (``RESTARTS`` starts)."""
    blocks = fisher_blocks(candidates, theta)
    ridge = 1e-9 * np.trace(blocks.mean(axis=0)) / 12 * np.eye(12)
    rng = np.random.default_rng(seed)
    best = -np.inf
    for _ in range(RESTARTS):
        start = list(rng.choice(len(candidates), count, replace=False))
        chosen = _exchange(blocks, np.zeros((12, 12)), start, ridge)
        best = max(best, float(_logdet(blocks[chosen].sum(axis=0))))
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=200)
    parser.add_argument("--seed", type=int, default=2020)
    args = parser.parse_args()
    theta = nominal_theta()
    R_paper = paper.paper_poses().rotations.as_matrix()
    names = ("G", "F0", "M0", "P")
    start = time.perf_counter()
    base = rms(R_paper, "paper", args.trials, args.seed)
    joint_paper = rms(R_paper, "joint", args.trials, args.seed)
    print(f"{args.trials} seeded trials, {PER_POSE} readings per pose, paper noise and tool")
    print("RMS error: " + ", ".join(f"{n} {v:.3g}" for n, v in zip(names, base, strict=True)))
    print("  paper method, paper poses: ratio 1 (baseline)")
    ratios = base / joint_paper
    print(
        "  joint method, paper poses:  "
        + "  ".join(f"{n} {r:.2f}x" for n, r in zip(names, ratios, strict=True))
    )
    for tilt in (180.0, 90.0):
        candidates = candidate_orientations(tilt)
        designed = design_poses(9, candidates, theta)
        joint_design = rms(designed, "joint", args.trials, args.seed)
        ratios = base / joint_design
        print(
            f"  joint method, 9 designed poses (--max-tilt-deg {tilt:g}): "
            + "  ".join(f"{n} {r:.2f}x" for n, r in zip(names, ratios, strict=True))
        )
        found = best_by_search(candidates, theta, 9, args.seed)
        ours = float(_logdet(fisher_blocks(designed, theta).sum(axis=0)))
        se_ours = predicted_std_errors(designed, theta)
        # D-efficiency: (det F_ours / det F_best)^(1/12): the geometric-mean ratio of the
        # predicted standard errors is its inverse.
        efficiency = np.exp((ours - max(found, ours)) / 12)
        se_paper = predicted_std_errors(R_paper, theta)
        gain = "  ".join(
            f"{n} {np.linalg.norm(se_paper[n]) / np.linalg.norm(se_ours[n]):.2f}x" for n in names
        )
        print(
            f"    predicted SE gain over the joint method at the paper's poses: {gain}; "
            f"D-efficiency against the best of {RESTARTS} random-restart exchange searches: "
            f"{efficiency:.4f} (predicted errors {100 * (1 / efficiency - 1):.2f} % above)"
        )
    print(f"({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
