"""Recordings with the simulated sensor's realistic drift (a Matérn 3/2 wander of minutes and a
warm-up trend): the paper's tool at tilted poses, known truth."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from calibration.drift_data import readings, tilted_poses, truth
from ftcomp.model import GravityModel
from ftcomp.samples import Samples
from ftcomp.sim.sensor import SensorSpec, WanderKnots

#: Readings per pose (half a second at the sensor's 1.2 kHz) and the time between poses [s].
PER_POSE = 600
POSE_PERIOD_S = 10.0


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


def session(seed: int, poses: int) -> tuple[GravityModel, Samples, RealisticDrift]:
    """``poses`` poses, one every 10 s from t = 0, each 600 readings at the paper's noise."""
    rng = np.random.default_rng(seed)
    drift = RealisticDrift(seed)
    model = truth()
    samples = readings(
        rng,
        model,
        tilted_poses(rng, poses),
        PER_POSE,
        pose_period_s=POSE_PERIOD_S,
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
