"""The two identification methods: the paper's two-stage linear fit and a joint nonlinear fit.

Both take per-pose mean readings ``wrench (P, 6)`` at orientations ``R_base_sensor (P, 3, 3)``
and return a :class:`Fit`: the parameter vector ``theta = [a (3), F0 (3), M0 (3), P (3)]`` where
``a`` is the tool's gravity in the base frame (Eq. 5), with its covariance. ``G, U, V`` follow
from ``a`` (Eq. 10-11); see :mod:`ftcomp.calibration` for the derived quantities.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration_record import Method
from ftcomp.model import skew

__all__ = [
    "CONDITION_SINGULAR",
    "Fit",
    "fit_joint",
    "fit_method",
    "fit_paper",
    "force_regressor",
    "joint_jacobian",
    "joint_residuals",
    "joint_sigma",
    "predict_wrench",
    "skew_stack",
    "torque_regressor",
]

#: Condition number of the force regressor above which bias and gravity are not separable.
CONDITION_SINGULAR = 1e7

#: Slices of the parameter vector theta.
A, F0, M0, P = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12)


@dataclass(frozen=True)
class Fit:
    """Estimated parameters ``theta = [a, F0, M0, P]`` (12,) and their covariance (12, 12)."""

    theta: NDArray[np.float64]
    covariance: NDArray[np.float64]


def force_regressor(R_base_sensor: NDArray[np.float64]) -> NDArray[np.float64]:
    """Eq. 7: rows ``[R_i.T, I]`` stacked, shape (3P, 6), unknowns ``[a, F0]``.

    The paper prints ``R_i`` here; the published numbers come out only with the transpose
    (``R_base_sensor.T`` maps base-frame gravity into the sensor frame).
    """
    n = len(R_base_sensor)
    blocks = np.concatenate(
        [np.transpose(R_base_sensor, (0, 2, 1)), np.broadcast_to(np.eye(3), (n, 3, 3))], axis=2
    )
    return blocks.reshape(3 * n, 6)


def skew_stack(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """The cross-product matrix of each row of ``v`` (N, 3): shape (N, 3, 3)."""
    out = np.zeros((len(v), 3, 3))
    out[:, 0, 1], out[:, 0, 2], out[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    out[:, 1, 0], out[:, 2, 0], out[:, 2, 1] = v[:, 2], -v[:, 1], v[:, 0]
    return out


def torque_regressor(force: NDArray[np.float64]) -> NDArray[np.float64]:
    """Eq. 16: rows ``[-skew(f_i), I]`` stacked, shape (3P, 6), unknowns ``[P, b]``."""
    n = len(force)
    blocks = np.concatenate([-skew_stack(force), np.broadcast_to(np.eye(3), (n, 3, 3))], axis=2)
    return blocks.reshape(3 * n, 6)


def predict_wrench(theta: NDArray[np.float64], R_base_sensor: NDArray[np.float64]) -> NDArray:
    """The model's reading at each pose, shape (P, 6)."""
    g_s = theta[A] @ R_base_sensor
    return np.concatenate([theta[F0] + g_s, theta[M0] + np.cross(theta[P], g_s)], axis=1)


