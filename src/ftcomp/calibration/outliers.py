"""Readings and fits no sensor could produce, and poses whose readings disagree with the rest.

**Plausibility.** No force/torque sensor reads beyond
:data:`~ftcomp.constants.PLAUSIBLE_FORCE_N` (1e6 N, a hundred tonnes) or
:data:`~ftcomp.constants.PLAUSIBLE_TORQUE_NM` (1e5 N*m); the largest six-axis sensors made
stop near 1e5 N and 1e4 N*m. A reading beyond them is a corrupt cell or a unit mistake, and
letting it into a least-squares fit gives a meaningless result (readings near 1e155 overflow
the squares). The sample readers reject such readings (naming row and column), and
:func:`check_readings` and :func:`check_fit` guard :func:`ftcomp.calibration.identify.calibrate`
for samples built in code.

**Outlier poses.** One corrupt reading that still parses (``33445`` for ``3.3445``) pulls the
least-squares fit towards it and spreads its error over every pose, so the ordinary residuals
hide it. :func:`outlier_warning` uses *externally studentised* residuals instead: for each pose
``k``, its residual as predicted by the fit *without* ``k`` (closed form for the linear
regressions of the paper method, Eq. 7 and 16), divided by the residual standard deviation of
that fit. A clean pose is then a few standard deviations at most; a corrupt one hundreds.
Poses beyond :func:`outlier_threshold` (8 sd, more with fewer than 6 poses) are named in a
warning; they are not removed (the fit is the user's data; the warning says which poses to
check or leave out).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.methods import force_regressor, torque_regressor
from ftcomp.constants import PLAUSIBLE_FORCE_N, PLAUSIBLE_TORQUE_NM
from ftcomp.errors import IdentificationError

__all__ = [
    "OUTLIER_THRESHOLD",
    "PLAUSIBLE_COG_M",
    "check_fit",
    "check_readings",
    "outlier_threshold",
    "outlier_warning",
    "studentized_pose_residuals",
]

#: Externally studentised residual [standard deviations] beyond which a pose is an outlier,
#: at least: with few poses the threshold rises so that clean Gaussian readings are flagged in
#: fewer than one calibration in a thousand (Bonferroni over every pose and column, the
#: residuals' t distribution); 8 with 9 poses or more.
OUTLIER_THRESHOLD = 8.0
_FALSE_ALARM = 1e-3  # chance of any warning on clean Gaussian readings, per calibration
_MIN_DOF = 3  # degrees of freedom left without a pose, below which no scale can be trusted
_RELATIVE_FLOOR = 1e-7  # residual scale floor relative to the readings (exact synthetic data)
_COLUMNS = ("fx", "fy", "fz", "tx", "ty", "tz")


def check_readings(
    wrench: NDArray[np.float64], source: str, pose: Sequence[str] | NDArray | None = None
) -> None:
    """Raise if a reading (N, 6) is not finite or beyond the plausible bounds.

    Raises:
        IdentificationError: naming the row (1 = first), its pose id and the column.
    """
    limits = np.array([PLAUSIBLE_FORCE_N] * 3 + [PLAUSIBLE_TORQUE_NM] * 3)
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(wrench) <= limits)
    if bad.any():
        k, j = (int(v) for v in np.argwhere(bad)[0])
        unit = "N" if j < 3 else "N*m"
        at = f"row {k + 1}" if pose is None else f"row {k + 1} (pose {pose[k]})"
        raise IdentificationError(
            f"{source}: {at}, column {_COLUMNS[j]!r}: {wrench[k, j]:g} {unit} is not a "
            f"plausible F/T reading (finite, within +-{limits[j]:g} {unit})"
        )


#: Farthest a tool's centre of gravity may lie from the sensor [m]: beyond the reach of the
#: largest collaborative arms (a UR10e reaches 1.3 m). Torques in N*mm read as N*m put it 1000x
#: too far, tens of metres for a real tool.
PLAUSIBLE_COG_M = 2.0


def check_fit(theta: NDArray[np.float64], covariance: NDArray[np.float64], source: str) -> None:
    """Raise if an identified ``theta = [a, F0, M0, P]`` is not finite or absurd: gravity or
    force bias beyond :data:`PLAUSIBLE_FORCE_N`, torque bias beyond :data:`PLAUSIBLE_TORQUE_NM`.

    Raises:
        IdentificationError: one line, with what was found.
    """
    if not (np.isfinite(theta).all() and np.isfinite(np.diag(covariance)).all()):
        raise IdentificationError(
            f"{source}: the fit did not converge to finite values; check the readings"
        )
    weight = float(np.linalg.norm(theta[0:3]))
    force_bias = float(np.abs(theta[3:6]).max())
    torque_bias = float(np.abs(theta[6:9]).max())
    if weight > PLAUSIBLE_FORCE_N or force_bias > PLAUSIBLE_FORCE_N:
        raise IdentificationError(
            f"{source}: absurd fit (tool weight {weight:.3g} N, force bias up to "
            f"{force_bias:.3g} N, beyond {PLAUSIBLE_FORCE_N:g} N); check the readings"
        )
    if torque_bias > PLAUSIBLE_TORQUE_NM:
        raise IdentificationError(
            f"{source}: absurd fit (torque bias up to {torque_bias:.3g} N*m, beyond "
            f"{PLAUSIBLE_TORQUE_NM:g} N*m); check the readings"
        )
    cog = float(np.linalg.norm(theta[9:12]))
    if cog > PLAUSIBLE_COG_M:
        milli = f" ({cog / 1000.0:.3g} m if the torques were N*mm)" if cog > 100.0 else ""
        raise IdentificationError(
            f"{source}: the identified centre of gravity is {cog:.4g} m from the sensor, beyond "
            f"any tool on an arm ({PLAUSIBLE_COG_M:g} m){milli}: are the torques tx, ty, tz in "
            "N*m? ftcomp reads forces in N and torques in N*m (divide torques in N*mm by 1000)"
        )
    a = theta[0:3]
    if not a[2] < 0.0 or abs(a[1]) >= weight:  # tilted 90 deg or more, or no weight at all
        raise IdentificationError(
            f"{source}: the identified tool gravity a = [{a[0]:.3g}, {a[1]:.3g}, {a[2]:.3g}] N "
            "does not point down the base's z axis (a base tilted 90 deg or more): are the "
            "orientations R_base_sensor right (recorded from a robot: its TCP pose times the "
            "sensor's mount on the flange, as given to record; a wrong mount turns gravity away) "
            "and the readings in the sensor frame (docs/conventions.md)?"
        )


def _studentized(X: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float64]:
    """Externally studentised residuals of ``y ~ X beta``, rows in blocks of 3 (one block per
    pose): shape (P, 3), NaN where a pose cannot be left out."""
    n_rows, n_params = X.shape
    poses = n_rows // 3
    out = np.full((poses, 3), np.nan)
    dof = n_rows - 3 - n_params
    if dof < _MIN_DOF:
        return out
    Q, _ = np.linalg.qr(X)
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    e = (y - X @ beta).reshape(poses, 3)
    Qk = Q.reshape(poses, 3, n_params)
    M = np.eye(3) - Qk @ np.transpose(Qk, (0, 2, 1))  # I - H_kk
    ok = np.linalg.cond(M) < 1e8  # pose k not needed to identify beta
    if not ok.any():
        return out
    V = np.linalg.inv(M[ok])  # covariance of the deleted residual / sigma^2
    deleted = np.einsum("kij,kj->ki", V, e[ok])
    rss = float(e.ravel() @ e.ravel()) - np.einsum("ki,ki->k", e[ok], deleted)
    floor = _RELATIVE_FLOOR * max(float(np.sqrt(np.mean(y**2))), 1e-300)
    scale = np.maximum(np.sqrt(np.maximum(rss, 0.0) / dof), floor)
    diag = np.sqrt(np.maximum(np.diagonal(V, axis1=1, axis2=2), 0.0))
    out[ok] = deleted / (scale[:, None] * diag)
    return out


def studentized_pose_residuals(
    R_base_sensor: NDArray[np.float64], wrench: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Each pose's externally studentised residual per column ``fx..tz`` (P, 6), from the
    paper method's linear regressions (forces on ``[R.T, I]``, torques on the measured
    forces); NaN where undefined (fewer than 4 poses, or a pose the others cannot do without).
    """
    force, torque = wrench[:, :3], wrench[:, 3:]
    with np.errstate(all="ignore"):
        return np.concatenate(
            [
                _studentized(force_regressor(R_base_sensor), force.ravel()),
                _studentized(torque_regressor(force), torque.ravel()),
            ],
            axis=1,
        )


