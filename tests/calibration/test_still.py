"""Still-segment detection on synthetic recordings with known holds, moves and ringing."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.calibration.still import StillConfig, find_still_segments
from ftcomp.errors import ParameterError

RATE_HZ = 500
NS = 1_000_000_000


def _recording(
    rng, holds_s=(1.0, 1.5, 1.2), move_s=0.8, ring_s=0.2, gap_at_s=None, drift_N_per_s=0.0
):
    """Holds at three orientations; each starts with a decaying 4 N oscillation (ringing)."""
    angles, wrench, t = [], [], []
    clock, angle = 0.0, 0.0
    for k, hold in enumerate(holds_s):
        if k:  # a move: 30 degrees about x at constant speed
            for s in np.arange(0, move_s, 1 / RATE_HZ):
                t.append(clock + s)
                angles.append(angle + 30 * s / move_s)
                wrench.append(np.full(6, 5.0 * s))
            clock, angle = clock + move_s, angle + 30
        for s in np.arange(0, hold, 1 / RATE_HZ):
            t.append(clock + s)
            angles.append(angle)
            ring = 4.0 * np.exp(-s / (ring_s / 5)) * np.sin(2 * np.pi * 20 * s)
            wrench.append(np.array([ring, 0, 10 + k + drift_N_per_s * s, 0, 0, 0.0]))
        clock += hold
    t_ns = np.round(np.array(t) * NS).astype(np.int64)
    w = np.array(wrench) + rng.normal(size=(len(t), 6)) * [0.1, 0.1, 0.1, 0.003, 0.003, 0.003]
    if gap_at_s is not None:
        keep = np.abs(np.array(t) - gap_at_s) > 0.15
        return (
            t_ns[keep],
            Rotation.from_euler("x", np.array(angles)[keep, None], degrees=True),
            w[keep],
        )
    return t_ns, Rotation.from_euler("x", np.array(angles)[:, None], degrees=True), w


def test_each_hold_is_one_segment_without_its_ringing(rng) -> None:
    t, R, w = _recording(rng)
    segments, unsettled = find_still_segments(t, R, w, StillConfig())
    assert unsettled == 0
    assert len(segments) == 3
    starts = [0.0, 1.8, 4.1]  # hold starts [s]
    for seg, start, fz in zip(segments, starts, (10, 11, 12), strict=True):
        t_start = seg.t_start_ns / NS
        assert start + 0.05 < t_start < start + 0.4  # the ringing (~0.2 s) dropped, not more
        assert seg.wrench_mean[2] == pytest.approx(fz, abs=0.05)
        assert seg.wrench_std[0] < 0.2  # the ringing is gone from the scatter


def test_a_recording_in_motion_has_no_segment(rng) -> None:
    t, R, w = _recording(rng, holds_s=(0.2, 0.2, 0.2))
    assert find_still_segments(t, R, w, StillConfig())[0] == []


def test_a_gap_in_the_readings_splits_a_hold(rng) -> None:
    t, R, w = _recording(rng, holds_s=(2.0,), gap_at_s=1.0)
    segments, _ = find_still_segments(t, R, w, StillConfig())
    assert len(segments) == 2
    assert all(seg.duration_s < 0.9 for seg in segments)


def test_a_hold_that_never_settles_is_counted_not_kept(rng) -> None:
    t, R, w = _recording(rng, holds_s=(1.0,), drift_N_per_s=2.0)
    segments, unsettled = find_still_segments(t, R, w, StillConfig())
    assert (segments, unsettled) == ([], 1)


def test_thresholds_must_be_positive() -> None:
    with pytest.raises(ParameterError, match="angle_deg must be finite and > 0"):
        StillConfig(angle_deg=0.0)
