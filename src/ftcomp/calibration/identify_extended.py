"""Identification with a drifting bias and/or an unknown mount rotation (beyond the paper).

:func:`calibrate_extended` is the joint method of :func:`ftcomp.calibration.identify.calibrate`
with extra parameters: a bias that drifts with time (:mod:`.drift`, ``ftcomp calibrate
--bias-drift``) or follows the sensor's temperature (:mod:`.temperature`, ``--bias-drift
temperature``) and the sensor's mount rotation in the frame the orientations were recorded in
(:mod:`.mount`, ``--identify-mount``). The fit is :func:`ftcomp.calibration.extended.fit_extended`;
the result is a :class:`~ftcomp.calibration_record.Calibration` carrying the
:class:`~ftcomp.calibration_record.BiasDrift` and :class:`~ftcomp.calibration_record.MountRotation`
it found, with their standard errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Final, Literal, get_args

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.drift import drift_from_fit, drift_times
from ftcomp.calibration.extended import fit_extended, predict_extended
from ftcomp.calibration.identify import (
    calibrate,
    model_from_theta,
    pose_means,
    relative_error_percent,
    standard_errors_from_fit,
)
from ftcomp.calibration.methods import fit_paper, joint_sigma
from ftcomp.calibration.mount import MIN_POSES, mount_from_fit, mount_warnings
from ftcomp.calibration.stochastic import MIN_POSES as STOCHASTIC_MIN_POSES
from ftcomp.calibration.stochastic import (
    StochasticFit,
    fit_stochastic,
    linear_bias_log_likelihood,
    pose_times,
)
from ftcomp.calibration.temperature import (
    TemperatureRegressor,
    sample_temperatures,
    temperature_drift_from_fit,
    temperature_regressor,
)
from ftcomp.calibration_record import (
    DRIFT_ORDERS,
    SENSOR_MAP_SUPPORT,
    Calibration,
    DriftModel,
    Method,
    MountAxes,
    SensorMap,
    StandardErrors,
)
from ftcomp.errors import IdentificationError, ParameterError
from ftcomp.model import GravityModel
from ftcomp.samples import Samples

__all__ = [
    "BIAS_CHOICES",
    "DRIFT_SUPPORT",
    "SENSOR_MAP_CHOICES",
    "TEMPERATURE_SUPPORT",
    "BiasChoice",
    "ModelChoice",
    "ModelSpec",
    "SensorMapChoice",
    "calibrate_extended",
    "identify",
]

#: The bias model to identify: one of :data:`~ftcomp.calibration_record.DriftModel`, or
#: ``"auto"``: the one the data support (:func:`identify`).
BiasChoice = Literal["auto", "none", "linear", "quadratic", "stochastic", "temperature"]
BIAS_CHOICES: Final[tuple[str, ...]] = get_args(BiasChoice)
#: The sensor map: ``"physical"`` (the paper's model), ``"linear"`` (fit the general linear map
#: and apply it where the data support it) or ``"auto"`` (``"linear"`` wherever the bias model
#: combines with it, else ``"physical"``).
SensorMapChoice = Literal["auto", "physical", "linear"]
SENSOR_MAP_CHOICES: Final[tuple[str, ...]] = get_args(SensorMapChoice)
#: Restricted log-likelihood gain of the stochastic bias over a constant one above which the
#: data support a drift (``"auto"``). The stochastic model adds 7 hyperparameters (a time
#: constant and 6 scales), maximised, not integrated out: under a constant bias twice the gain
#: is at most a chi-square of 7 degrees of freedom, above 14 in 5 % of sessions, so a gain of 7
#: is Akaike's criterion (one per parameter); docs/calibration.md measures how often it
#: is passed without drift and what it picks on the real recording.
DRIFT_SUPPORT: Final = 7.0
#: The same rule for a bias linear in the sensor's temperature: it adds 6 hyperparameters (a
#: scale per axis, the slopes integrated out), so Akaike's criterion is a gain of 6. Where both
#: are candidates, the one whose gain exceeds its own threshold by more is taken.
TEMPERATURE_SUPPORT: Final = 6.0
#: A drift polynomial's order by the bias model, the temperature model's slopes a first order
#: term in the scaled temperature.
_ORDERS: Final = {**DRIFT_ORDERS, "temperature": 1}

_LOO_REFITS: Final = 30  # leave-one-pose-out by exact refits up to this many poses


@dataclass(frozen=True)
class ModelSpec:
    """What to identify: the method, the bias model, the mount, the sensor map.

    Attributes:
        method: ``"paper"`` (the paper's two-stage linear fit: a constant bias, the physical
            map, nothing else) or ``"joint"``.
        bias_drift: a :data:`~ftcomp.calibration_record.DriftModel`, or ``"auto"`` (the
            default): a stochastic bias or one that follows the sensor's temperature where the
            data support it (:func:`identify`), else a constant one.
        identify_mount: None, ``"yaw"`` or ``"full"`` (:mod:`.mount`).
        sensor_map: ``"physical"``, ``"linear"`` or ``"auto"`` (the default: ``"linear"``
            wherever the bias model combines with it; applied only where the data support it).

    Raises:
        ParameterError: a choice out of its list, or one that does not combine with another
            (the paper method with anything beyond it; the stochastic bias or the map with a
            mount, a polynomial or a temperature drift), naming the fields.
    """

    method: Method = "joint"
    bias_drift: BiasChoice = "auto"
    identify_mount: MountAxes | None = None
    sensor_map: SensorMapChoice = "auto"

    def __post_init__(self) -> None:
        for name, value, allowed in (
            ("method", self.method, get_args(Method)),
            ("bias_drift", self.bias_drift, BIAS_CHOICES),
            ("sensor_map", self.sensor_map, SENSOR_MAP_CHOICES),
            ("identify_mount", self.identify_mount, (None, *get_args(MountAxes))),
        ):
            if value not in allowed:
                raise ParameterError(
                    f"{name} must be one of {', '.join(map(str, allowed))}, got {value!r}",
                    field=name,
                )
        beyond = [
            f"{name} {value}"
            for name, value, plain in (
                ("bias_drift", self.bias_drift, ("none", "auto")),
                ("sensor_map", self.sensor_map, ("physical", "auto")),
                ("identify_mount", self.identify_mount, (None,)),
            )
            if value not in plain
        ]
        if self.method == "paper" and beyond:
            raise ParameterError(
                f"{' and '.join(beyond)} need method joint (the paper method is its constant "
                "bias and physical model only)",
                field=("method", "bias_drift", "identify_mount", "sensor_map"),
            )
        gp = self.bias_drift == "stochastic" or self.sensor_map == "linear"
        regressed = self.bias_drift in ("linear", "quadratic", "temperature")
        if gp and (self.identify_mount is not None or regressed):
            raise ParameterError(
                "bias_drift stochastic and sensor_map linear combine with neither identify_mount "
                "nor a polynomial or temperature drift (identify the mount first, with a "
                "constant, polynomial or temperature bias)",
                field=("bias_drift", "sensor_map", "identify_mount"),
            )


@dataclass(frozen=True)
class ModelChoice:
    """The model :func:`identify` fitted, and why.

    Attributes:
        bias_drift: the bias model fitted.
        sensor_map_fitted: whether the general linear map was fitted (the calibration's
            ``sensor_map`` says whether it is applied).
        reasons: one sentence per choice made from the data or forced by another (empty when
            everything was given).
    """

    bias_drift: DriftModel
    sensor_map_fitted: bool
    reasons: tuple[str, ...]


def identify(
    samples: Samples, spec: ModelSpec | None = None, *, leave_one_out: bool = True
) -> tuple[Calibration, ModelChoice]:
    """Identify the model ``spec`` asks for (default: the best the data support).

    The one entry point for every model: ``spec.bias_drift == "auto"`` compares a constant
    bias with a stochastic one (:mod:`.stochastic`) by their restricted marginal likelihoods
    (the same framework, nested models) and takes the stochastic one when it gains more than
    :data:`DRIFT_SUPPORT`; it needs each reading's time and 6+ poses recorded in order. Where
    the samples carry the sensor's temperature (``temperature_C``), a bias linear in it is a
    candidate in the same framework (:func:`~.stochastic.linear_bias_log_likelihood`, its gain
    against :data:`TEMPERATURE_SUPPORT`); of the candidates whose gain passes its threshold the
    one passing it by most is taken, else the bias is constant. A polynomial drift is never
    chosen: it is the stochastic model's poorer cousin on every recording measured
    (docs/calibration.md) and extrapolates. ``sensor_map == "auto"`` fits the general linear
    map with a constant or stochastic bias and applies it where its log Bayes factor exceeds
    :data:`~ftcomp.calibration_record.SENSOR_MAP_SUPPORT`.

    Returns:
        The calibration, and what was fitted with the reasons.

    Raises:
        IdentificationError: as :func:`~ftcomp.calibration.identify.calibrate` and
            :func:`calibrate_extended` for the model chosen.
    """
    spec = spec or ModelSpec()
    reasons: list[str] = []
    bias: DriftModel
    if spec.method == "paper":
        result = calibrate(samples, method="paper", leave_one_out=leave_one_out)
        return result, ModelChoice("none", False, ())
    if spec.bias_drift != "auto":
        bias = spec.bias_drift
    elif spec.identify_mount is not None:
        bias = "none"
        reasons.append("a constant bias: with identify_mount no drift model is chosen")
    else:
        bias, why = _choose_bias(samples)
        reasons.append(why)
    if spec.sensor_map == "auto":
        mapped = spec.identify_mount is None and bias in ("none", "stochastic")
        if not mapped:
            reasons.append(
                "the physical sensor map: the linear map combines with neither identify_mount "
                "nor a polynomial or temperature drift"
            )
    else:
        mapped = spec.sensor_map == "linear"
    if bias == "none" and spec.identify_mount is None:
        result = calibrate(samples, method="joint", leave_one_out=leave_one_out)
        if mapped:
            result = _with_map_if_supported(samples, result, leave_one_out=leave_one_out)
    else:
        result = calibrate_extended(
            samples,
            bias_drift=bias,
            identify_mount=spec.identify_mount,
            leave_one_out=leave_one_out,
            sensor_map=mapped,
        )
    if spec.sensor_map == "auto" and result.sensor_map is not None:
        verdict = result.sensor_map.verdict()  # a choice made, not a warning
        reasons.append(verdict)
        result = replace(result, warnings=tuple(w for w in result.warnings if w != verdict))
    return result, ModelChoice(bias, mapped, tuple(reasons))


def _with_map_if_supported(
    samples: Samples, constant: Calibration, *, leave_one_out: bool
) -> Calibration:
    """The constant-bias calibration with the linear map where the data support it; else
    ``constant`` itself (the joint method's fit), the map's record and verdict added."""
    mapped = _calibrate_stochastic(
        samples, leave_one_out=False, drift=False, sensor_map=True, base=constant
    )
    record = mapped.sensor_map
    if record is None or not record.applied:  # the usual case at few poses: no refits
        return replace(
            constant, sensor_map=record, warnings=(*constant.warnings, *_verdict(record))
        )
    if leave_one_out:
        mapped = _calibrate_stochastic(
            samples, leave_one_out=True, drift=False, sensor_map=True, base=constant
        )
    return mapped


def _verdict(record: SensorMap | None) -> list[str]:
    return [] if record is None else [record.verdict()]


def _choose_bias(samples: Samples) -> tuple[DriftModel, str]:
    """The bias model the data support best among constant, stochastic in time and (with the
    sensor's temperatures) linear in temperature; and why."""
    why_not: list[str] = []
    t_pose = _time_candidate(samples, why_not)
    temperature = _temperature_candidate(samples, why_not)
    if t_pose is None and temperature is None:
        return "none", "a constant bias: " + "; ".join(why_not)
    base = calibrate(samples, method="joint", leave_one_out=False)
    inputs = _StochasticInputs.of(samples, base, drift=t_pose is not None)
    constant = inputs.fit(drift=False, sensor_map=False, leave_one_out=False)[0]
    gains: dict[DriftModel, tuple[float, float]] = {}  # model: (gain, its threshold)
    time_constant_s = math.nan
    if t_pose is not None:
        drifting = inputs.fit(drift=True, sensor_map=False, leave_one_out=False)[0]
        gains["stochastic"] = (drifting.log_likelihood - constant.log_likelihood, DRIFT_SUPPORT)
        time_constant_s = drifting.drift.time_constant_s
    if temperature is not None:
        linear = linear_bias_log_likelihood(
            inputs.wrench, inputs.R, inputs.sigma, inputs.theta0, temperature.tau
        )
        gains["temperature"] = (linear - constant.log_likelihood, TEMPERATURE_SUPPORT)
    best = max(gains, key=lambda m: gains[m][0] - gains[m][1])
    gain, need = gains[best]
    also = "".join(f"; {why}" for why in why_not)
    if list(gains) == ["stochastic"]:  # the drift in time alone: the sentences of before
        if gain > need:
            return "stochastic", (
                f"a stochastic bias drift: the data support it (restricted log likelihood "
                f"{gain:+.1f} over a constant bias, > {need:g}; time constant "
                f"{time_constant_s:.3g} s){also}"
            )
        return "none", (
            f"a constant bias: the data do not support a drift (restricted log likelihood of a "
            f"stochastic drift {gain:+.1f} over it, needs > {need:g}){also}"
        )
    names = {"stochastic": "a stochastic drift", "temperature": "a temperature bias"}
    evidence = ", ".join(f"{names[m]} {g:+.1f} (needs > {n:g})" for m, (g, n) in gains.items())
    if gain <= need:
        return "none", (
            f"a constant bias: the data do not support a drift (restricted log likelihood over "
            f"it: {evidence}){also}"
        )
    if best == "stochastic" or temperature is None:
        what = f"a stochastic bias drift (time constant {time_constant_s:.3g} s)"
    else:
        what = (
            f"a bias linear in the sensor's temperature ({temperature.T_min_C:.4g} .. "
            f"{temperature.T_max_C:.4g} degC)"
        )
    return best, (
        f"{what}: the data support it best (restricted log likelihood over a constant bias: "
        f"{evidence}){also}"
    )


def _time_candidate(samples: Samples, why_not: list[str]) -> NDArray[np.float64] | None:
    """The poses' mean times when a stochastic drift in time is a candidate, else None with
    the reason added to ``why_not``."""
    if samples.t is None:
        why_not.append("the samples have no times ('t'), so a drift cannot be told from the tool")
        return None
    try:
        t_pose = pose_times(samples)
    except IdentificationError as exc:
        why_not.append(f"no drift model fits these times ({exc})")
        return None
    if len(t_pose) < STOCHASTIC_MIN_POSES:
        why_not.append(f"{len(t_pose)} poses; a drift model needs {STOCHASTIC_MIN_POSES} or more")
        return None
    return t_pose


def _temperature_candidate(samples: Samples, why_not: list[str]) -> TemperatureRegressor | None:
    """The poses' temperatures when the samples carry them and a temperature bias is a
    candidate, else None (the reason added to ``why_not`` where the samples have temperatures)."""
    temperature = sample_temperatures(samples)
    if temperature is None:
        return None
    try:
        regressor = temperature_regressor(samples, temperature)
    except IdentificationError as exc:
        why_not.append(f"no temperature bias ({exc})")
        return None
    needed = 3 + _ORDERS["temperature"]
    if len(regressor.tau) < needed:
        why_not.append(f"{len(regressor.tau)} poses; a temperature bias needs {needed} or more")
        return None
    return regressor


def calibrate_extended(
    samples: Samples,
    *,
    bias_drift: DriftModel = "none",
    identify_mount: MountAxes | None = None,
    leave_one_out: bool = True,
    sensor_map: bool = False,
) -> Calibration:
    """The joint method with a drifting bias and/or an unknown mount rotation or sensor map.

    Args:
        samples: readings at distinct poses; a drift model needs their times (``t``), the
            temperature model their sensor temperatures (``temperature_C``).
        bias_drift: ``"none"``, ``"linear"`` or ``"quadratic"`` in time,
            ``"stochastic"`` (:mod:`.stochastic`: a Matérn 3/2 process, smoothed; not with a
            mount), or ``"temperature"`` (linear in the sensor's temperature, the slopes fitted
            with the tool model as a linear drift's rates are, :mod:`.temperature`).
        identify_mount: None, ``"yaw"`` (about the recorded frame's z) or ``"full"``; the
            samples' orientations are then the recorded frame's (flange, TCP).
        leave_one_out: each pose predicted (at its time) by a refit to the others.
        sensor_map: also fit a general linear sensor map (:mod:`.sensor_map`), regularised
            toward the physical model, with a verdict on whether the data support it; with a
            constant or stochastic bias, not with a mount.

    Raises:
        IdentificationError: no ``t`` for a drift model (no temperatures, or temperatures
            that do not vary, for the temperature model), too few poses for the parameters,
            (stochastic) times that go back.
    """
    if bias_drift == "stochastic" or sensor_map:
        if identify_mount is not None or bias_drift in ("linear", "quadratic", "temperature"):
            raise IdentificationError(
                "bias_drift stochastic and sensor_map combine with neither identify_mount "
                "nor a polynomial or temperature drift (identify the mount first, with a "
                "constant, polynomial or temperature bias)",
                field=("bias_drift", "sensor_map", "identify_mount"),
            )
        return _calibrate_stochastic(
            samples,
            leave_one_out=leave_one_out,
            drift=bias_drift == "stochastic",
            sensor_map=sensor_map,
        )
    order = _ORDERS.get(bias_drift)
    if order is None:
        raise IdentificationError(
            f"bias drift must be one of {', '.join([*_ORDERS, 'stochastic'])}"
        )
    thermal = (
        temperature_regressor(samples, sample_temperatures(samples))
        if bias_drift == "temperature"
        else None
    )
    if order and thermal is None and samples.t is None:
        raise IdentificationError(
            f"{samples.source}: bias_drift {bias_drift} needs each reading's time: the file "
            "has no 't' (or 't_ns') column",
            field="bias_drift",
        )
    base = calibrate(samples, method="joint", leave_one_out=False)
    ids, R, wrench, count, var_mean = pose_means(samples)
    P = len(ids)
    needed = 3 + order
    if identify_mount is not None:
        needed = max(needed, MIN_POSES[identify_mount])
    if needed > P:
        what = [f"bias_drift {bias_drift}"] if order else []
        what += [f"identify_mount {identify_mount}"] if identify_mount else []
        raise IdentificationError(
            f"{samples.source}: {P} poses; {' with '.join(what)} needs at least {needed}",
            field=("bias_drift", "identify_mount"),
        )
    times = drift_times(samples, order) if order and thermal is None else None
    tau = thermal.tau if thermal is not None else None if times is None else times.tau
    paper = fit_paper(wrench, R)
    sigma = joint_sigma(wrench, R, var_mean, count, paper)
    fit = fit_extended(
        wrench, R, sigma, paper.theta, tau=tau, order=order, mount_axes=identify_mount
    )
    model = model_from_theta(fit.theta)
    std_errors = standard_errors_from_fit(fit.theta, fit.covariance)
    drift = None if times is None else drift_from_fit(fit, times)
    heat = None if thermal is None else temperature_drift_from_fit(fit, thermal)
    mount = mount_from_fit(fit) if identify_mount is not None else None
    R_sensor = R if mount is None else R @ mount.R_rec_sensor
    predicted = model.predict(R_sensor)
    if drift is not None and times is not None:
        predicted = predicted + drift.offset(times.t_s)
    if heat is not None and thermal is not None:
        predicted = predicted + heat.offset(thermal.T_pose_C)
    residuals = wrench - predicted
    loo = np.full_like(wrench, np.nan)
    if leave_one_out and needed < P:
        loo = _leave_one_out(wrench, R, sigma, fit.x, tau, order, identify_mount)
    warnings = list(base.warnings)
    if mount is not None:
        warnings += mount_warnings(mount)
    return replace(
        _refitted(base, model, std_errors, wrench, residuals, loo, warnings),
        bias_drift=heat if heat is not None else drift,
        mount=mount,
    )


def _refitted(
    base: Calibration,
    model: GravityModel,
    std_errors: StandardErrors,
    wrench: NDArray[np.float64],
    residuals: NDArray[np.float64],
    loo: NDArray[np.float64],
    warnings: list[str],
) -> Calibration:
    """``base`` with an extended fit's model, errors, residuals and warnings."""
    return replace(
        base,
        model=model,
        std_errors=std_errors,
        residuals=residuals,
        relative_error_percent=relative_error_percent(residuals, wrench),
        loo_error=loo,
        warnings=tuple(warnings),
    )


@dataclass(frozen=True)
class _StochasticInputs:
    """The per-pose data of a fit in the framework of :mod:`.stochastic`, prepared once."""

    source: str
    R: NDArray[np.float64]
    wrench: NDArray[np.float64]
    sigma: NDArray[np.float64]
    t_pose: NDArray[np.float64]
    t_range: tuple[float, float]
    theta0: NDArray[np.float64]

    @classmethod
    def of(cls, samples: Samples, base: Calibration, *, drift: bool) -> _StochasticInputs:
        """From the samples and their constant-bias joint calibration ``base`` (the start)."""
        _, R, wrench, count, var_mean = pose_means(samples)
        t_pose = pose_times(samples) if drift else np.arange(len(R), dtype=float)
        repeated = bool(np.any(count > 1))
        sigma = (
            joint_sigma(wrench, R, var_mean, count, fit_paper(wrench, R))
            if repeated
            else np.zeros_like(wrench)  # one reading per pose: the white scatter carries the noise
        )
        t_all = t_pose if samples.t is None or not drift else samples.t
        m = base.model
        theta0 = np.concatenate(
            [m.gravity_base_N, m.force_bias_N, m.torque_bias_Nm, m.center_of_gravity_m]
        )
        t_range = (float(t_all.min()), float(t_all.max()))
        return cls(samples.source, R, wrench, sigma, t_pose, t_range, theta0)

    def fit(
        self, *, drift: bool, sensor_map: bool, leave_one_out: bool
    ) -> tuple[StochasticFit, NDArray[np.float64]]:
        """:func:`~.stochastic.fit_stochastic` on these data."""
        return fit_stochastic(
            self.wrench,
            self.R,
            self.sigma,
            self.theta0,
            self.t_pose,
            t_range_s=self.t_range,
            source=self.source,
            drift=drift,
            sensor_map=sensor_map,
            leave_one_out=leave_one_out,
        )


def _calibrate_stochastic(
    samples: Samples,
    *,
    leave_one_out: bool,
    drift: bool,
    sensor_map: bool,
    base: Calibration | None = None,
) -> Calibration:
    """The joint method with the bias a Matérn 3/2 process (:mod:`.stochastic`) and/or a
    general linear sensor map (:mod:`.sensor_map`); ``base``: the samples' constant-bias
    joint calibration, if already made."""
    if base is None:
        base = calibrate(samples, method="joint", leave_one_out=False)
    inputs = _StochasticInputs.of(samples, base, drift=drift)
    R, wrench, t_pose = inputs.R, inputs.wrench, inputs.t_pose

    def run(with_map: bool) -> tuple[StochasticFit, NDArray[np.float64]]:
        return inputs.fit(drift=drift, sensor_map=with_map, leave_one_out=leave_one_out)

    fit, loo = run(False)
    mapped = None
    with_map, loo_map = run(True) if sensor_map else (fit, loo)
    if with_map.sensor_map is not None:
        delta, delta_se = with_map.sensor_map
        gain = with_map.log_likelihood - fit.log_likelihood
        mapped = SensorMap(delta, delta_se, gain, applied=gain > SENSOR_MAP_SUPPORT)
        if mapped.applied:
            fit, loo = with_map, loo_map
    theta = fit.theta.copy()
    theta[3:9] = fit.end_bias
    model = model_from_theta(theta)
    std_errors = standard_errors_from_fit(fit.theta, fit.covariance)
    std_errors = replace(
        std_errors,
        force_bias_N=fit.drift.end_std[:3],
        torque_bias_Nm=fit.drift.end_std[3:],
    )
    predicted = model.predict(R) + (fit.drift.offset(t_pose) if drift else 0.0)
    if mapped is not None and mapped.applied:
        predicted = predicted + model.gravity_wrench(R)[:, :3] @ mapped.delta.T
    residuals = wrench - predicted
    warnings = [*base.warnings, *([mapped.verdict()] if mapped is not None else [])]
    return replace(
        _refitted(base, model, std_errors, wrench, residuals, loo, warnings),
        bias_drift=fit.drift if drift else None,
        mount=None,
        sensor_map=mapped,
    )


def _leave_one_out(
    wrench: NDArray[np.float64],
    R: NDArray[np.float64],
    sigma: NDArray[np.float64],
    x: NDArray[np.float64],
    tau: NDArray[np.float64] | None,
    order: int,
    axes: MountAxes | None,
) -> NDArray[np.float64]:
    """Each pose's reading minus its prediction by a refit to the others (at its time)."""
    P = len(wrench)
    out = np.full_like(wrench, np.nan)
    basis = (
        np.column_stack([np.asarray(tau) ** k for k in range(1, order + 1)])
        if order and tau is not None
        else np.zeros((P, 0))
    )
    n_phi = len(x) - 12 - 6 * order
    for i in range(min(P, _LOO_REFITS)):
        keep = np.arange(P) != i
        fit = fit_extended(
            wrench[keep],
            R[keep],
            sigma[keep],
            x[:12],
            tau=None if tau is None else tau[keep],
            order=order,
            mount_axes=axes,
            phi0=x[12 + 6 * order :] if n_phi else None,
        )
        out[i] = wrench[i] - predict_extended(fit.x, R[i : i + 1], basis[i : i + 1], order, axes)[0]
    return out