def outlier_warning(
    ids: Sequence[str], R_base_sensor: NDArray[np.float64], wrench: NDArray[np.float64]
) -> str | None:
    """A warning naming every pose whose readings disagree with the others by more than
    :data:`OUTLIER_THRESHOLD` standard deviations (its worst column), or None."""
    z = np.abs(studentized_pose_residuals(R_base_sensor, wrench))
    z[~np.isfinite(z)] = 0.0
    worst = z.max(axis=1) if len(z) else z
    threshold = outlier_threshold(len(z))
    flagged = np.flatnonzero(worst > threshold)
    if not flagged.size:
        return None
    order = flagged[np.argsort(-worst[flagged], kind="stable")]
    shown = [f"{ids[k]} ({_COLUMNS[int(z[k].argmax())]}: {_sd(worst[k])} sd)" for k in order[:10]]
    more = f" and {len(order) - 10} more" if len(order) > 10 else ""
    return (
        f"OUTLIER POSE(S) {', '.join(shown)}{more}: readings disagree with the other poses by "
        f"more than {threshold:.3g} standard deviations of their residuals (externally "
        "studentised); the fit above includes them and may be wrong"
        f"{_weights(R_base_sensor, wrench, flagged)}: check those readings (a corrupt number?) "
        "or leave those poses out"
    )


