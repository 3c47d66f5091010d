"""The joint fit extended: a bias that drifts with time and an unknown sensor mount rotation.

The fit itself; :func:`ftcomp.calibration.identify_extended.calibrate_extended` turns its
parameters into a calibration (with :mod:`.drift` and :mod:`.mount`).

One weighted nonlinear least-squares fit over the per-pose means, as
:func:`ftcomp.calibration.methods.fit_joint`, with optional extra parameters::

    reading_i = bias(t_i) + gravity wrench of theta at R_rec_i @ R_rec_sensor(phi)
    bias(t)   = [F0, M0] + sum_k c_k tau^k,   tau = (t - t_ref) / half_span,  k = 1..order

``theta = [a, F0, M0, P]`` as in :mod:`.methods`; ``c`` (order x 6) are the drift coefficients in
scaled time; ``phi`` the mount's rotation vector (yaw: ``(0, 0, psi)``, about the recorded
frame's z axis; full: all three) applied after the nominal mount. The Jacobian is the joint
method's (analytic) for theta, analytic for c, central differences for phi.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.methods import joint_jacobian, predict_wrench
from ftcomp.calibration_record import MountAxes, mount_matrix

__all__ = ["ExtendedFit", "fit_extended", "predict_extended"]


@dataclass(frozen=True)
class ExtendedFit:
    """``x = [theta (12), c (order*6), phi (k)]``, its covariance ``s^2 (J^T J)^-1`` and the
    Fisher information ``J^T J / s^2`` (singular where the data cannot separate parameters)."""

    x: NDArray[np.float64]
    covariance: NDArray[np.float64]
    order: int
    mount_axes: MountAxes | None
    information: NDArray[np.float64]

    def unidentified(self, index: int) -> bool:
        """Whether parameter ``index`` is (numerically) inseparable from the others: its
        information left after the others explain what they can is below 1e-9 of its own."""
        F = self.information
        own = F[index, index]
        if not own > 0.0:
            return True
        rest = np.arange(len(F)) != index
        cross = F[rest, index]
        left = own - cross @ np.linalg.pinv(F[np.ix_(rest, rest)]) @ cross
        return bool(left < 1e-9 * own)

    @property
    def theta(self) -> NDArray[np.float64]:
        """The joint model's 12 parameters."""
        return self.x[:12]

    @property
    def drift(self) -> NDArray[np.float64]:
        """Drift coefficients in scaled time, shape (order, 6)."""
        return self.x[12 : 12 + 6 * self.order].reshape(self.order, 6)

    @property
    def phi(self) -> NDArray[np.float64]:
        """Mount parameters: (1,) yaw [rad], (3,) rotation vector, or (0,)."""
        return self.x[12 + 6 * self.order :]


def predict_extended(
    x: NDArray[np.float64],
    R_rec: NDArray[np.float64],
    basis: NDArray[np.float64],
    order: int,
    axes: MountAxes | None,
) -> NDArray[np.float64]:
    """The wrench an extended fit predicts, shape (N, 6).

    Args:
        x: the fit's parameters: the joint method's 12, then ``6 * order`` bias-drift
            coefficients, then the mount's (1 for yaw, 3 for full, none without).
        R_rec: the recorded orientations (the sensor's, or the flange's with a mount), (N, 3, 3).
        basis: the drift basis per row (powers of the scaled time), (N, order).
        order: the drift polynomial's order (0: constant bias).
        axes: the mount parameters, or None.
    """
    R = R_rec @ mount_matrix(x[12 + 6 * order :], axes)
    out = predict_wrench(x[:12], R)
    if order:
        out = out + basis @ x[12 : 12 + 6 * order].reshape(order, 6)
    return out


def fit_extended(
    wrench: NDArray[np.float64],
    R_rec: NDArray[np.float64],
    sigma: NDArray[np.float64],
    theta0: NDArray[np.float64],
    *,
    tau: NDArray[np.float64] | None = None,
    order: int = 0,
    mount_axes: MountAxes | None = None,
    phi0: NDArray[np.float64] | None = None,
) -> ExtendedFit:
    """Fit per-pose means with drift and/or mount parameters.

    Args:
        wrench: per-pose mean readings (P, 6); sigma: their standard deviations (P, 6).
        R_rec: recorded orientations (P, 3, 3) (the sensor's, or the flange's with a mount).
        theta0: starting joint parameters (12,), e.g. the paper method's.
        tau: each pose's scaled time (P,) (needed when ``order`` > 0).
        order: 0 (constant bias), 1 (linear) or 2 (quadratic).
        mount_axes: None, ``"yaw"`` or ``"full"``; phi0: its starting values (default zeros).
    """
    from scipy.optimize import least_squares  # imported here: it takes a second to load

    n_phi = 0 if mount_axes is None else (1 if mount_axes == "yaw" else 3)
    if order and tau is None:
        raise ValueError("fit_extended: a drift order needs tau")
    basis = (
        np.column_stack([np.asarray(tau) ** k for k in range(1, order + 1)])
        if order
        else np.zeros((len(wrench), 0))
    )
    x0 = np.concatenate([theta0, np.zeros(6 * order), np.zeros(n_phi) if phi0 is None else phi0])

    def residuals(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return ((predict_extended(x, R_rec, basis, order, mount_axes) - wrench) / sigma).ravel()

    def jacobian(x: NDArray[np.float64]) -> NDArray[np.float64]:
        R = R_rec @ mount_matrix(x[12 + 6 * order :], mount_axes)
        cols = [joint_jacobian(x[:12], R, wrench, sigma)]
        if order:  # d reading[p, c] / d c[k, c] = tau_p^k
            D = np.zeros((len(wrench), 6, order, 6))
            for c in range(6):
                D[:, c, :, c] = basis
            cols.append((D / sigma[:, :, None, None]).reshape(6 * len(wrench), 6 * order))
        for j in range(n_phi):
            h = 1e-6
            step = np.zeros_like(x)
            step[12 + 6 * order + j] = h
            cols.append(((residuals(x + step) - residuals(x - step)) / (2 * h))[:, None])
        return np.hstack(cols)

    result = least_squares(
        residuals, x0, jac=jacobian, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15
    )
    J = jacobian(result.x)
    dof = max(J.shape[0] - J.shape[1], 1)
    s2 = float(np.sum(result.fun**2)) / dof
    F = J.T @ J
    return ExtendedFit(
        np.asarray(result.x, dtype=float), s2 * np.linalg.pinv(F), order, mount_axes, F / s2
    )
