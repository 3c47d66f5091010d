"""The temperature-aware bias model on a simulated sensor whose bias follows its temperature.

Run by hand (not a test): ``.venv/bin/python bench/bench_temperature.py [--seeds 10]``.

Each seed simulates a recording (numpy, the sensor model alone: the twin has no thermal model):
36 orientations (tilts up to 60 deg about random axes, random yaw) visited 10 s apart over
6 minutes, 200 readings each; a 0.8 kg tool with its centre of gravity 4 cm off axis; the
sensor's temperature rises and falls (25 degC + 3 degC * sin(2 pi t / 300 s) + 0.5 degC of
warm-up), its bias following it at 0.05-0.12 N/degC and 2-4 mN*m/degC, the reading noise
0.05 N and 2 mN*m per reading, the temperature read to 0.01 degC per pose mean. Each bias
model (:mod:`ftcomp.calibration.temperature`: ``constant``, ``time``, ``temperature``) is
judged by its leave-one-pose-out force error over the noise floor (a pose mean's noise,
0.05 N / sqrt(200)); ``chosen`` is what the evidence rule picks. Prints one row per seed and
the mean; the target: temperature within 1.2x the floor where time does worse.
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.spatial.transform import Rotation

from ftcomp.calibration.temperature import choose_bias_model

POSES = 36
READINGS = 200
SIGMA_F_N = 0.05
SIGMA_M_NM = 0.002
SIGMA_T_C = 0.01
VISIT_S = 10.0


def simulate(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Pose orientations (P, 3, 3), mean readings (P, 6), mean times (P,), temperatures (P,)."""
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(POSES, 3))
    axes[:, 2] = 0.0
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    tilt = np.radians(rng.uniform(0.0, 60.0, POSES))
    yaw = rng.uniform(-np.pi, np.pi, POSES)
    tilted = Rotation.from_rotvec(axes * tilt[:, None])
    R = (tilted * Rotation.from_euler("z", yaw[:, None])).as_matrix()
    t = VISIT_S * np.arange(POSES)
    temperature = 25.0 + 3.0 * np.sin(2.0 * np.pi * t / 300.0) + 0.5 * t / t[-1]
    gravity_base = 0.8 * 9.81 * np.array([0.002, -0.003, -1.0])
    cog = np.array([0.04, -0.01, 0.06])
    k_f = np.array([0.08, -0.05, 0.12])
    k_m = np.array([0.004, -0.003, 0.002])
    f_grav = np.einsum("kji,j->ki", R, gravity_base)
    dT = (temperature - 25.0)[:, None]
    force = f_grav + np.array([0.5, -0.3, 1.2]) + dT * k_f
    torque = np.cross(cog, f_grav) + np.array([0.02, 0.01, -0.03]) + dT * k_m
    noise = rng.normal(size=(POSES, 6)) * np.repeat([SIGMA_F_N, SIGMA_M_NM], 3)
    wrench = np.hstack([force, torque]) + noise / np.sqrt(READINGS)
    measured_T = temperature + rng.normal(0.0, SIGMA_T_C, POSES)
    return R, wrench, t, measured_T


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    args = parser.parse_args()
    floor = SIGMA_F_N / np.sqrt(READINGS)
    print(f"noise floor: {floor * 1e3:.2f} mN per axis (a pose mean's noise)")
    print(f"{'seed':>4} {'constant/floor':>15} {'time/floor':>11} {'temp/floor':>11}  chosen")
    rows = []
    for seed in range(args.seeds):
        R, wrench, t, temperature = simulate(seed)
        choice = choose_bias_model(R, wrench, t, temperature)
        row = [choice.force_rms_N[m] / floor for m in ("constant", "time", "temperature")]
        rows.append(row)
        print(f"{seed:>4} {row[0]:>15.2f} {row[1]:>11.2f} {row[2]:>11.2f}  {choice.model}")
    mean = np.mean(rows, axis=0)
    print(f"mean {mean[0]:>15.2f} {mean[1]:>11.2f} {mean[2]:>11.2f}")


if __name__ == "__main__":
    main()
