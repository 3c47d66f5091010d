"""A bias that follows the sensor's temperature: the bias model with a regressor.

A strain-gauge sensor's zero moves with its temperature (Kim et al. 2025 cut a sensor's drift
from 26 N to 2.7 N by compensating temperature). Where a recording has the sensor's
temperature (a Bota sensor reports it in every frame), the bias can be modelled as

    F0(T) = F0 + kF * (T - T_ref),   M0(T) = M0 + kM * (T - T_ref)

instead of as a function of time (:mod:`.drift`), which cannot follow a temperature that rises
and falls. The tool model is Huang et al.'s, in two linear stages as the paper method's
(:mod:`.methods`): forces ``F_k = R_k^T G + F0 + kF z_k`` (``G``: the tool's weight as a
base-frame vector, tilt included; ``R_k = R_base_sensor`` of pose k), then torques
``M_k = c x (R_k^T G) + M0 + kM z_k`` (``c``: the centre of gravity, sensor frame). ``z_k`` is
the pose's regressor less its mean: nothing (``constant``), its time (``time``) or its
temperature (``temperature``).

:func:`choose_bias_model` picks the one whose leave-one-pose-out force error (each pose
predicted from a fit without it, :func:`held_out_errors`) is smallest;
``bench/bench_temperature.py`` shows the gain on a simulated sensor whose bias follows its
temperature. These two-stage fits are the reference the bench uses.

``ftcomp calibrate`` fits the temperature model through the joint method instead
(:func:`~ftcomp.calibration.identify_extended.calibrate_extended` with
``bias_drift="temperature"``: the tool model, the bias and its slopes in one weighted fit, with
standard errors), on the regressor this module prepares (:func:`sample_temperatures`,
:func:`temperature_regressor`), and its ``auto`` choice weighs the temperature model by the same
restricted likelihood as the drift in time (:func:`~ftcomp.calibration.identify_extended.identify`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final, Literal, get_args

import numpy as np
from numpy.typing import NDArray

from ftcomp.arrays import freeze_field
from ftcomp.calibration.extended import ExtendedFit
from ftcomp.calibration.identify import pose_groups
from ftcomp.calibration_record import TemperatureBiasDrift
from ftcomp.errors import IdentificationError, ParameterError
from ftcomp.hardware.protocols import TEMPERATURE_CHANNEL
from ftcomp.samples import Samples

__all__ = [
    "BIAS_MODELS",
    "BiasModel",
    "BiasModelChoice",
    "TemperatureFit",
    "TemperatureRegressor",
    "choose_bias_model",
    "fit_bias_model",
    "held_out_errors",
    "sample_temperatures",
    "temperature_drift_from_fit",
    "temperature_regressor",
]

#: The bias's regressor: none, the pose's time, or the sensor's temperature.
BiasModel = Literal["constant", "time", "temperature"]
BIAS_MODELS: Final[tuple[BiasModel, ...]] = get_args(BiasModel)


def _skew(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rows ``[v]x`` for each row of ``v`` (P, 3) -> (P, 3, 3)."""
    z = np.zeros(len(v))
    x, y, w = v[:, 0], v[:, 1], v[:, 2]
    return np.stack(
        [np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)], 1
    )


