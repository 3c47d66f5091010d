"""Inverse kinematics of a serial chain within its joint limits (pose design's reachability
check, a Franka's joint moves).

:class:`ChainIk` finds joint positions that put a :class:`Chain`'s tip at a pose in its base
frame (a URDF's chain, :class:`~ftcomp.ros2.urdf.UrdfChain`; a Franka's own model,
:mod:`ftcomp.hardware.franka`): bounded nonlinear least squares
(:func:`scipy.optimize.least_squares`, trust region reflective, bounds = the joint limits,
continuous joints unbounded) on the residual ``[p - p_target; w (R - R_target)]`` (12 entries,
``w`` = :data:`ORIENTATION_WEIGHT_M`), whose Jacobian is exact from the chain's geometric
Jacobian (``d R / d q_i = [w_i]x R``). It starts from a configuration the caller gives (the
joints now, for a move nearest them), then from the previous solution (a warm start: the
design checks neighbouring orientations one after another), then from the mid-limit
configuration, then from seeded random configurations within the limits (a fixed generator, so
the same sequence of requests gives the same answers), and accepts the first solution within
``position_tol_m`` and ``angle_tol_rad``. It is a reachability check, not a controller: it
ignores collisions and self-collisions, as the simulated cell's IK does.
"""

from __future__ import annotations

import math
from typing import Final, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from ftcomp.errors import ParameterError

__all__ = ["ORIENTATION_WEIGHT_M", "Chain", "ChainIk", "mid_configuration"]

#: Weight of the orientation residual ``R - R_target`` [m]: a rotation by a small angle theta
#: [rad] counts as ``sqrt(2) * 0.1 * theta`` metres (1 deg as 2.5 mm), an arm's link scale.
ORIENTATION_WEIGHT_M: Final = 0.1
#: Span a start is drawn from for a joint without limits: [rad] revolute, [m] prismatic.
_UNBOUNDED_SPAN: Final = {True: math.pi, False: 0.5}
#: A joint whose lower and upper limits are equal is widened by this much [rad or m] (the
#: solver needs ``lower < upper``), far below any tolerance here.
_WIDEN: Final = 1e-9


