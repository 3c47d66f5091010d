"""Recordings with the simulated sensor's realistic drift (a Matérn 3/2 wander of minutes and a
warm-up trend): the paper's tool at tilted poses, known truth."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from calibration.drift_data import NOISE_6, readings, tilted_poses, truth
from ftcomp.calibration_record import StochasticBiasDrift
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


def spanning_split(
    rng: np.random.Generator, poses: int, train: int
) -> tuple[NDArray[np.int_], NDArray[np.int_]]:
    """``train`` poses that span the session (its first and last, the others drawn between)
    and the rest held out: every held-out pose lies inside the calibration's time window,
    where its bias is the smoothed estimate (outside it, the bias is held by design, which is
    the after-the-session case)."""
    middle = 1 + rng.permutation(poses - 2)
    return np.concatenate([[0, poses - 1], middle[: train - 2]]), middle[train - 2 :]


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


@dataclass(frozen=True)
class LaterUse:
    """A stochastic calibration used ``after_s`` after its session, the arm still and free for
    the last ``still_s`` (force errors of the bias, RMS over the axes [N])."""

    untracked_N: float
    tracked_N: float
    updates: int
    readings: int
    rebiased_tracked_N: float
    rebiased_updates: int


def used_later(
    seed: int, t0_s: float, *, poses: int = 12, after_s: float = 600.0, still_s: float = 30.0
) -> LaterUse:
    """Calibrate ``poses`` poses (``--bias-drift stochastic``) of a session starting ``t0_s``
    after switch-on; ``after_s`` after its end, the bias held against
    :class:`~ftcomp.compensation.bias_tracking.BiasTracker` fed 500 Hz readings of a still,
    free arm for the last ``still_s``, and against the same tracking after a re-bias from the
    first 0.5 s of them (``--rebias-s 0.5 --track-bias``)."""
    from ftcomp.calibration.identify_extended import calibrate_extended
    from ftcomp.calibration.rebias import rebias
    from ftcomp.compensation.bias_tracking import BiasTracker, BiasTrackingConfig
    from ftcomp.compensation.compensator import GravityCompensator

    model, samples, drift = session(seed, poses, t0_s=t0_s)
    result = calibrate_extended(samples, bias_drift="stochastic", leave_one_out=False)
    assert isinstance(result.bias_drift, StochasticBiasDrift)
    end = result.bias_drift.t_max_s
    later = end + after_s
    R = samples.R_base_sensor[0]
    true_bias = model_bias(model) + drift(np.array([later]))[0]
    held = model_bias(result.model)
    tracker = BiasTracker(BiasTrackingConfig(), initial_std=result.bias_drift.end_std)
    tracker.update(end, np.zeros(6), R)  # the session's end; the arm busy until still_s before
    rng = np.random.default_rng(seed + 1000)
    t = later - still_s + np.arange(int(still_s * 500.0)) / 500.0
    w = model.predict(R) + drift(t) + rng.standard_normal((len(t), 6)) * NOISE_6
    contact = GravityCompensator(result).compensate(w, np.broadcast_to(R, (len(w), 3, 3)))
    moved = [tracker.update(float(ti), ci, R) for ti, ci in zip(t, contact, strict=True)]
    tracked = held + tracker.correction
    # Re-biased from the first 0.5 s, then tracked over the rest.
    first = 250
    still = Samples(w[:first], np.broadcast_to(R, (first, 3, 3)), "quaternion")
    now = rebias(result, still)
    se = np.concatenate([now.std_errors.force_bias_N, now.std_errors.torque_bias_Nm])
    after = BiasTracker(BiasTrackingConfig(), initial_std=se)
    after.update(float(t[first - 1]), np.zeros(6), R)
    contact = GravityCompensator(now).compensate(
        w[first:], np.broadcast_to(R, (len(t) - first, 3, 3))
    )
    moved_after = [
        after.update(float(ti), ci, R) for ti, ci in zip(t[first:], contact, strict=True)
    ]
    rebiased = model_bias(now.model) + after.correction
    return LaterUse(
        float(np.linalg.norm(held[:3] - true_bias[:3]) / np.sqrt(3)),
        float(np.linalg.norm(tracked[:3] - true_bias[:3]) / np.sqrt(3)),
        int(np.sum(moved)),
        len(moved),
        float(np.linalg.norm(rebiased[:3] - true_bias[:3]) / np.sqrt(3)),
        int(np.sum(moved_after)),
    )


def model_bias(model: GravityModel) -> NDArray[np.float64]:
    """``[F0, M0]`` of a model, (6,)."""
    return np.concatenate([model.force_bias_N, model.torque_bias_Nm])