@dataclass(frozen=True)
class TemperatureFit:
    """A tool model with a bias that follows a regressor (module docstring).

    Attributes:
        model: the regressor: ``constant``, ``time`` or ``temperature``.
        gravity_base_N: the tool's weight as a base-frame vector ``G`` [N], (3,).
        center_of_gravity_m: ``c``, sensor frame [m], (3,).
        force_bias_N: ``F0`` at the reference [N], (3,).
        torque_bias_Nm: ``M0`` at the reference [N*m], (3,).
        force_slope: ``kF`` [N per regressor unit: s or degC], (3,); zero for ``constant``.
        torque_slope: ``kM`` [N*m per regressor unit], (3,).
        reference: the regressor's reference (its mean over the poses) [s or degC].
    """

    model: BiasModel
    gravity_base_N: NDArray[np.float64]
    center_of_gravity_m: NDArray[np.float64]
    force_bias_N: NDArray[np.float64]
    torque_bias_Nm: NDArray[np.float64]
    force_slope: NDArray[np.float64]
    torque_slope: NDArray[np.float64]
    reference: float

    def __post_init__(self) -> None:
        for name in (
            "gravity_base_N",
            "center_of_gravity_m",
            "force_bias_N",
            "torque_bias_Nm",
            "force_slope",
            "torque_slope",
        ):
            freeze_field(self, name, (3,), finite=True)

    def predict(self, R_base_sensor: NDArray[np.float64], value: NDArray[np.float64]) -> NDArray:
        """The readings [N, N*m] at poses ``R_base_sensor`` (P, 3, 3) and regressor values
        ``value`` (P,) [s or degC; ignored for ``constant``], (P, 6)."""
        R = np.asarray(R_base_sensor, dtype=float).reshape(-1, 3, 3)
        z = np.asarray(value, dtype=float).reshape(-1) - self.reference
        if self.model == "constant":
            z = np.zeros(len(R))
        f_grav = np.einsum("kji,j->ki", R, self.gravity_base_N)
        force = f_grav + self.force_bias_N + z[:, None] * self.force_slope
        torque = (
            np.cross(self.center_of_gravity_m, f_grav)
            + self.torque_bias_Nm
            + z[:, None] * self.torque_slope
        )
        return np.hstack([force, torque])


def _check(R: NDArray, wrench: NDArray, value: NDArray | None, model: BiasModel) -> NDArray:
    if model not in BIAS_MODELS:
        raise ParameterError(f"bias_model: {model!r} is not one of {', '.join(BIAS_MODELS)}")
    P = len(R)
    if R.shape != (P, 3, 3) or wrench.shape != (P, 6):
        raise ParameterError(
            f"fit_bias_model: R_base_sensor (P, 3, 3) and wrench (P, 6), got {R.shape} and "
            f"{wrench.shape}"
        )
    if model == "constant":
        return np.zeros(P)
    if value is None or np.shape(value) != (P,) or not np.all(np.isfinite(value)):
        raise IdentificationError(
            f"bias_model {model}: needs each pose's {model} ({P} finite values)",
            field="bias_model",
        )
    return np.asarray(value, dtype=float)


def fit_bias_model(
    R_base_sensor: NDArray[np.float64],
    wrench: NDArray[np.float64],
    value: NDArray[np.float64] | None,
    model: BiasModel,
) -> TemperatureFit:
    """Fit the tool model with the bias ``model`` to pose means.

    Args:
        R_base_sensor: each pose's sensor orientation in the base frame, (P, 3, 3).
        wrench: each pose's mean reading [N, N*m], sensor frame, (P, 6).
        value: each pose's regressor, (P,): its mean time [s] for ``time``, the sensor's mean
            temperature [degC] for ``temperature``; None for ``constant``.
        model: the bias model.

    Raises:
        ParameterError: shapes or a model name that do not fit.
        IdentificationError: no regressor for the model, or poses that cannot separate the
            bias, its slope and the weight (too few, too alike, a regressor that does not vary).
    """
    R = np.asarray(R_base_sensor, dtype=float)
    w = np.asarray(wrench, dtype=float)
    raw = _check(R, w, value, model)
    reference = float(raw.mean()) if model != "constant" else 0.0
    z = raw - reference
    P = len(R)
    eye = np.broadcast_to(np.eye(3), (P, 3, 3))
    slope_cols = [z[:, None, None] * eye] if model != "constant" else []
    # Forces: [R_k^T | I | z_k I] [G; F0; kF].
    X = np.concatenate([np.transpose(R, (0, 2, 1)), eye, *slope_cols], axis=2).reshape(3 * P, -1)
    unknowns = X.shape[1]
    if unknowns >= 3 * P or np.linalg.matrix_rank(X) < unknowns:
        raise IdentificationError(
            f"bias_model {model}: {P} poses cannot separate the weight, the bias"
            + (" and its slope" if model != "constant" else "")
            + " (more poses, more varied orientations, a regressor that varies)",
            field="bias_model",
        )
    beta = np.linalg.lstsq(X, w[:, :3].reshape(-1), rcond=None)[0]
    G = beta[:3]
    f_grav = np.einsum("kji,j->ki", R, G)
    # Torques: c x f = -[f]x c, so [-[f_k]x | I | z_k I] [c; M0; kM].
    Y = np.concatenate([-_skew(f_grav), eye, *slope_cols], axis=2).reshape(3 * P, -1)
    gamma = np.linalg.lstsq(Y, w[:, 3:].reshape(-1), rcond=None)[0]
    zeros = np.zeros(3)
    return TemperatureFit(
        model=model,
        gravity_base_N=G,
        center_of_gravity_m=gamma[:3],
        force_bias_N=beta[3:6],
        torque_bias_Nm=gamma[3:6],
        force_slope=beta[6:9] if model != "constant" else zeros,
        torque_slope=gamma[6:9] if model != "constant" else zeros,
        reference=reference,
    )


