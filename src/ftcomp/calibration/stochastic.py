"""The bias as a stochastic process, identified jointly with the tool model and the tilt.

``ftcomp calibrate --bias-drift stochastic``. A polynomial in time is too rigid for a handful of
poses and extrapolates wildly once the session is over; here the bias is the model's constant
plus a smooth wander ``g(t)``, a Matérn 3/2 process per axis (a state-space pair value/rate
driven by white noise, the covariance :func:`~ftcomp.calibration_record.matern32_correlation`)::

    mean reading_i = gravity wrench of theta at R_i + [F0, M0] + g(t_i) + e_i
    g_j ~ GP(0, scale_j^2 rho(t - t'; time_constant)),  e_ij ~ N(0, sigma_ij^2 + white_j^2)

with ``theta = [a, F0, M0, P]`` as in :mod:`.methods`. Marginalising ``g`` makes the fit a
generalised least squares with the covariance ``V_j = scale_j^2 rho + diag(sigma^2 + white^2)``
per axis; its hyperparameters (one time constant, six scales, a white scatter for force and one
for torque) maximise the restricted marginal likelihood (REML: the likelihood of the residuals
with the tool parameters integrated out), alternating with Gauss-Newton steps on ``theta``. The
tool parameters' covariance ``(J^T V^-1 J)^-1`` therefore includes the drift, and the bias at
any time is the process's smoothed estimate with the universal-kriging variance (the
tool parameters' uncertainty included).

The poses are few (tens to a few hundred): the Gaussian-process form with dense ``P x P``
Cholesky factors is exact and cheaper than a Kalman/RTS pass here; both give the same estimate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.identify import pose_groups
from ftcomp.calibration.sensor_map import map_jacobian, predict_mapped, prior_precision
from ftcomp.calibration_record import StochasticBiasDrift, matern32_correlation
from ftcomp.errors import IdentificationError
from ftcomp.samples import Samples

__all__ = [
    "MIN_POSES",
    "StochasticFit",
    "fit_stochastic",
    "linear_bias_log_likelihood",
    "pose_times",
]

#: Poses needed: 12 tool parameters and 9 hyperparameters from 6 numbers per pose.
MIN_POSES: Final = 6
_ROUNDS: Final = 3  # hyperparameters, then Gauss-Newton on theta, this many times
_GAUSS_NEWTON: Final = 8


def pose_times(samples: Samples) -> NDArray[np.float64]:
    """Each pose's mean time [s] (poses as :func:`~ftcomp.calibration.identify.pose_means`
    groups them), checked for the stochastic drift.

    Raises:
        IdentificationError: no ``t`` column; times that go back from one reading to the next;
            poses whose mean times do not increase in recording order.
    """
    if samples.t is None:
        raise IdentificationError(
            f"{samples.source}: bias_drift stochastic needs each reading's time: the file "
            "has no 't' (or 't_ns') column",
            field="bias_drift",
        )
    t = samples.t
    back = np.flatnonzero(np.diff(t) < 0.0)
    if back.size:
        k = int(back[0]) + 1
        raise IdentificationError(
            f"{samples.source}: t must not decrease from one reading to the next (row {k + 1}: "
            f"{t[k]:.9g} s after {t[k - 1]:.9g} s): bias_drift stochastic needs the readings "
            "in recording order on one clock",
            field="bias_drift",
        )
    group, first = pose_groups(samples)
    poses = len(first)
    t_pose = np.bincount(group, t, poses) / np.bincount(group, minlength=poses)
    if np.any(np.diff(t_pose) <= 0.0):
        raise IdentificationError(
            f"{samples.source}: the poses' mean times do not increase in recording order (a "
            "pose revisited later, or poses at one time): bias_drift stochastic needs each "
            "pose id recorded once, at its own time",
            field="bias_drift",
        )
    return t_pose


@dataclass(frozen=True)
class StochasticFit:
    """A joint fit with a stochastic bias.

    Attributes:
        theta: the tool parameters ``[a, F0, M0, P]`` (12,), ``F0, M0`` the process's mean.
        covariance: their covariance (12, 12), the drift included.
        drift: the smoothed bias process (the model's bias is ``F0, M0 + g(t_max)``).
        end_bias: the bias at the end of the calibration ``F0, M0 + g(t_max)``, (6,).
        log_likelihood: the restricted log marginal likelihood at the optimum (the map, when
            fitted, integrated out under its prior: comparable between fits with and without).
        sensor_map: the map ``delta`` (6, 3) and its standard errors (6, 3), or None.
    """

    theta: NDArray[np.float64]
    covariance: NDArray[np.float64]
    drift: StochasticBiasDrift
    end_bias: NDArray[np.float64]
    log_likelihood: float
    sensor_map: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None


class _Problem:
    """The data and the linearised GLS pieces for one ``theta``."""

    def __init__(
        self,
        wrench: NDArray[np.float64],
        R: NDArray[np.float64],
        sigma: NDArray[np.float64],
        t: NDArray[np.float64],
        n: int,
        regressor: NDArray[np.float64] | None = None,
    ) -> None:
        self.wrench, self.R, self.sigma2, self.t = wrench, R, sigma**2, t
        self.P, self.n = len(wrench), n
        self.dt = t[:, None] - t[None, :]
        #: With a regressor ``z`` the process is linear in it, ``g_j = k_j z``, ``k_j ~ N(0,
        #: scale_j^2)``: its correlation ``z z^T`` (the time constant unused); else Matérn 3/2.
        self.linear = None if regressor is None else np.outer(regressor, regressor)
        self.theta = np.zeros(n)
        self.r = np.zeros((self.P, 6))
        self.J = np.zeros((6, self.P, n))
        self.prior = prior_precision(n)
        mapped = self.prior > 0.0
        self.prior_logdet = float(np.sum(np.log(self.prior[mapped])))

    def linearise(self, theta: NDArray[np.float64]) -> None:
        """Residuals ``y - h(x)`` (P, 6) and ``dh/dx`` per axis (6, P, n)."""
        self.theta = theta
        self.r = self.wrench - predict_mapped(theta, self.R)
        self.J = map_jacobian(theta, self.R).transpose(1, 0, 2).copy()

    def normal(
        self, rw: NDArray[np.float64], Jw: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The Gauss-Newton system with the map's prior: ``(J^T V^-1 J + Lambda, J^T V^-1 r -
        Lambda x)``."""
        F = Jw.T @ Jw + np.diag(self.prior)
        return F, Jw.T @ rw - self.prior * self.theta

    def factor(self, h: NDArray[np.float64]) -> NDArray[np.float64]:
        """Cholesky factors of ``V_j`` for hyperparameters ``h`` (log), (6, P, P)."""
        ell, scale, white = _unpack(h)
        rho = matern32_correlation(self.dt, ell) if self.linear is None else self.linear
        V = scale[:, None, None] ** 2 * rho[None]
        diag = self.sigma2.T + (white**2)[:, None]
        V[:, np.arange(self.P), np.arange(self.P)] += diag
        return np.asarray(np.linalg.cholesky(V))

    def whiten(self, L: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``L^-1 r`` stacked (6P,) and ``L^-1 J`` stacked (6P, n)."""
        from scipy.linalg import solve_triangular

        rw = np.empty((6, self.P))
        Jw = np.empty((6, self.P, self.n))
        for j in range(6):
            both = solve_triangular(
                L[j], np.column_stack([self.r[:, j], self.J[j]]), lower=True, check_finite=False
            )
            rw[j], Jw[j] = both[:, 0], both[:, 1:]
        return rw.reshape(-1), Jw.reshape(6 * self.P, self.n)

    def neg_log_likelihood(self, h: NDArray[np.float64]) -> float:
        """Minus the restricted log marginal likelihood (constants dropped)."""
        try:
            L = self.factor(h)
        except np.linalg.LinAlgError:
            return math.inf
        rw, Jw = self.whiten(L)
        F, b = self.normal(rw, Jw)
        sign, logdet_F = np.linalg.slogdet(F)
        if sign <= 0:
            return math.inf
        delta = np.linalg.solve(F, b)
        x = self.theta + delta
        e = rw - Jw @ delta
        quad = float(e @ e + x @ (self.prior * x))
        logdet_V = 2.0 * float(np.sum(np.log(np.diagonal(L, axis1=1, axis2=2))))
        return 0.5 * (logdet_V + logdet_F - self.prior_logdet + quad)


def _unpack(h: NDArray[np.float64]) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """``(time constant [s], scale (6,), white (6,))`` from the log hyperparameters (9,)."""
    e = np.exp(h)
    return float(e[0]), e[1:7], np.repeat(e[7:9], 3)


def fit_stochastic(
    wrench: NDArray[np.float64],
    R: NDArray[np.float64],
    sigma: NDArray[np.float64],
    theta0: NDArray[np.float64],
    t_pose_s: NDArray[np.float64],
    *,
    t_range_s: tuple[float, float] | None = None,
    source: str = "the poses",
    drift: bool = True,
    sensor_map: bool = False,
    leave_one_out: bool = True,
) -> tuple[StochasticFit, NDArray[np.float64]]:
    """Fit per-pose means with a Matérn 3/2 bias process and/or a general linear sensor map
    (:mod:`.sensor_map`); hyperparameters by REML.

    Args:
        wrench: per-pose mean readings (P, 6) [N, N*m], sensor frame.
        R: their orientations ``R_base_sensor`` (P, 3, 3).
        sigma: the readings' noise in each mean (P, 6) (zeros where unknown: the white scatter
            hyperparameter then carries it).
        theta0: starting tool parameters (12,), e.g. the constant-bias joint fit's.
        t_pose_s: each pose's mean time [s] (P,), increasing.
        t_range_s: the calibration's time range [s] (default: the poses' times).
        source: where the poses came from, for messages.
        drift: fit the bias process (False: a constant bias, the white scatter alone).
        sensor_map: fit the map ``delta`` too, under its prior.
        leave_one_out: compute the leave-one-pose-out errors (P refits; NaN if not).

    Returns:
        The fit, and each pose's leave-one-pose-out error (P, 6) (hyperparameters held).
    """
    P = len(wrench)
    if drift and P < MIN_POSES:
        raise IdentificationError(
            f"{source}: {P} poses; bias_drift stochastic needs at least {MIN_POSES} (12 tool "
            "parameters and 9 hyperparameters of the drift from 6 numbers per pose)",
            field="bias_drift",
        )
    n = 30 if sensor_map else 12
    problem = _Problem(wrench, R, sigma, t_pose_s, n)
    problem.linearise(np.concatenate([theta0[:12], np.zeros(n - 12)]))
    span = float(t_pose_s[-1] - t_pose_s[0])
    gap = float(np.min(np.diff(t_pose_s)))
    spread = np.maximum(np.std(problem.r, axis=0), 1e-9)
    floor = np.maximum(np.array([spread[:3].mean(), spread[3:].mean()]), 1e-9)
    h = np.concatenate([[math.log(span / 2.0)], np.log(spread), np.log(floor / 4.0)])
    bounds = (
        [(math.log(max(gap, 1e-9) / 2.0), math.log(20.0 * span))]
        + [(math.log(s * 1e-4), math.log(s * 10.0)) for s in spread]
        + [(math.log(f * 1e-5), math.log(f * 10.0)) for f in floor]
    )
    if not drift:  # the process held at a negligible size: a constant bias
        h[1:7] = np.log(spread * 1e-9)
        bounds[:7] = [(v, v) for v in h[:7]]
    h, nll = _optimise(problem, h, bounds)
    fit = _result(problem, h, nll, t_range_s or (float(t_pose_s[0]), float(t_pose_s[-1])))
    return fit, _leave_one_out(problem, h) if leave_one_out else np.full((P, 6), np.nan)


def _optimise(
    problem: _Problem, h: NDArray[np.float64], bounds: list[tuple[float, float]]
) -> tuple[NDArray[np.float64], float]:
    """REML hyperparameters alternating with Gauss-Newton steps on ``theta`` (left in
    ``problem``): the log hyperparameters and the minus log likelihood reached."""
    from scipy.optimize import minimize  # imported here: it takes a second to load

    nll = math.inf
    for _ in range(_ROUNDS):
        result = minimize(problem.neg_log_likelihood, h, method="L-BFGS-B", bounds=bounds)
        h = np.asarray(result.x, dtype=float)
        nll = float(result.fun)
        L = problem.factor(h)
        theta = problem.theta
        for _ in range(_GAUSS_NEWTON):
            F, b = problem.normal(*problem.whiten(L))
            delta = np.linalg.lstsq(F, b, rcond=None)[0]
            theta = theta + delta
            problem.linearise(theta)
            if np.all(np.abs(delta) <= 1e-10 * np.maximum(np.abs(theta), 1.0)):
                break
    return h, nll


def linear_bias_log_likelihood(
    wrench: NDArray[np.float64],
    R: NDArray[np.float64],
    sigma: NDArray[np.float64],
    theta0: NDArray[np.float64],
    regressor: NDArray[np.float64],
) -> float:
    """The restricted log marginal likelihood of a bias linear in a per-pose regressor (the
    sensor's temperature), in the framework of :func:`fit_stochastic`: comparable with its
    ``log_likelihood`` for the same poses, a constant bias being this model with its slopes
    held at zero (nested, as the process in time is).

    The bias is ``[F0, M0] + k z_i`` per axis with ``k_j ~ N(0, scale_j^2)`` integrated out:
    the covariance ``V_j = scale_j^2 z z^T + diag(sigma^2 + white^2)``; its hyperparameters (six
    scales, the two white scatters) by REML, the tool parameters integrated out as there.

    Args:
        wrench, R, sigma, theta0: as :func:`fit_stochastic`.
        regressor: each pose's regressor, centred and scaled to about -1 .. 1, (P,).
    """
    problem = _Problem(wrench, R, sigma, np.arange(len(wrench), dtype=float), 12, regressor)
    problem.linearise(np.asarray(theta0[:12], dtype=float))
    spread = np.maximum(np.std(problem.r, axis=0), 1e-9)
    floor = np.maximum(np.array([spread[:3].mean(), spread[3:].mean()]), 1e-9)
    h = np.concatenate([[0.0], np.log(spread), np.log(floor / 4.0)])
    bounds = (
        [(0.0, 0.0)]  # the time constant: unused by a linear bias
        + [(math.log(s * 1e-4), math.log(s * 10.0)) for s in spread]
        + [(math.log(f * 1e-5), math.log(f * 10.0)) for f in floor]
    )
    _, nll = _optimise(problem, h, bounds)
    return -nll


def _leave_one_out(problem: _Problem, h: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each pose's residual minus its prediction from the others, (P, 6): the tool parameters
    refitted (one generalised least-squares step from the full fit's, hyperparameters held) and
    the bias at its time smoothed from the other poses."""
    from scipy.linalg import cho_factor, cho_solve

    ell, scale, white = _unpack(h)
    P = problem.P
    rho = matern32_correlation(problem.dt, ell)
    V = scale[:, None, None] ** 2 * rho[None]
    V[:, np.arange(P), np.arange(P)] += problem.sigma2.T + (white**2)[:, None]
    out = np.empty((P, 6))
    for i in range(P):
        keep = np.arange(P) != i
        factors = [cho_factor(V[j][np.ix_(keep, keep)], lower=True) for j in range(6)]
        solved = [
            cho_solve(factors[j], np.column_stack([problem.r[keep, j], problem.J[j][keep]]))
            for j in range(6)
        ]
        F = sum(problem.J[j][keep].T @ solved[j][:, 1:] for j in range(6)) + np.diag(problem.prior)
        b = sum(problem.J[j][keep].T @ solved[j][:, 0] for j in range(6)) - (
            problem.prior * problem.theta
        )
        delta = np.linalg.lstsq(F, b, rcond=None)[0]
        for j in range(6):
            left = solved[j][:, 0] - solved[j][:, 1:] @ delta  # V^-1 (r - J delta), others
            predicted = problem.J[j][i] @ delta + V[j][i, keep] @ left
            out[i, j] = problem.r[i, j] - predicted
    return out


def _result(
    problem: _Problem, h: NDArray[np.float64], nll: float, t_range: tuple[float, float]
) -> StochasticFit:
    """The fit's record at the final hyperparameters and linearisation."""
    from scipy.linalg import cho_solve, solve_triangular

    ell, scale, white = _unpack(h)
    L = problem.factor(h)
    F, _ = problem.normal(*problem.whiten(L))
    _, Jw = problem.whiten(L)
    cov = np.asarray(np.linalg.pinv(F), dtype=np.float64)
    P, t = problem.P, problem.t
    weights = np.column_stack([cho_solve((L[j], True), problem.r[:, j]) for j in range(6)])
    # Posterior standard error of the bias F0_j + g_j(t*) (universal kriging).
    t_eval = np.concatenate([t, [t_range[1]]])
    rho = matern32_correlation(t_eval[:, None] - t[None, :], ell)  # (P + 1, P)
    std = np.empty((P + 1, 6))
    Jw3 = Jw.reshape(6, P, problem.n)
    for j in range(6):
        k = scale[j] ** 2 * rho  # (P + 1, P)
        w = solve_triangular(L[j], k.T, lower=True, check_finite=False)  # (P, P + 1)
        u = -(Jw3[j].T @ w)  # (n, P + 1)
        u[3 + j] += 1.0  # the selector of F0_j (or M0_j)
        var = scale[j] ** 2 - np.sum(w * w, axis=0) + np.einsum("ip,ij,jp->p", u, cov, u)
        std[:, j] = np.sqrt(np.maximum(var, 0.0))
    drift = StochasticBiasDrift(
        t_knots_s=t,
        weights=weights,
        scale=scale,
        time_constant_s=ell,
        white_noise=white,
        knot_std=std[:P],
        end_std=std[P],
        t_min_s=t_range[0],
        t_max_s=t_range[1],
    )
    g_end = (scale**2 * weights * matern32_correlation(t_range[1] - t, ell)[:, None]).sum(axis=0)
    end_bias = problem.theta[3:9] + g_end
    x = problem.theta
    mapped = None
    if problem.n > 12:
        se = np.sqrt(np.maximum(np.diag(cov)[12:30], 0.0))
        mapped = (x[12:30].reshape(6, 3).copy(), se.reshape(6, 3))
    return StochasticFit(x[:12].copy(), cov[:12, :12], drift, end_bias, -nll, mapped)