def _weights(R: NDArray[np.float64], wrench: NDArray[np.float64], flagged: NDArray) -> str:
    """The paper method's tool weight with and without the flagged poses, as a clause."""
    keep = np.ones(len(R), dtype=bool)
    keep[flagged] = False
    X = force_regressor(R[keep])
    if keep.sum() < 3 or np.linalg.cond(X) > 1e7:  # the others alone cannot separate them
        return ""
    with_them, *_ = np.linalg.lstsq(force_regressor(R), wrench[:, :3].ravel(), rcond=None)
    without, *_ = np.linalg.lstsq(X, wrench[keep, :3].ravel(), rcond=None)
    return (
        f" (tool weight by the paper method: {np.linalg.norm(with_them[:3]):.4g} N with them, "
        f"{np.linalg.norm(without[:3]):.4g} N without)"
    )


def outlier_threshold(poses: int) -> float:
    """The studentised residual [sd] beyond which one of ``poses`` poses is named."""
    dof = 3 * poses - 9  # each regression: 3 rows per pose, 6 parameters, one pose left out
    if dof < _MIN_DOF:
        return math.inf
    # Student's t's quantile from scipy.special (what scipy.stats.t.isf computes, to the last
    # bit): importing scipy.stats took a second of every ``calibrate`` (2.2 s in all, 2-core).
    from scipy.special import stdtrit

    bound = -float(stdtrit(dof, _FALSE_ALARM / (2 * 6 * poses)))
    return max(OUTLIER_THRESHOLD, bound)


def _sd(value: float) -> str:
    return f"{value:.3g}" if math.isfinite(value) else "inf"