def held_out_errors(
    R_base_sensor: NDArray[np.float64],
    wrench: NDArray[np.float64],
    value: NDArray[np.float64] | None,
    model: BiasModel,
) -> NDArray[np.float64]:
    """Each pose's reading less its prediction by a fit without it, (P, 6) [N, N*m] (exact
    refits: P fits)."""
    R = np.asarray(R_base_sensor, dtype=float)
    w = np.asarray(wrench, dtype=float)
    v = _check(R, w, value, model)
    errors = np.empty_like(w)
    for k in range(len(R)):
        keep = np.arange(len(R)) != k
        fit = fit_bias_model(R[keep], w[keep], None if model == "constant" else v[keep], model)
        errors[k] = w[k] - fit.predict(R[k : k + 1], v[k : k + 1])[0]
    return errors


@dataclass(frozen=True)
class BiasModelChoice:
    """The bias model the evidence chose, with every candidate's held-out error.

    Attributes:
        model: the chosen model.
        fit: its fit on all poses.
        force_rms_N: each candidate's held-out force error, RMS over poses and axes [N].
        torque_rms_Nm: the same for torques [N*m].
    """

    model: BiasModel
    fit: TemperatureFit
    force_rms_N: dict[str, float]
    torque_rms_Nm: dict[str, float]


def choose_bias_model(
    R_base_sensor: NDArray[np.float64],
    wrench: NDArray[np.float64],
    t_s: NDArray[np.float64] | None,
    temperature_C: NDArray[np.float64] | None,
) -> BiasModelChoice:
    """The bias model (among those the data allow: ``time`` needs times, ``temperature``
    temperatures) whose held-out force error is smallest.

    Args:
        R_base_sensor: each pose's orientation, (P, 3, 3).
        wrench: each pose's mean reading, (P, 6) [N, N*m].
        t_s: each pose's mean time [s], (P,), or None.
        temperature_C: each pose's mean sensor temperature [degC], (P,), or None.
    """
    values: dict[BiasModel, NDArray[np.float64] | None] = {"constant": None}
    if t_s is not None:
        values["time"] = np.asarray(t_s, dtype=float)
    if temperature_C is not None:
        values["temperature"] = np.asarray(temperature_C, dtype=float)
    force: dict[str, float] = {}
    torque: dict[str, float] = {}
    for model, value in values.items():
        errors = held_out_errors(R_base_sensor, wrench, value, model)
        force[model] = float(np.sqrt(np.mean(errors[:, :3] ** 2)))
        torque[model] = float(np.sqrt(np.mean(errors[:, 3:] ** 2)))
    best: BiasModel = min(values, key=lambda m: force[m])
    fit = fit_bias_model(R_base_sensor, wrench, values[best], best)
    return BiasModelChoice(best, fit, force, torque)


def sample_temperatures(samples: Samples) -> NDArray[np.float64] | None:
    """Each reading's sensor temperature [degC], (N,), or None when the samples have none.

    From the recording's extra channel ``temperature_C`` (:attr:`~ftcomp.samples.Samples.extras`)
    or, for samples read from a file, its ``temperature_C`` column.

    Raises:
        IdentificationError: a temperature that is not a finite number (naming its row).
    """
    if TEMPERATURE_CHANNEL in samples.extras:
        values = np.asarray(samples.extras[TEMPERATURE_CHANNEL], dtype=float)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            k = int(bad[0])
            raise IdentificationError(
                f"{samples.source}: row {k + 1}, column {TEMPERATURE_CHANNEL!r}: "
                f"{values[k]!r} is not a finite temperature",
                field="bias_drift",
            )
        return values
    if TEMPERATURE_CHANNEL not in samples.header:
        return None
    column = samples.header.index(TEMPERATURE_CHANNEL)
    out = np.empty(len(samples))
    for k, row in enumerate(samples.rows):
        cell = row[column] if column < len(row) else ""
        try:
            value = float(cell)
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            raise IdentificationError(
                f"{samples.source}: row {k + 1}, column {TEMPERATURE_CHANNEL!r}: {cell!r} is "
                "not a finite temperature [degC]",
                field="bias_drift",
            )
        out[k] = value
    return out


