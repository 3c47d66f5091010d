"""Leave-one-pose-out prediction error: how well a calibration predicts a pose it has not seen.

For each pose k, fit without it, predict its mean reading and compare:
``loo[k] = wrench[k] - prediction``. Refitting once per pose costs P fits, hours for thousands
of poses; instead:

- **paper method, exact, closed form.** Both stages are linear least squares. Deleting the three
  rows ``X_k`` of pose k changes the solution by
  ``beta_(-k) = beta - N^-1 X_k^T (I - H_kk)^-1 e_k`` (``N = X^T X``, ``H_kk = X_k N^-1 X_k^T``
  the 3x3 block of the hat matrix, ``e_k`` the residuals), and the stage-1 prediction error is
  ``(I - H_kk)^-1 e_k``. Stage 2 regresses on measured forces, so the torque prediction is
  ``b_(-k) + P_(-k) x f_pred``. O(P) in all; equal to refitting up to rounding.
- **joint method, exact refits up to** :data:`LOO_EXACT_MAX_POSES` **poses; beyond, an
  approximation**: one Gauss-Newton step from the full fit on the problem without pose k,
  ``theta_(-k) = theta + (J^T J - J_k^T J_k)^-1 (J_k^T r_k - J^T r)``, keeping the full fit's
  weights; the prediction itself is the nonlinear model at ``theta_(-k)``. Its error is of second
  order in the change one pose makes; at 100 poses it agrees with the refits within 5 %
  (``tests/calibration/test_loo.py``).

A pose whose removal leaves poses that cannot separate bias from gravity (force regressor
condition number above :data:`~ftcomp.calibration.methods.CONDITION_SINGULAR`) gets NaN.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.methods import (
    CONDITION_SINGULAR,
    F0,
    M0,
    A,
    Fit,
    Method,
    P,
    fit_method,
    force_regressor,
    joint_jacobian,
    joint_residuals,
    predict_wrench,
    torque_regressor,
)

__all__ = [
    "LOO_EXACT_MAX_POSES",
    "leave_one_out",
    "loo_joint_one_step",
    "loo_paper",
    "loo_refit",
    "reduced_condition",
]

#: Up to this many poses the joint method's leave-one-pose-out refits every pose exactly.
LOO_EXACT_MAX_POSES = 30


def reduced_condition(R_base_sensor: NDArray[np.float64]) -> NDArray[np.float64]:
    """Condition number of the force regressor (Eq. 7) without each pose in turn, shape (P,)."""
    X = force_regressor(R_base_sensor).reshape(-1, 3, 6)
    blocks = np.einsum("kij,kil->kjl", X, X)
    eig = np.linalg.eigvalsh(blocks.sum(axis=0) - blocks)  # ascending
    with np.errstate(divide="ignore", invalid="ignore"):
        cond = np.sqrt(eig[:, -1] / eig[:, 0])
    cond[~(eig[:, 0] > 0.0)] = np.inf
    return np.asarray(cond, dtype=float)


def _delete_one(
    X: NDArray[np.float64], y: NDArray[np.float64], usable: NDArray[np.bool_]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Least squares of ``y`` (P, 3) on ``X`` (P, 3, q) without each pose's rows, in closed form.

    Returns ``(loo_residual (P, 3), beta_without_k (P, q))``; rows where not ``usable`` are
    garbage (their reduced problem is singular).
    """
    N_inv = np.linalg.inv(np.einsum("kij,kil->jl", X, X))
    beta = N_inv @ np.einsum("kij,ki->j", X, y)
    e = y - X @ beta
    H = np.einsum("kij,jl,kml->kim", X, N_inv, X)
    I_minus_H = np.eye(3) - H
    I_minus_H[~usable] = np.eye(3)
    u = np.linalg.solve(I_minus_H, e[..., None])[..., 0]  # (I - H_kk)^-1 e_k
    return u, beta - np.einsum("jl,kml,km->kj", N_inv, X, u)


