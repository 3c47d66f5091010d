"""Bias drift and re-bias: the sensor's zero offset as a function of time.

Real sensors' bias wanders (temperature): a calibration from poses recorded over minutes then
mixes that wander into the tool model. :func:`calibrate_extended` with ``bias_drift="linear"``
or ``"quadratic"`` fits the force and torque bias as a polynomial in the sample time ``t``
jointly with the tool model (:mod:`.extended`), so the tool model is shared by all poses and
the bias is free to move; the result carries a :class:`BiasDrift` (rates with standard errors,
the time range it was fitted over). The model's ``F0, M0`` are the bias at the end of the
recording (``t_ref``), the best constant for what comes next.

:func:`rebias` is the practical cure for drift: with the tool model known, a few seconds of
still readings at any one pose without contact give the bias alone (``reading - tool
gravity wrench``), gravity-aware where a vendor's tare is not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Final, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.arrays import freeze_field
from ftcomp.calibration.extended import MountAxes, fit_extended
from ftcomp.calibration.identify import (
    Calibration,
    _groups,
    _model,
    _standard_errors,
    calibrate,
    pose_means,
)
from ftcomp.calibration.methods import fit_paper, joint_sigma
from ftcomp.calibration.mount import MIN_POSES, mount_from_fit, mount_warnings
from ftcomp.errors import IdentificationError
from ftcomp.model import GravityModel
from ftcomp.samples import Samples

__all__ = [
    "DRIFT_ORDERS",
    "BiasDrift",
    "DriftModel",
    "bias_from_still",
    "calibrate_extended",
    "rebias",
]

DriftModel = Literal["none", "linear", "quadratic"]
DRIFT_ORDERS: Final[dict[str, int]] = {"none": 0, "linear": 1, "quadratic": 2}
_LOO_REFITS: Final = 30  # leave-one-pose-out by exact refits up to this many poses


@dataclass(frozen=True)
class BiasDrift:
    """The bias as a polynomial in time: ``bias(t) = [F0, M0] + sum_k c_k (t - t_ref)^k``.

    Attributes:
        order: 1 (linear) or 2 (quadratic).
        t_ref_s: reference time [s] (the model's ``F0, M0`` are the bias then).
        t_min_s, t_max_s: the time range the drift was fitted over [s].
        coefficients: ``c_k`` per row k = 1..order, ``[N/s^k]*3 + [N*m/s^k]*3``, (order, 6).
        std_errors: their standard errors, (order, 6).
    """

    order: int
    t_ref_s: float
    t_min_s: float
    t_max_s: float
    coefficients: NDArray[np.float64]
    std_errors: NDArray[np.float64]

    def __post_init__(self) -> None:
        if self.order not in (1, 2):
            raise ValueError(f"BiasDrift.order must be 1 or 2, got {self.order}")
        freeze_field(self, "coefficients", (self.order, 6), finite=True)
        freeze_field(self, "std_errors", (self.order, 6))

    @property
    def name(self) -> DriftModel:
        """``"linear"`` or ``"quadratic"``."""
        return "linear" if self.order == 1 else "quadratic"

    def offset(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """Bias at ``t_s`` [s] minus the bias at ``t_ref``, shape (N, 6) (or (6,))."""
        dt = np.asarray(t_s, dtype=float) - self.t_ref_s
        out = np.multiply.outer(dt, self.coefficients[0])
        if self.order == 2:
            out += np.multiply.outer(dt * dt, self.coefficients[1])
        return out

    def to_dict(self) -> dict[str, object]:
        """Calibration-file form."""
        return {
            "model": self.name,
            "t_ref_s": self.t_ref_s,
            "t_range_s": [self.t_min_s, self.t_max_s],
            "columns": ["fx", "fy", "fz", "tx", "ty", "tz"],
            "coefficients_per_s_power": self.coefficients.tolist(),
            "std_errors": [[v if math.isfinite(v) else None for v in r] for r in self.std_errors],
        }


def _se(values: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.sqrt(np.maximum(values, 0.0))


def calibrate_extended(
    samples: Samples,
    *,
    bias_drift: DriftModel = "none",
    identify_mount: MountAxes | None = None,
    leave_one_out: bool = True,
) -> Calibration:
    """The joint method with a drifting bias and/or an unknown mount rotation.

    Args:
        samples: readings at distinct poses; a drift model needs their times (``t``).
        bias_drift: ``"none"``, ``"linear"`` or ``"quadratic"`` in time.
        identify_mount: None, ``"yaw"`` (about the recorded frame's z) or ``"full"``; the
            samples' orientations are then the recorded frame's (flange, TCP).
        leave_one_out: each pose predicted (at its time) by a refit to the others.

    Raises:
        IdentificationError: no ``t`` for a drift model, too few poses for the parameters.
    """
    order = DRIFT_ORDERS.get(bias_drift)
    if order is None:
        raise IdentificationError(f"bias drift must be one of {', '.join(DRIFT_ORDERS)}")
    if order and samples.t is None:
        raise IdentificationError(
            f"{samples.source}: --bias-drift {bias_drift} needs each reading's time: the file "
            "has no 't' (or 't_ns') column"
        )
    base = calibrate(samples, method="joint", leave_one_out=False)
    ids, R, wrench, count, var_mean = pose_means(samples)
    P = len(ids)
    needed = 3 + order
    if identify_mount is not None:
        needed = max(needed, MIN_POSES[identify_mount])
    if needed > P:
        what = [f"--bias-drift {bias_drift}"] if order else []
        what += [f"--identify-mount {identify_mount}"] if identify_mount else []
        raise IdentificationError(
            f"{samples.source}: {P} poses; {' with '.join(what)} needs at least {needed}"
        )
    tau, t_ref, t_min, t_max, half = None, math.nan, math.nan, math.nan, 1.0
    if order:
        assert samples.t is not None
        group, _ = _groups(samples)
        t_pose = np.bincount(group, samples.t, P) / count
        t_min, t_max = float(samples.t.min()), float(samples.t.max())
        t_ref, half = t_max, max((t_max - t_min) / 2.0, 1e-9)
        tau = (t_pose - t_ref) / half
        if len(np.unique(np.round(t_pose, 9))) <= order:
            raise IdentificationError(
                f"{samples.source}: the poses' times take {order} value(s) or fewer: a "
                f"{bias_drift} drift needs poses recorded at {order + 1} or more times"
            )
    paper = fit_paper(wrench, R)
    sigma = joint_sigma(wrench, R, var_mean, count, paper)
    fit = fit_extended(
        wrench, R, sigma, paper.theta, tau=tau, order=order, mount_axes=identify_mount
    )
    theta, cov = fit.theta, fit.covariance
    model = _model(theta)
    se = _se(np.diag(cov))
    std_errors = _standard_errors(theta, cov)
    drift = None
    if order:
        scale = np.repeat(half ** -np.arange(1, order + 1, dtype=float), 6)
        drift_se = se[12 : 12 + 6 * order] * scale
        drift = BiasDrift(
            order,
            t_ref,
            t_min,
            t_max,
            (fit.drift.ravel() * scale).reshape(order, 6),
            drift_se.reshape(order, 6),
        )
    mount = mount_from_fit(fit) if identify_mount is not None else None
    R_sensor = R if mount is None else R @ mount.R_rec_sensor
    predicted = model.predict(R_sensor)
    if drift is not None and tau is not None:
        predicted = predicted + drift.offset(t_ref + tau * half)
    residuals = wrench - predicted
    with np.errstate(divide="ignore", invalid="ignore"):
        relative = 100.0 * np.abs(residuals) / np.abs(wrench)
    relative[~np.isfinite(relative)] = np.nan
    loo = np.full_like(wrench, np.nan)
    if leave_one_out and needed < P:
        loo = _leave_one_out(wrench, R, sigma, fit.x, tau, order, identify_mount)
    warnings = list(base.warnings)
    if mount is not None:
        warnings += mount_warnings(mount)
    return replace(
        base,
        model=model,
        std_errors=std_errors,
        residuals=residuals,
        relative_error_percent=relative,
        loo_error=loo,
        warnings=tuple(warnings),
        bias_drift=drift,
        mount=mount,
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
    from ftcomp.calibration.extended import predict_extended

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


def bias_from_still(
    model: GravityModel, wrench_sensor: ArrayLike, R_base_sensor: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The bias ``[F0, M0]`` from still readings without contact, the tool model known.

    Args:
        model: the identified tool model (its bias is ignored).
        wrench_sensor: readings [N, N*m], sensor frame, (N, 6), at one or more poses.
        R_base_sensor: the sensor's orientation at each, (N, 3, 3).

    Returns:
        ``(bias (6,), standard error (6,))``, the standard error from the readings' scatter
        (NaN with a single reading). The live loop can call this on a buffer of readings.
    """
    w = np.atleast_2d(np.asarray(wrench_sensor, dtype=float))
    R = np.asarray(R_base_sensor, dtype=float).reshape(len(w), 3, 3)
    estimate = w - model.gravity_wrench(R)
    n = len(estimate)
    se = estimate.std(axis=0, ddof=1) / math.sqrt(n) if n > 1 else np.full(6, np.nan)
    return estimate.mean(axis=0), se


def rebias(calibration: Calibration, samples: Samples) -> Calibration:
    """The calibration with only its bias re-estimated from still readings (tool model kept).

    The samples' orientations are the sensor's, or the recorded frame's when the calibration
    carries a mount. A drift model is dropped: the new bias is the bias now.

    Raises:
        IdentificationError: no readings.
    """
    if len(samples) == 0:
        raise IdentificationError(f"{samples.source}: no readings to re-estimate the bias from")
    R = samples.R_base_sensor
    if calibration.mount is not None:
        R = R @ calibration.mount.R_rec_sensor
    bias, se = bias_from_still(calibration.model, samples.wrench_sensor, R)
    m = calibration.model
    model = GravityModel(
        m.weight_N,
        m.center_of_gravity_m,
        bias[:3],
        bias[3:],
        tilt_U_rad=m.tilt_U_rad,
        tilt_V_rad=m.tilt_V_rad,
    )
    std_errors = replace(calibration.std_errors, force_bias_N=se[:3], torque_bias_Nm=se[3:])
    return replace(calibration, model=model, std_errors=std_errors, bias_drift=None)