@dataclass(frozen=True)
class TemperatureRegressor:
    """Each pose's mean temperature, scaled for the joint fit as a drift's times are
    (:class:`~ftcomp.calibration.drift.DriftTimes`): ``tau = (T - T_ref_C) / half_span_C``.

    Attributes:
        tau: each pose's scaled temperature, (P,).
        T_ref_C: the reference temperature [degC]: the poses' mean.
        T_min_C, T_max_C: the readings' temperature range [degC].
        half_span_C: half that range [degC] (at least 1e-9).
    """

    tau: NDArray[np.float64]
    T_ref_C: float
    T_min_C: float
    T_max_C: float
    half_span_C: float

    def __post_init__(self) -> None:
        freeze_field(self, "tau", (len(self.tau),), finite=True)

    @property
    def T_pose_C(self) -> NDArray[np.float64]:
        """Each pose's mean temperature [degC], (P,)."""
        return self.T_ref_C + self.tau * self.half_span_C


#: The smallest spread of the poses' mean temperatures a slope is fitted on [degC]: below it
#: the temperature is taken as constant (a sensor reporting a fixed value, or a few mK).
MIN_SPREAD_C: Final = 0.01


def temperature_regressor(
    samples: Samples, temperature_C: NDArray[np.float64] | None
) -> TemperatureRegressor:
    """The poses' mean temperatures (poses as :func:`~ftcomp.calibration.identify.pose_means`
    groups them) as the regressor of a bias linear in temperature.

    Args:
        samples: the readings.
        temperature_C: each reading's temperature [degC] (:func:`sample_temperatures`), or None.

    Raises:
        IdentificationError: no temperatures, or poses whose mean temperatures differ by less
            than :data:`MIN_SPREAD_C` (a slope cannot be told from the bias).
    """
    if temperature_C is None:
        raise IdentificationError(
            f"{samples.source}: bias_drift temperature needs each reading's sensor "
            f"temperature: the samples have no {TEMPERATURE_CHANNEL!r} column",
            field="bias_drift",
        )
    group, first = pose_groups(samples)
    poses = len(first)
    T_pose = np.bincount(group, temperature_C, poses) / np.bincount(group, minlength=poses)
    spread = float(T_pose.max() - T_pose.min())
    if not spread >= MIN_SPREAD_C:
        raise IdentificationError(
            f"{samples.source}: the poses' mean temperatures span {spread:.3g} degC "
            f"({T_pose.min():.6g} .. {T_pose.max():.6g}): bias_drift temperature needs them "
            f"to differ by {MIN_SPREAD_C:g} degC or more",
            field="bias_drift",
        )
    T_min, T_max = float(temperature_C.min()), float(temperature_C.max())
    T_ref = float(T_pose.mean())
    half = max((T_max - T_min) / 2.0, 1e-9)
    return TemperatureRegressor((T_pose - T_ref) / half, T_ref, T_min, T_max, half)


def temperature_drift_from_fit(
    fit: ExtendedFit, regressor: TemperatureRegressor
) -> TemperatureBiasDrift:
    """The slopes per degC a joint fit with one drift term in the scaled temperature found,
    with standard errors."""
    if fit.order != 1:
        raise ParameterError(f"a temperature bias is linear: the fit's order is {fit.order}")
    scale = 1.0 / regressor.half_span_C
    se = np.sqrt(np.maximum(np.diag(fit.covariance)[12:18], 0.0)) * scale
    return TemperatureBiasDrift(
        regressor.T_ref_C,
        regressor.T_min_C,
        regressor.T_max_C,
        fit.drift[0] * scale,
        se,
    )
