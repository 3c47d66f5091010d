"""Identification with a drifting bias and/or an unknown mount rotation (beyond the paper).

:func:`calibrate_extended` is the joint method of :func:`ftcomp.calibration.identify.calibrate`
with extra parameters: a bias that drifts with time (:mod:`.drift`, ``ftcomp calibrate
--bias-drift``) and the sensor's mount rotation in the frame the orientations were recorded in
(:mod:`.mount`, ``--identify-mount``). The fit is :func:`ftcomp.calibration.extended.fit_extended`;
the result is a :class:`~ftcomp.calibration_record.Calibration` carrying the
:class:`~ftcomp.calibration_record.BiasDrift` and :class:`~ftcomp.calibration_record.MountRotation`
it found, with their standard errors.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Final

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
from ftcomp.calibration.stochastic import StochasticFit, fit_stochastic, pose_times
from ftcomp.calibration_record import (
    DRIFT_ORDERS,
    SENSOR_MAP_SUPPORT,
    Calibration,
    DriftModel,
    MountAxes,
    SensorMap,
    StandardErrors,
)
from ftcomp.errors import IdentificationError
from ftcomp.model import GravityModel
from ftcomp.samples import Samples

__all__ = ["calibrate_extended"]

_LOO_REFITS: Final = 30  # leave-one-pose-out by exact refits up to this many poses


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
        samples: readings at distinct poses; a drift model needs their times (``t``).
        bias_drift: ``"none"``, ``"linear"`` or ``"quadratic"`` in time, or
            ``"stochastic"`` (:mod:`.stochastic`: a Matérn 3/2 process, smoothed; not with a
            mount).
        identify_mount: None, ``"yaw"`` (about the recorded frame's z) or ``"full"``; the
            samples' orientations are then the recorded frame's (flange, TCP).
        leave_one_out: each pose predicted (at its time) by a refit to the others.
        sensor_map: also fit a general linear sensor map (:mod:`.sensor_map`), regularised
            toward the physical model, with a verdict on whether the data support it; with a
            constant or stochastic bias, not with a mount.

    Raises:
        IdentificationError: no ``t`` for a drift model, too few poses for the parameters,
            (stochastic) times that go back.
    """
    if bias_drift == "stochastic" or sensor_map:
        if identify_mount is not None or bias_drift in ("linear", "quadratic"):
            raise IdentificationError(
                "bias_drift stochastic and sensor_map combine with neither identify_mount "
                "nor a polynomial drift (identify the mount first, with a constant or "
                "polynomial bias)",
                field=("bias_drift", "sensor_map", "identify_mount"),
            )
        return _calibrate_stochastic(
            samples,
            leave_one_out=leave_one_out,
            drift=bias_drift == "stochastic",
            sensor_map=sensor_map,
        )
    order = DRIFT_ORDERS.get(bias_drift)
    if order is None:
        raise IdentificationError(
            f"bias drift must be one of {', '.join([*DRIFT_ORDERS, 'stochastic'])}"
        )
    if order and samples.t is None:
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
    times = drift_times(samples, order) if order else None
    tau = None if times is None else times.tau
    paper = fit_paper(wrench, R)
    sigma = joint_sigma(wrench, R, var_mean, count, paper)
    fit = fit_extended(
        wrench, R, sigma, paper.theta, tau=tau, order=order, mount_axes=identify_mount
    )
    model = model_from_theta(fit.theta)
    std_errors = standard_errors_from_fit(fit.theta, fit.covariance)
    drift = None if times is None else drift_from_fit(fit, times)
    mount = mount_from_fit(fit) if identify_mount is not None else None
    R_sensor = R if mount is None else R @ mount.R_rec_sensor
    predicted = model.predict(R_sensor)
    if drift is not None and times is not None:
        predicted = predicted + drift.offset(times.t_s)
    residuals = wrench - predicted
    loo = np.full_like(wrench, np.nan)
    if leave_one_out and needed < P:
        loo = _leave_one_out(wrench, R, sigma, fit.x, tau, order, identify_mount)
    warnings = list(base.warnings)
    if mount is not None:
        warnings += mount_warnings(mount)
    return replace(
        _refitted(base, model, std_errors, wrench, residuals, loo, warnings),
        bias_drift=drift,
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


def _calibrate_stochastic(
    samples: Samples, *, leave_one_out: bool, drift: bool, sensor_map: bool
) -> Calibration:
    """The joint method with the bias a Matérn 3/2 process (:mod:`.stochastic`) and/or a
    general linear sensor map (:mod:`.sensor_map`)."""
    base = calibrate(samples, method="joint", leave_one_out=False)
    _, R, wrench, count, var_mean = pose_means(samples)
    t_pose = pose_times(samples) if drift else np.arange(len(R), dtype=float)
    repeated = bool(np.any(count > 1))
    sigma = (
        joint_sigma(wrench, R, var_mean, count, fit_paper(wrench, R))
        if repeated
        else np.zeros_like(wrench)  # one reading per pose: the white scatter carries the noise
    )
    t_all = t_pose if samples.t is None or not drift else samples.t
    t_range = (float(t_all.min()), float(t_all.max()))
    theta0 = np.concatenate(
        [
            base.model.gravity_base_N,
            base.model.force_bias_N,
            base.model.torque_bias_Nm,
            base.model.center_of_gravity_m,
        ]
    )

    def run(with_map: bool) -> tuple[StochasticFit, NDArray[np.float64]]:
        return fit_stochastic(
            wrench,
            R,
            sigma,
            theta0,
            t_pose,
            t_range_s=t_range,
            source=samples.source,
            drift=drift,
            sensor_map=with_map,
            leave_one_out=leave_one_out,
        )

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
