"""The streaming low-pass filter against scipy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from ftcomp.control import LowPassFilter
from ftcomp.errors import ParameterError


def _run(filt: LowPassFilter, x: np.ndarray, zi: np.ndarray) -> np.ndarray:
    out = []
    for row in x:
        zi, y = filt.step(zi, row)
        out.append(y)
    return np.array(out)


@pytest.mark.parametrize("order", [1, 2, 4])
def test_step_equals_sosfilt_sample_by_sample(order: int) -> None:
    filt = LowPassFilter(cutoff_hz=20.0, period_s=1e-3, order=order)
    rng = np.random.default_rng(1)
    x = rng.normal(size=(500, 6))
    zi0 = filt.initial_state(x[0])
    y_ref, _ = signal.sosfilt(np.array(filt.sos), x, axis=0, zi=zi0)
    np.testing.assert_allclose(_run(filt, x, zi0), y_ref, atol=1e-12)  # same arithmetic


def test_frequency_response_matches_design() -> None:
    filt = LowPassFilter(cutoff_hz=10.0, period_s=1e-3, order=2)
    t = np.arange(4000) * 1e-3
    for f_hz in (2.0, 10.0, 40.0):
        x = np.sin(2 * np.pi * f_hz * t)
        y = _run(filt, np.tile(x[:, None], (1, 6)), filt.initial_state(np.zeros(6)))[:, 0]
        gain = np.sqrt(2 * np.mean(y[2000:] ** 2))
        _, h = signal.sosfreqz(np.array(filt.sos), worN=[f_hz], fs=1000.0)
        np.testing.assert_allclose(gain, abs(h[0]), rtol=1e-2)  # RMS over 2 s of a sine
    _, h = signal.sosfreqz(np.array(filt.sos), worN=[10.0], fs=1000.0)
    np.testing.assert_allclose(abs(h[0]), 1 / np.sqrt(2), rtol=1e-6)


def test_initial_state_is_steady_at_x0() -> None:
    filt = LowPassFilter(cutoff_hz=5.0, period_s=1e-3)
    x0 = np.arange(6.0)
    _, y = filt.step(filt.initial_state(x0), x0)
    np.testing.assert_allclose(y, x0, atol=1e-12)


def test_filter_raises_on_cutoff_above_nyquist() -> None:
    with pytest.raises(ParameterError, match=r"cutoff_hz must be in \(0, 500\) Hz"):
        LowPassFilter(cutoff_hz=600.0, period_s=1e-3)
