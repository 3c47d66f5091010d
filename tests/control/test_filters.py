"""The streaming low-pass filter against scipy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from ftcomp.control import LowPassFilter
from ftcomp.control.filters import butterworth_sections
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


@pytest.mark.parametrize("order", range(1, 9))
def test_the_design_is_scipys_butterworth(order: int) -> None:
    rng = np.random.default_rng(order)
    x = rng.normal(size=2000)
    for cutoff_hz, rate_hz in ((10.0, 500.0), (20.0, 500.0), (0.5, 1000.0), (240.0, 500.0)):
        ours = butterworth_sections(order, cutoff_hz, rate_hz)
        scipys = signal.butter(order, cutoff_hz, output="sos", fs=rate_hz)
        # The same transfer function (the sections' gains are spread differently): the same
        # response and output, to rounding; the sections ordered as scipy orders them.
        _, h_ours = signal.sosfreqz(ours, worN=256, fs=rate_hz)
        _, h_scipys = signal.sosfreqz(scipys, worN=256, fs=rate_hz)
        np.testing.assert_allclose(h_ours, h_scipys, rtol=0, atol=1e-10)
        np.testing.assert_allclose(signal.sosfilt(ours, x), signal.sosfilt(scipys, x), atol=1e-10)
        np.testing.assert_allclose(ours[:, 3:], scipys[:, 3:], atol=1e-12)
        # The steady state, written out, is scipy's solve of it
        filt = LowPassFilter(cutoff_hz, 1.0 / rate_hz, order=order, channels=1)
        zi = filt.initial_state([1.0])[:, :, 0]
        np.testing.assert_allclose(zi, signal.sosfilt_zi(ours), atol=1e-10)


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


@pytest.mark.parametrize("order", [1, 2, 5])
def test_step_scalar_equals_sosfilt_and_step_on_one_channel(order: int) -> None:
    filt = LowPassFilter(cutoff_hz=2.0, period_s=1e-3, order=order, channels=1)
    rng = np.random.default_rng(2)
    x = 3.0 + rng.normal(size=800)
    zi0 = filt.initial_state([x[0]])
    y_ref, zf = signal.sosfilt(np.array(filt.sos), x, zi=zi0[:, :, 0])
    state = filt.initial_state_scalar(x[0])
    np.testing.assert_array_equal(state, zi0.ravel())
    z_array, ys, ys_array = zi0, [], []
    for value in x:
        state, y = filt.step_scalar(state, value)
        z_array, y_array = filt.step(z_array, [value])
        ys.append(y)
        ys_array.append(y_array[0])
    assert isinstance(state, tuple) and isinstance(ys[0], float)
    np.testing.assert_allclose(ys, y_ref, atol=1e-12)  # same arithmetic as sosfilt
    np.testing.assert_array_equal(ys, ys_array)  # and exactly that of step
    np.testing.assert_allclose(state, zf.ravel(), atol=1e-12)
    np.testing.assert_array_equal(state, z_array.ravel())


@pytest.mark.parametrize("channels", [1, 3])
def test_step_equals_sosfilt_on_any_number_of_channels(channels: int) -> None:
    filt = LowPassFilter(cutoff_hz=20.0, period_s=1e-3, order=3, channels=channels)
    x = np.random.default_rng(4).normal(size=(300, channels))
    zi0 = filt.initial_state(x[0])
    y_ref, zf = signal.sosfilt(np.array(filt.sos), x, axis=0, zi=zi0)
    zi = zi0.copy()
    np.testing.assert_allclose(_run(filt, x, zi0), y_ref, atol=1e-12)
    np.testing.assert_array_equal(zi0, zi)  # step never writes into its state
    state = zi0
    for row in x:
        state, _ = filt.step(state, row)
    np.testing.assert_allclose(state, zf, atol=1e-12)


def test_filter_raises_on_a_state_of_the_wrong_size() -> None:
    filt = LowPassFilter(cutoff_hz=5.0, period_s=1e-3, order=3, channels=1)
    with pytest.raises(ParameterError, match="filter state must hold 4 floats, got 2"):
        filt.step_scalar((0.0, 0.0), 1.0)
    with pytest.raises(ParameterError, match=r"filter state must have shape \(2, 2, 1\)"):
        filt.step(np.zeros((1, 2, 1)), [1.0])
    with pytest.raises(ParameterError, match="needs channels=1"):
        LowPassFilter(cutoff_hz=5.0, period_s=1e-3).initial_state_scalar(0.0)
