"""Recordings with the simulated sensor's realistic drift (a Matérn 3/2 wander of minutes and a
warm-up trend): the paper's tool at tilted poses, known truth."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from calibration.drift_data import readings, tilted_poses, truth
from ftcomp.model import GravityModel
from ftcomp.samples import Samples
from ftcomp.sim.sensor import SensorSpec, WanderKnots

#: Readings per pose (half a second at the sensor's 1.2 kHz) and the time between poses [s]:
#: a robot-driven ``ftcomp record`` on the twin (``--move-s 1``, 600 readings a pose) took
#: 1.8-2.0 s a pose (measured under load, docs/calibration.md).
PER_POSE = 600
POSE_PERIOD_S = 2.0


class RealisticDrift:
    """The simulated sensor's realistic drift as a function of time (what it adds to the bias)."""

    def __init__(self, seed: int, scale: float = 1.0) -> None:
        self.spec = SensorSpec().realistic_drift(scale)
        self._wander = WanderKnots(
            self.spec.bias_wander_std, self.spec.bias_wander_time_constant_s, [seed, 1]
        )

    def __call__(self, t_s: NDArray[np.float64]) -> NDArray[np.float64]:
        t = np.asarray(t_s, dtype=float)
        trend = np.outer(-np.expm1(-t / self.spec.bias_trend_time_constant_s), self.spec.bias_trend)
        return trend + self._wander.at(t)


def session(
    seed: int, poses: int, pose_period_s: float = POSE_PERIOD_S, t0_s: float = 0.0
) -> tuple[GravityModel, Samples, RealisticDrift]:
    """``poses`` poses, one every ``pose_period_s`` from ``t0_s`` (the sensor switched on at
    t = 0), each 600 readings at the paper's noise."""
    rng = np.random.default_rng(seed)
    drift = RealisticDrift(seed)
    model = truth()
    samples = readings(
        rng,
        model,
        tilted_poses(rng, poses),
        PER_POSE,
        t0_s=t0_s,
        pose_period_s=pose_period_s,
        rate_hz=1200.0,
        drift=drift,
    )
    return model, samples, drift


def subset(samples: Samples, keep_pose: NDArray[np.bool_]) -> Samples:
    """The readings of the poses ``keep_pose`` (per pose, in order) marks."""
    from dataclasses import replace

    assert samples.pose is not None and samples.t is not None
    ids = np.array(sorted(set(samples.pose.tolist()), key=lambda p: int(p[1:])))
    chosen = np.isin(samples.pose, ids[keep_pose])
    return replace(
        samples,
        wrench_sensor=samples.wrench_sensor[chosen],
        R_base_sensor=samples.R_base_sensor[chosen],
        pose=samples.pose[chosen],
        t=samples.t[chosen],
    )