class Chain(Protocol):
    """A serial chain's kinematics: what :class:`ChainIk` solves on."""

    #: The movable joints' names, in the order of ``q``.
    joint_names: tuple[str, ...]
    #: Each joint's ``[lower, upper]`` [rad or m], shape (n, 2); infinite where unlimited.
    joint_limits: NDArray[np.float64]
    #: True for each revolute or continuous joint, False for a prismatic one.
    joint_revolute: tuple[bool, ...]

    def pose_and_jacobian(
        self, q: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``T_base_tip`` (4, 4) and the geometric Jacobian (6, n), ``[v; w] = J @ dq``, both
        in the base frame."""
        ...


def mid_configuration(chain: Chain) -> NDArray[np.float64]:
    """The middle of every joint's range [rad or m] (0 for a joint without limits), shape (n,)."""
    lower, upper = chain.joint_limits.T
    bounded = np.isfinite(lower) & np.isfinite(upper)
    mid = np.where(bounded, lower, 0.0) / 2.0 + np.where(bounded, upper, 0.0) / 2.0
    return np.where(bounded, mid, np.clip(0.0, lower, upper))


class ChainIk:
    """Joint positions placing a chain's tip at a pose, within its joint limits.

    Args:
        chain: the chain from the base link to the tip (sensor) link.
        starts: configurations tried after the warm start (the mid-limit one and ``starts - 1``
            random ones), at least 1.
        seed: the random starts' generator seed.
        position_tol_m: largest accepted position error [m].
        angle_tol_rad: largest accepted orientation error [rad].
    """

    def __init__(
        self,
        chain: Chain,
        *,
        starts: int = 8,
        seed: int = 0,
        position_tol_m: float = 1e-3,
        angle_tol_rad: float = math.radians(0.1),
    ) -> None:
        if starts < 1:
            raise ParameterError(f"starts {starts}: need at least 1")
        self.chain = chain
        self.position_tol_m = float(position_tol_m)
        self.angle_tol_rad = float(angle_tol_rad)
        lower, upper = np.array(chain.joint_limits, dtype=float).T
        same = lower == upper
        self._lower = np.where(same, lower - _WIDEN, lower)
        self._upper = np.where(same, upper + _WIDEN, upper)
        span = np.array([_UNBOUNDED_SPAN[r] for r in chain.joint_revolute])
        lo = np.where(np.isfinite(self._lower), self._lower, -span)
        hi = np.where(np.isfinite(self._upper), self._upper, span)
        lo, hi = np.minimum(lo, hi - _WIDEN), np.maximum(hi, lo + _WIDEN)  # one-sided limits
        rng = np.random.default_rng(seed)
        self._starts = [np.clip(mid_configuration(chain), lo, hi)]
        self._starts += [lo + (hi - lo) * rng.random(len(lo)) for _ in range(starts - 1)]
        self._last: NDArray[np.float64] | None = None

    def pose(self, q: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(p_base_tip (3,) [m], R_base_tip (3, 3))`` at joint positions ``q``."""
        T, _ = self.chain.pose_and_jacobian(np.asarray(q, dtype=float))
        return T[:3, 3], T[:3, :3]

    def errors(
        self, q: ArrayLike, p_base_tip_m: ArrayLike, R_base_tip: ArrayLike | None = None
    ) -> tuple[float, float]:
        """Position error [m] and orientation error [rad] (0 without a target ``R``) at ``q``."""
        p, R = self.pose(q)
        dp = float(np.linalg.norm(p - np.asarray(p_base_tip_m, dtype=float)))
        if R_base_tip is None:
            return dp, 0.0
        # |R - R_t|_F = sqrt(8) sin(theta / 2): exact also for tiny angles, unlike arccos.
        chord = float(np.linalg.norm(R - np.asarray(R_base_tip, dtype=float))) / math.sqrt(8.0)
        return dp, 2.0 * math.asin(min(1.0, chord))

    def solve(
        self,
        p_base_tip_m: ArrayLike,
        R_base_tip: ArrayLike | None = None,
        *,
        q_start: ArrayLike | None = None,
    ) -> NDArray[np.float64] | None:
        """Joint positions [rad or m] in ``chain.joint_names`` order putting the tip at
        ``p_base_tip_m`` [m] with orientation ``R_base_tip`` (None: any orientation), within
        the joint limits; None if no start reaches it within the tolerances. ``q_start``, if
        given, is tried first (the solution is then the one its descent finds: near it).
        """
        p_t = np.asarray(p_base_tip_m, dtype=float)
        R_t = None if R_base_tip is None else np.asarray(R_base_tip, dtype=float)
        if p_t.shape != (3,) or not np.isfinite(p_t).all():
            raise ParameterError(f"target position {p_t.tolist()}: need three finite numbers [m]")
        if R_t is not None and not (
            R_t.shape == (3, 3)
            and np.isfinite(R_t).all()
            and np.allclose(R_t @ R_t.T, np.eye(3), atol=1e-6)
            and np.linalg.det(R_t) > 0
        ):
            raise ParameterError("target orientation: need a 3 x 3 rotation matrix")
        w = ORIENTATION_WEIGHT_M

        last: list[tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]] = []

        def kinematics(q: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
            if not last or not np.array_equal(last[0][0], q):  # the solver asks for r, then J
                last[:] = [(q.copy(), *self.chain.pose_and_jacobian(q))]
            return last[0][1], last[0][2]

        def residual(q: NDArray[np.float64]) -> NDArray[np.float64]:
            T, _ = kinematics(q)
            if R_t is None:
                return T[:3, 3] - p_t
            return np.concatenate([T[:3, 3] - p_t, w * (T[:3, :3] - R_t).ravel()])

        def jacobian(q: NDArray[np.float64]) -> NDArray[np.float64]:
            T, J = kinematics(q)
            if R_t is None:
                return J[:3]
            # d R / d q_i = [w_i]x R: the cross product of w_i with each column of R.
            dR = np.cross(J[3:].T[:, None, :], T[:3, :3].T[None, :, :])  # (n, column, row)
            return np.vstack([J[:3], w * np.swapaxes(dR, 1, 2).reshape(len(q), 9).T])

        if not self.chain.joint_names:  # nothing moves: the pose is what it is
            q = np.zeros(0)
            dp, angle = self.errors(q, p_t, R_t)
            return q if dp < self.position_tol_m and angle < self.angle_tol_rad else None
        starts = ([] if self._last is None else [self._last]) + self._starts
        if q_start is not None:
            starts.insert(0, np.asarray(q_start, dtype=float))
        for q0 in starts:
            fit = least_squares(
                residual,
                np.clip(q0, self._lower, self._upper),
                jac=jacobian,
                bounds=(self._lower, self._upper),
                method="trf",
                xtol=1e-12,
                ftol=1e-8,
                gtol=1e-10,
                max_nfev=40,
            )
            q = np.clip(fit.x, self._lower, self._upper)
            dp, angle = self.errors(q, p_t, R_t)
            if dp < self.position_tol_m and angle < self.angle_tol_rad:
                self._last = q
                return q
        return None