def _linear_lstsq(
    X: NDArray[np.float64], y: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Ordinary least squares with the covariance ``s^2 (X^T X)^-1``, s^2 = RSS / dof."""
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    dof = max(len(y) - X.shape[1], 1)
    s2 = float(np.sum((y - X @ beta) ** 2)) / dof
    return np.asarray(beta, dtype=float), s2 * np.linalg.pinv(X.T @ X)


def fit_paper(wrench: NDArray[np.float64], R_base_sensor: NDArray[np.float64]) -> Fit:
    """The paper's two-stage linear least squares, exactly (Eq. 7-9, 16-19).

    Stage 1 regresses forces on ``[R_i.T, I]`` for ``[a, F0]``; stage 2 regresses torques on the
    *measured* forces for ``[P, b]`` and recovers ``M0 = b - F0 x P`` (Eq. 19). The covariance
    treats the two stages as independent and propagates Eq. 19 to first order.
    """
    force, torque = wrench[:, :3], wrench[:, 3:]
    a_f0, cov1 = _linear_lstsq(force_regressor(R_base_sensor), force.ravel())
    p_b, cov2 = _linear_lstsq(torque_regressor(force), torque.ravel())
    f0, p, b = a_f0[3:], p_b[:3], p_b[3:]
    m0 = b - np.cross(f0, p)
    theta = np.concatenate([a_f0[:3], f0, m0, p])
    # d theta / d [a, F0, P, b]: M0 = b - F0 x P = b + skew(P) F0 - ... linearised.
    J = np.zeros((12, 12))
    J[0:6, 0:6] = np.eye(6)  # a, F0
    J[6:9, 3:6] = skew(p)  # dM0/dF0 = -d(F0 x P)/dF0 = skew(P)
    J[6:9, 6:9] = -skew(f0)  # dM0/dP = -skew(F0)
    J[6:9, 9:12] = np.eye(3)  # dM0/db
    J[9:12, 6:9] = np.eye(3)  # P
    cov_in = np.zeros((12, 12))
    cov_in[:6, :6] = cov1
    cov_in[6:, 6:] = cov2
    return Fit(theta, J @ cov_in @ J.T)


def joint_residuals(
    theta: NDArray[np.float64],
    R_base_sensor: NDArray[np.float64],
    wrench: NDArray[np.float64],
    sigma: NDArray[np.float64],
) -> NDArray[np.float64]:
    """The joint method's residuals, prediction minus reading over the noise, shape (6P,)."""
    return ((predict_wrench(theta, R_base_sensor) - wrench) / sigma).ravel()


def joint_jacobian(
    theta: NDArray[np.float64],
    R_base_sensor: NDArray[np.float64],
    wrench: NDArray[np.float64],
    sigma: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Analytic Jacobian of the joint method's weighted residuals (:func:`joint_residuals`) in its
    12 parameters, shape (6P, 12): for pose design, leave-one-out and extended fits."""
    n = len(R_base_sensor)
    Rt = np.transpose(R_base_sensor, (0, 2, 1))
    g_s = theta[A] @ R_base_sensor
    J = np.zeros((n, 6, 12))
    J[:, :3, A] = Rt
    J[:, :3, F0] = np.eye(3)
    J[:, 3:, A] = skew(theta[P]) @ Rt
    J[:, 3:, M0] = np.eye(3)
    J[:, 3:, P] = -skew_stack(g_s)
    return (J / sigma[:, :, None]).reshape(6 * n, 12)


def fit_joint(
    wrench: NDArray[np.float64],
    R_base_sensor: NDArray[np.float64],
    sigma: NDArray[np.float64],
    initial: NDArray[np.float64],
) -> Fit:
    """All parameters together by weighted nonlinear least squares.

    The torque model uses the *modelled* gravity force ``R_i.T a`` rather than the measured force,
    so noise in the forces does not enter the regressor (the paper's stage 2 suffers from that).

    Args:
        wrench: per-pose mean readings, shape (P, 6).
        R_base_sensor: shape (P, 3, 3).
        sigma: standard deviation of each mean reading, shape (P, 6): the weights.
        initial: starting theta (12,), e.g. from :func:`fit_paper`.

    Returns:
        The fit, with covariance ``s^2 (J^T J)^-1``, ``s^2`` the weighted residual variance.
    """
    from scipy.optimize import least_squares  # imported here: it takes a second to load

    result = least_squares(
        joint_residuals,
        initial,
        jac=joint_jacobian,
        args=(R_base_sensor, wrench, sigma),
        method="lm",
        xtol=1e-15,
        ftol=1e-15,
        gtol=1e-15,
    )
    J = result.jac
    dof = max(J.shape[0] - J.shape[1], 1)
    s2 = float(np.sum(result.fun**2)) / dof
    return Fit(np.asarray(result.x, dtype=float), s2 * np.linalg.pinv(J.T @ J))


def joint_sigma(
    wrench: NDArray[np.float64],
    R_base_sensor: NDArray[np.float64],
    var_mean: NDArray[np.float64],
    count: NDArray[np.float64],
    paper: Fit,
) -> NDArray[np.float64]:
    """Standard deviation of each pose's mean reading, shape (P, 6): the joint fit's weights.

    From the pooled scatter of repeated readings per channel where there are any (scaled by
    1/sqrt(n) per pose), else from the paper fit's force and torque residuals.
    """
    repeated = count > 1
    if np.any(repeated):
        # Pooled within-pose variance of one reading, per channel.
        single_var = np.sum(
            var_mean[repeated] * count[repeated, None] * (count[repeated, None] - 1), axis=0
        )
        single_var /= np.sum(count[repeated] - 1)
        if np.all(single_var > 0.0):
            return np.sqrt(single_var[None, :] / count[:, None])
    r = predict_wrench(paper.theta, R_base_sensor) - wrench
    group = np.array([np.sqrt(np.mean(r[:, :3] ** 2)), np.sqrt(np.mean(r[:, 3:] ** 2))])
    group = np.maximum(group, 1e-12 * np.maximum(np.abs(wrench).max(), 1.0))
    return np.broadcast_to(np.repeat(group, 3), wrench.shape).copy()


def fit_method(
    method: Method,
    wrench: NDArray[np.float64],
    R_base_sensor: NDArray[np.float64],
    var_mean: NDArray[np.float64],
    count: NDArray[np.float64],
) -> tuple[Fit, NDArray[np.float64] | None]:
    """Fit per-pose means with ``method``; returns the fit and the joint fit's weights (sigma,
    (P, 6); None for the paper method).

    Args:
        wrench: per-pose mean readings (P, 6); ``var_mean`` the variance of each mean (P, 6),
            NaN where a pose has one reading; ``count`` readings per pose (P,).
    """
    paper = fit_paper(wrench, R_base_sensor)
    if method == "paper":
        return paper, None
    sigma = joint_sigma(wrench, R_base_sensor, var_mean, count, paper)
    return fit_joint(wrench, R_base_sensor, sigma, paper.theta), sigma