def loo_paper(wrench: NDArray[np.float64], R_base_sensor: NDArray[np.float64]) -> NDArray:
    """The paper method's leave-one-pose-out error, exact, in closed form, shape (P, 6)."""
    usable = reduced_condition(R_base_sensor) <= CONDITION_SINGULAR
    force, torque = wrench[:, :3], wrench[:, 3:]
    force_error, _ = _delete_one(force_regressor(R_base_sensor).reshape(-1, 3, 6), force, usable)
    _, beta = _delete_one(torque_regressor(force).reshape(-1, 3, 6), torque, usable)
    predicted_torque = beta[:, 3:] + np.cross(beta[:, :3], force - force_error)
    out = np.concatenate([force_error, torque - predicted_torque], axis=1)
    out[~usable] = np.nan
    return out


def loo_joint_one_step(
    wrench: NDArray[np.float64],
    R_base_sensor: NDArray[np.float64],
    sigma: NDArray[np.float64],
    fit: Fit,
) -> NDArray[np.float64]:
    """The joint method's leave-one-pose-out error by one Gauss-Newton step per pose from the
    full fit (an approximation, see the module docstring), shape (P, 6)."""
    usable = reduced_condition(R_base_sensor) <= CONDITION_SINGULAR
    r = joint_residuals(fit.theta, R_base_sensor, wrench, sigma).reshape(-1, 6)
    J = joint_jacobian(fit.theta, R_base_sensor, wrench, sigma).reshape(-1, 6, 12)
    blocks = np.einsum("kij,kil->kjl", J, J)
    reduced = blocks.sum(axis=0) - blocks
    reduced[~usable] = np.eye(12)
    step = np.einsum("kij,ki->kj", J, r)
    step -= step.sum(axis=0)
    theta = fit.theta + np.linalg.solve(reduced, step[..., None])[..., 0]  # (P, 12)
    g_s = np.einsum("kj,kjl->kl", theta[:, A], R_base_sensor)
    predicted = np.concatenate(
        [theta[:, F0] + g_s, theta[:, M0] + np.cross(theta[:, P], g_s)], axis=1
    )
    out = wrench - predicted
    out[~usable] = np.nan
    return out


def loo_refit(
    method: Method,
    wrench: NDArray[np.float64],
    R_base_sensor: NDArray[np.float64],
    var_mean: NDArray[np.float64],
    count: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Leave-one-pose-out error by refitting without each pose (exact; P fits), shape (P, 6)."""
    usable = reduced_condition(R_base_sensor) <= CONDITION_SINGULAR
    out = np.full_like(wrench, np.nan)
    for k in np.flatnonzero(usable):
        keep = np.arange(len(wrench)) != k
        fit, _ = fit_method(method, wrench[keep], R_base_sensor[keep], var_mean[keep], count[keep])
        out[k] = wrench[k] - predict_wrench(fit.theta, R_base_sensor[k : k + 1])[0]
    return out


def leave_one_out(
    method: Method,
    wrench: NDArray[np.float64],
    R_base_sensor: NDArray[np.float64],
    var_mean: NDArray[np.float64],
    count: NDArray[np.float64],
    fit: Fit,
    sigma: NDArray[np.float64] | None,
    *,
    exact: bool | None = None,
) -> NDArray[np.float64]:
    """Leave-one-pose-out prediction error of every pose, shape (P, 6); NaN with 3 poses or
    fewer, and where the other poses cannot identify the model.

    Args:
        method: the method ``fit`` was made with.
        wrench, R_base_sensor, var_mean, count: the per-pose data of the fit.
        fit: the fit on every pose; ``sigma`` its weights (joint method).
        exact: joint method only: True refits every pose, False takes the one-step
            approximation, None (default) refits up to :data:`LOO_EXACT_MAX_POSES` poses.
    """
    if len(wrench) <= 3:
        return np.full_like(wrench, np.nan)
    if method == "paper":
        return loo_paper(wrench, R_base_sensor)
    if exact or (exact is None and len(wrench) <= LOO_EXACT_MAX_POSES) or sigma is None:
        return loo_refit(method, wrench, R_base_sensor, var_mean, count)
    return loo_joint_one_step(wrench, R_base_sensor, sigma, fit)
