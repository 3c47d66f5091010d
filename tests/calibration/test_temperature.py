"""The temperature-aware bias model: exact on exact data, chosen by held-out evidence only where
the temperature explains the bias, and one clear error where the data cannot carry it."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.calibration.temperature import choose_bias_model, fit_bias_model
from ftcomp.errors import IdentificationError, ParameterError

G = 0.8 * 9.81 * np.array([0.002, -0.003, -1.0])
COG = np.array([0.04, -0.01, 0.06])
F0, M0 = np.array([0.5, -0.3, 1.2]), np.array([0.02, 0.01, -0.03])
KF, KM = np.array([0.08, -0.05, 0.12]), np.array([0.004, -0.003, 0.002])


def poses(seed: int, count: int = 24) -> np.ndarray:
    return Rotation.random(count, random_state=seed).as_matrix()


def readings(R: np.ndarray, regressor: np.ndarray, rng: np.random.Generator | None) -> np.ndarray:
    f = np.einsum("kji,j->ki", R, G)
    dz = (regressor - 25.0)[:, None]
    wrench = np.hstack([f + F0 + dz * KF, np.cross(COG, f) + M0 + dz * KM])
    if rng is not None:
        wrench += rng.normal(size=wrench.shape) * np.repeat([0.05, 0.002], 3) / np.sqrt(200)
    return wrench


def test_the_temperature_fit_recovers_an_exact_tool_and_bias_slope() -> None:
    R = poses(1)
    temperature = 25.0 + 3.0 * np.sin(np.linspace(0.0, 7.0, len(R)))
    fit = fit_bias_model(R, readings(R, temperature, None), temperature, "temperature")
    # exact algebra: rounding only
    assert np.allclose(fit.gravity_base_N, G, atol=1e-9)
    assert np.allclose(fit.center_of_gravity_m, COG, atol=1e-9)
    assert np.allclose(fit.force_slope, KF, atol=1e-9)
    assert np.allclose(fit.torque_slope, KM, atol=1e-9)
    bias_at_25 = fit.force_bias_N + (25.0 - fit.reference) * fit.force_slope
    assert np.allclose(bias_at_25, F0, atol=1e-9)


def test_the_evidence_picks_temperature_only_where_temperature_drives_the_bias() -> None:
    rng = np.random.default_rng(36)
    R = poses(2, 36)
    t = 10.0 * np.arange(len(R))
    temperature = 25.0 + 3.0 * np.sin(2.0 * np.pi * t / 300.0)
    follows_temperature = choose_bias_model(R, readings(R, temperature, rng), t, temperature)
    assert follows_temperature.model == "temperature"
    # the bias follows time (a steady warm-up), the temperature channel wanders unrelated
    warm_up = 25.0 + 0.01 * t
    follows_time = choose_bias_model(R, readings(R, warm_up, rng), t, temperature)
    assert follows_time.model == "time"
    assert follows_time.force_rms_N["temperature"] > 3 * follows_time.force_rms_N["time"]


def test_a_model_the_data_cannot_carry_is_one_error_naming_the_field() -> None:
    R = poses(3)
    wrench = readings(R, np.full(len(R), 25.0), None)
    with pytest.raises(IdentificationError, match="bias_model temperature: needs each pose's"):
        fit_bias_model(R, wrench, None, "temperature")
    with pytest.raises(IdentificationError, match="cannot separate"):
        fit_bias_model(R, wrench, np.full(len(R), 25.0), "temperature")
    with pytest.raises(ParameterError, match="bias_model: 'humidity'"):
        fit_bias_model(R, wrench, None, "humidity")  # type: ignore[arg-type]
