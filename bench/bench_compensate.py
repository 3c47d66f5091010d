"""Benchmark gravity compensation: single-sample latency and batch throughput.

Run by hand (not a test): ``.venv/bin/python bench/bench_compensate.py``.
Goals: single-sample ``compensate`` median <= 5 us; batch >= 20 M samples/s on 1,000,000 samples.
Each is printed beside a plain per-sample numpy version timed in the same run, as a ratio, so
the numbers mean something on a shared, noisy machine.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial.transform import Rotation

from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.model import GravityModel

MODEL = GravityModel(
    3.153,
    np.array([0.0001, -0.0003, 0.047]),
    np.array([-0.8613, 1.1015, 0.1976]),
    np.array([-0.0002, -0.0605, 0.0255]),
    tilt_U_rad=np.radians(-0.204),
    tilt_V_rad=np.radians(-0.129),
)


def plain_per_sample(w: np.ndarray, R: np.ndarray) -> np.ndarray:
    """The textbook way: Eq. 20-22 written out with numpy for one sample."""
    g_s = R.T @ MODEL.gravity_base_N
    force = w[:3] - MODEL.force_bias_N - g_s
    torque = w[3:] - MODEL.torque_bias_Nm - np.cross(MODEL.center_of_gravity_m, g_s)
    return np.concatenate([force, torque])


def median_latency_s(func, w: np.ndarray, R: np.ndarray, repeats: int = 20_000) -> float:
    times = np.empty(repeats)
    clock = time.perf_counter_ns
    for i in range(repeats):
        t0 = clock()
        func(w[i % len(w)], R[i % len(R)])
        times[i] = clock() - t0
    return float(np.median(times)) * 1e-9


def main() -> None:
    rng = np.random.default_rng(0)
    n = 1_000_000
    R = Rotation.random(n, rng=rng).as_matrix()
    w = rng.normal(size=(n, 6))
    comp = GravityCompensator(MODEL)

    ours = median_latency_s(comp.compensate, w, R)
    plain = median_latency_s(plain_per_sample, w, R)
    print(f"single sample: compensate {ours * 1e6:.2f} us median; plain numpy {plain * 1e6:.2f} us")
    print(f"  speed-up x{plain / ours:.1f}; goal <= 5 us: {'met' if ours <= 5e-6 else 'NOT met'}")

    comp.compensate(w[:1000], R[:1000])  # warm up
    batch_times = []
    for _ in range(5):
        t0 = time.perf_counter()
        out = comp.compensate(w, R)
        batch_times.append(time.perf_counter() - t0)
    batch = min(batch_times)
    buffer = np.empty((n, 6))
    reuse_times = []
    for _ in range(5):
        t0 = time.perf_counter()
        comp.compensate(w, R, out=buffer)
        reuse_times.append(time.perf_counter() - t0)
    reuse_rate = n / min(reuse_times)
    m = 20_000
    t0 = time.perf_counter()
    for i in range(m):
        plain_per_sample(w[i], R[i])
    loop_rate = m / (time.perf_counter() - t0)
    rate = n / batch
    expected = plain_per_sample(w[123], R[123])
    assert np.allclose(out[123], expected, atol=1e-12), "batch and per-sample results differ"
    print(f"batch of {n:,}: {batch * 1e3:.1f} ms = {rate / 1e6:.1f} M samples/s; ", end="")
    print(f"plain per-sample loop {loop_rate / 1e6:.3f} M samples/s")
    print(f"  speed-up x{rate / loop_rate:.0f}; goal >= 20 M samples/s: ", end="")
    print("met" if rate >= 20e6 else "NOT met")
    print(f"  into a reused out= buffer: {reuse_rate / 1e6:.1f} M samples/s")


if __name__ == "__main__":
    main()
