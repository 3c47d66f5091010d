"""Identification of sensor bias, tool weight and centre of gravity, and base tilt.

:func:`calibrate` averages the readings of each pose (the paper averages 500 per pose), checks
the poses can separate bias from gravity, fits with the chosen method
(:mod:`ftcomp.calibration.methods`) and reports what a user needs to trust the result: the standard
error of every parameter, the regressor's condition number, per-pose residuals, the paper's
Table-3 relative errors and the leave-one-pose-out prediction error, as a
:class:`~ftcomp.calibration_record.Calibration`.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.loo import leave_one_out as _leave_one_out
from ftcomp.calibration.methods import CONDITION_SINGULAR, fit_method, force_regressor
from ftcomp.calibration.outliers import check_fit, check_readings, outlier_warning
from ftcomp.calibration_record import Calibration, Method, StandardErrors
from ftcomp.errors import IdentificationError, ParameterError
from ftcomp.frames import tilt_from_gravity_in_base
from ftcomp.model import GravityModel
from ftcomp.samples import Samples

__all__ = [
    "CONDITION_WARNING",
    "calibrate",
    "deviations_in_standard_errors",
    "max_deviations_in_standard_errors",
    "model_from_theta",
    "pose_groups",
    "pose_means",
    "relative_error_percent",
    "standard_errors_from_fit",
]

#: Condition number of the force regressor above which the poses are reported as too alike.
CONDITION_WARNING = 30.0
_DISTINCT_POSE_TOLERANCE = 1e-6  # Frobenius norm between rotation matrices
_SAME_POSE_TOLERANCE = 1e-3  # ... within one pose id
#: Without a pose column: readings at distinct orientations, most rows their own, a median step
#: between consecutive rows below this (Frobenius; about 0.4 deg) make a recording in motion.
_CONTINUOUS_STEP = 0.01
_CONTINUOUS_MIN_ROWS = 20


def pose_groups(samples: Samples) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Which pose each reading belongs to, as :func:`pose_means` groups them.

    Returns:
        ``(group (N,), first (P,))``: each row's pose number (0, 1, ... in order of first
        appearance) and each pose's first row; poses by ``pose`` id, or without one by
        orientation (rounded to 1e-9). Use it to average any per-row quantity per pose, e.g.
        the times: ``np.bincount(group, samples.t) / np.bincount(group)``.
    """
    if samples.pose is not None:
        _, first, inverse = np.unique(samples.pose, return_index=True, return_inverse=True)
    else:
        rounded = np.round(samples.R_base_sensor.reshape(len(samples), 9), 9) + 0.0  # no -0.0
        _, first, inverse = np.unique(rounded, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return rank[inverse.reshape(-1)], first[order]


def _check_not_continuous(samples: Samples, poses: int) -> None:
    n = len(samples)
    if samples.pose is not None or n < _CONTINUOUS_MIN_ROWS or poses < n // 2:
        return
    R = samples.R_base_sensor
    step = float(np.median(np.linalg.norm(R[1:] - R[:-1], axis=(1, 2))))
    if step < _CONTINUOUS_STEP:
        step_deg = math.degrees(step / math.sqrt(2.0))  # |R1 - R2| = 2 sqrt(2) sin(angle / 2)
        raise IdentificationError(
            f"{samples.source}: no 'pose' column, and the orientation changes from row to row "
            f"({poses} orientations in {n} rows, median step {step_deg:.2g} deg): a recording "
            "in motion, not readings at still poses; cut it into still segments first "
            "(still_segments for any recording with a 't' column, ftcomp import-bag for bags) "
            "with a pose id each, or add a 'pose' column",
            field="still_segments",
        )


def pose_means(
    samples: Samples,
) -> tuple[tuple[str, ...], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray]:
    """Group readings by pose and average them.

    Rows with the same ``pose`` id form a pose; without a ``pose`` column, rows with the same
    orientation do (a file whose orientation changes continuously, a recording in motion, is an
    error pointing to still-segment detection). Returns ``(ids, R (P,3,3), wrench mean (P,6),
    counts (P,), variance of the mean (P,6))``, the variance NaN at poses with a single reading.
    """
    group, first = pose_groups(samples)
    _check_not_continuous(samples, len(first))
    n_poses = len(first)
    R_all, w = samples.R_base_sensor, samples.wrench_sensor
    R = R_all[first]
    spread = np.zeros(n_poses)
    np.maximum.at(spread, group, np.linalg.norm(R_all - R[group], axis=(1, 2)))
    bad = np.flatnonzero(spread > _SAME_POSE_TOLERANCE)
    if samples.pose is not None:
        ids = tuple(str(samples.pose[i]) for i in first)
    else:
        ids = tuple(str(k) for k in range(1, n_poses + 1))
    if bad.size:
        raise IdentificationError(
            f"{samples.source}: pose {ids[bad[0]]!r} has readings at orientations that differ "
            f"by {spread[bad[0]]:.3g} (Frobenius norm): one pose id must be one orientation"
        )
    count = np.bincount(group, minlength=n_poses).astype(float)
    mean = (
        np.column_stack([np.bincount(group, w[:, j], n_poses) for j in range(6)]) / count[:, None]
    )
    deviation = w - mean[group]
    squares = np.column_stack([np.bincount(group, deviation[:, j] ** 2, n_poses) for j in range(6)])
    with np.errstate(divide="ignore", invalid="ignore"):
        var = squares / ((count - 1.0) * count)[:, None]
    var[count < 2] = np.nan
    return ids, R, mean, count, var


def _distinct_poses(R: NDArray[np.float64], enough: int) -> int:
    """How many poses differ from every earlier one by more than the tolerance; stops counting
    once there are ``enough`` (exact duplicates, the usual case, are set aside first)."""
    flat = R.reshape(len(R), 9)
    _, first = np.unique(np.round(flat, 9) + 0.0, axis=0, return_index=True)
    candidates = flat[np.sort(first)]
    squares = np.einsum("ij,ij->i", candidates, candidates)
    distinct, block = 0, 512
    for start in range(0, len(candidates), block):
        stop = min(start + block, len(candidates))
        # Squared distances of this block's poses to every earlier one (|a|^2 + |b|^2 - 2 a.b:
        # rounding of 1e-15 against a tolerance of 1e-12).
        d2 = (
            squares[start:stop, None]
            + squares[None, :stop]
            - 2 * candidates[start:stop] @ candidates[:stop].T
        )
        d2[np.arange(stop - start)[:, None] + start <= np.arange(stop)[None, :]] = np.inf
        distinct += int(np.count_nonzero(d2.min(axis=1) > _DISTINCT_POSE_TOLERANCE**2))
        if distinct >= enough:
            break
    return distinct


def _check_identifiable(R: NDArray[np.float64], source: str) -> float:
    distinct = _distinct_poses(R, enough=3)
    if distinct < 3:
        raise IdentificationError(
            f"{source}: {distinct} distinct pose(s); at least 3 are needed to separate sensor "
            "bias from tool gravity"
        )
    cond = float(np.linalg.cond(force_regressor(R)))
    if not math.isfinite(cond) or cond > CONDITION_SINGULAR:
        raise IdentificationError(
            f"{source}: the poses differ only by rotation about one axis (e.g. about the gravity "
            f"direction; regressor condition number {cond:.3g}): bias and gravity cannot be "
            "separated; add poses that tilt the tool differently"
        )
    return cond


def _propagate(
    func: Callable[[NDArray[np.float64]], NDArray[np.float64]],
    x: NDArray[np.float64],
    cov: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Standard errors of ``func(x)`` by first-order propagation (central differences)."""
    y0 = func(x)
    J = np.zeros((len(y0), len(x)))
    for k in range(len(x)):
        h = 1e-7 * max(1.0, abs(x[k]))
        dx = np.zeros_like(x)
        dx[k] = h
        J[:, k] = (func(x + dx) - func(x - dx)) / (2 * h)
    return np.sqrt(np.maximum(np.diag(J @ cov @ J.T), 0.0))


def standard_errors_from_fit(
    theta: NDArray[np.float64], cov: NDArray[np.float64]
) -> StandardErrors:
    """The standard errors of the model's quantities from a fit's parameters and covariance.

    Args:
        theta: the fit's parameters, the first 12 ``[gravity_base (3), F0 (3), M0 (3), P (3)]``
            (:mod:`ftcomp.calibration.methods`); any further ones (drift, mount) are ignored.
        cov: their covariance, at least (12, 12).

    Weight and tilt by first-order propagation through
    :func:`~ftcomp.frames.tilt_from_gravity_in_base`.
    """
    theta, cov = theta[:12], cov[:12, :12]
    gvu = _propagate(lambda th: np.array(tilt_from_gravity_in_base(th[0:3])), theta, cov)
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return StandardErrors(
        weight_N=float(gvu[0]),
        center_of_gravity_m=se[9:12],
        force_bias_N=se[3:6],
        torque_bias_Nm=se[6:9],
        tilt_U_rad=float(gvu[1]),
        tilt_V_rad=float(gvu[2]),
        gravity_base_N=se[0:3],
    )


def model_from_theta(theta: NDArray[np.float64]) -> GravityModel:
    """The model of a fit's first 12 parameters ``[gravity_base, F0, M0, P]``
    (:mod:`ftcomp.calibration.methods`), any further ones (drift, mount) ignored."""
    return GravityModel.from_gravity_in_base(theta[0:3], theta[9:12], theta[3:6], theta[6:9])


def relative_error_percent(
    residuals: NDArray[np.float64], wrench_mean: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The paper's Table 3: ``100 |residual| / |wrench_mean|`` per pose and axis, (P, 6); NaN
    where the mean reading is 0 or so small the ratio overflows (no relative error can be
    measured)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        relative = 100.0 * np.abs(residuals) / np.abs(wrench_mean)
    relative[~np.isfinite(relative)] = np.nan
    return relative


def calibrate(
    samples: Samples, *, method: Method = "joint", leave_one_out: bool = True
) -> Calibration:
    """Identify the sensor bias, tool weight and centre of gravity and the base tilt.

    Args:
        samples: readings at three or more distinct poses (see :func:`ftcomp.io.read_samples`).
        method: ``"paper"`` for the paper's two-stage linear least squares (Eq. 7-11, 16-19),
            ``"joint"`` for the weighted joint nonlinear fit (the default).
        leave_one_out: also measure the prediction error on each pose left out of the fit
            (``loo_error``; NaN when false or with only 3 poses). Exact for the paper method
            (closed form) and for the joint method up to 30 poses (refits); beyond, the joint
            method's is a one-step linearised approximation (:mod:`ftcomp.calibration.loo`).

    Raises:
        IdentificationError: fewer than 3 distinct poses, or poses that cannot separate bias
            from gravity; a reading or a fit that is not finite or absurd
            (:mod:`ftcomp.calibration.outliers`, which also names outlier poses in ``warnings``).
    """
    if method not in ("paper", "joint"):
        raise ParameterError(f"method must be 'paper' or 'joint', got {method!r}")
    check_readings(samples.wrench_sensor, samples.source, samples.pose)
    ids, R, wrench, count, var_mean = pose_means(samples)
    cond = _check_identifiable(R, samples.source)
    fit, sigma = fit_method(method, wrench, R, var_mean, count)
    check_fit(fit.theta, fit.covariance, samples.source)
    model = model_from_theta(fit.theta)
    std_errors = standard_errors_from_fit(fit.theta, fit.covariance)
    residuals = wrench - model.predict(R)
    relative = relative_error_percent(residuals, wrench)

    loo = np.full_like(wrench, np.nan)
    if leave_one_out:
        loo = _leave_one_out(method, wrench, R, var_mean, count, fit, sigma)

    warnings = list(samples.warnings)
    warnings.extend(w for w in [outlier_warning(ids, R, wrench)] if w is not None)
    if cond > CONDITION_WARNING:
        warnings.append(
            f"the poses are too alike to separate bias from gravity well (regressor condition "
            f"number {cond:.1f} > {CONDITION_WARNING:g}): tilt the tool further between poses"
        )
    return Calibration(
        model=model,
        method=method,
        std_errors=std_errors,
        pose_ids=ids,
        R_base_sensor=R,
        wrench_mean=wrench,
        readings_per_pose=count,
        residuals=residuals,
        relative_error_percent=relative,
        loo_error=loo,
        condition_number=cond,
        warnings=tuple(warnings),
    )


def deviations_in_standard_errors(
    calibration: Calibration, truth: GravityModel
) -> dict[str, float]:
    """``|identified - true| / standard error`` of every identified number (scoring against a
    known truth, e.g. the simulator's): keys ``tool_weight_N``, ``tilt_U_rad``, ``tilt_V_rad``
    and ``center_of_gravity_m[k]``, ``force_bias_N[k]``, ``torque_bias_Nm[k]``."""
    m, se = calibration.model, calibration.std_errors
    out = {
        "tool_weight_N": abs(m.weight_N - truth.weight_N) / se.weight_N,
        "tilt_U_rad": abs(m.tilt_U_rad - truth.tilt_U_rad) / se.tilt_U_rad,
        "tilt_V_rad": abs(m.tilt_V_rad - truth.tilt_V_rad) / se.tilt_V_rad,
    }
    for name in ("center_of_gravity_m", "force_bias_N", "torque_bias_Nm"):
        est, tru, err = getattr(m, name), getattr(truth, name), getattr(se, name)
        for k in range(3):
            out[f"{name}[{k}]"] = float(abs(est[k] - tru[k]) / err[k])
    return out


def max_deviations_in_standard_errors(
    calibration: Calibration, truth: GravityModel
) -> dict[str, float]:
    """The largest :func:`deviations_in_standard_errors` per parameter (vectors by their worst
    component): ``tool_weight_N``, ``force_bias_N``, ``torque_bias_Nm``, ``center_of_gravity_m``."""
    each = deviations_in_standard_errors(calibration, truth)
    names = ("tool_weight_N", "force_bias_N", "torque_bias_Nm", "center_of_gravity_m")
    return {n: max(v for k, v in each.items() if k.split("[")[0] == n) for n in names}
