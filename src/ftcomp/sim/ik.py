"""Inverse kinematics on MuJoCo Jacobians (``mj_jacSite``) by damped least squares.

Two uses: :func:`dls_joint_velocity` turns a commanded twist into joint velocities every control
cycle (differential IK), and :func:`solve_pose` iterates it to reach a pose (Cartesian moves).
All quantities here are in MuJoCo's *world* frame; :class:`ftcomp.sim.cell.SimCell` converts from
the robot base frame.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np
from numpy.typing import NDArray

__all__ = ["DifferentialIK", "dls_joint_velocity", "pose_error_world", "solve_pose"]


def dls_joint_velocity(
    J: NDArray[np.float64], twist: NDArray[np.float64], damping: float
) -> NDArray[np.float64]:
    """Damped least squares: ``dq = J.T @ inv(J @ J.T + damping^2 I) @ twist``.

    Args:
        J: the 6 x n Jacobian of the site ``[linear; angular]``, world frame.
        twist: ``[v (m/s), w (rad/s)]``, shape (6,), world frame.
        damping: lambda [same units as J's entries]; trades accuracy for bounded speed near
            singularities.

    Returns:
        Joint velocities [rad/s], shape (n,).
    """
    A = J @ J.T
    A.flat[:: A.shape[0] + 1] += damping * damping
    # mju_cholFactor/mju_cholSolve: the same answer as np.linalg.solve at half the overhead,
    # which matters in a 1 kHz Python loop.
    mujoco.mju_cholFactor(A, 0.0)
    x = np.empty(A.shape[0])
    mujoco.mju_cholSolve(x, A, np.ascontiguousarray(twist, dtype=float))
    return np.asarray(J.T @ x, dtype=float)


class DifferentialIK:
    """Damped-least-squares differential IK of one site, with preallocated buffers.

    For the 1 kHz loop: every call is a handful of MuJoCo C functions, no numpy temporaries.
    The site's Jacobian is taken over all ``model.nv`` degrees of freedom; those outside the
    site's kinematic chain (a free load, the sponge) have zero columns, so they get zero
    velocity and the result is the arm's ``dq`` padded with zeros.

    With ``refresh_rad > 0`` the Jacobian and its factorisation are kept while the chain's joints
    (``qpos[chain]``) stay within ``refresh_rad`` of where they were computed: over 1 mrad the
    Jacobian changes by about 0.1 %, far below the servo's tracking error, and the 1 kHz loop
    saves four of its six MuJoCo calls on most cycles.

    Args:
        model: the MuJoCo model.
        site_id: the site whose origin and frame the twist moves.
        damping: lambda [m or rad], as in :func:`dls_joint_velocity`.
        refresh_rad: recompute once a chain joint has moved this far [rad]; 0: every call.
        chain: the ``qpos`` slice of the joints that move the site (with ``refresh_rad``).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        site_id: int,
        damping: float,
        *,
        refresh_rad: float = 0.0,
        chain: slice = slice(0, 0),
    ) -> None:
        self._refresh = refresh_rad
        self._chain = chain
        self._q_factored: NDArray[np.float64] | None = None
        self._model = model
        self._site = site_id
        self._jac = np.zeros((6, model.nv))
        self._jacp = self._jac[:3]
        self._jacr = self._jac[3:]
        self._A = np.zeros((6, 6))
        self._damping_I = np.eye(6) * damping * damping
        self._x = np.zeros(6)
        self._qd = np.zeros(model.nv)

    def joint_velocity(
        self, data: mujoco.MjData, twist_world: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """``dq`` [rad/s or m/s] for every degree of freedom, shape (nv,) (an internal buffer:
        copy it to keep it), realising ``twist_world`` ``[v, w]`` of the site at ``data``'s state.
        """
        q = data.qpos[self._chain]
        fresh = self._q_factored is not None and (
            float(np.abs(q - self._q_factored).max()) < self._refresh
        )
        if not fresh:
            mujoco.mj_jacSite(self._model, data, self._jacp, self._jacr, self._site)
            mujoco.mju_mulMatMatT(self._A, self._jac, self._jac)
            mujoco.mju_addTo(self._A.reshape(-1), self._damping_I.reshape(-1))
            mujoco.mju_cholFactor(self._A, 0.0)
            self._q_factored = q.copy() if self._refresh > 0.0 else None
        mujoco.mju_cholSolve(self._x, self._A, twist_world)
        mujoco.mju_mulMatTVec(self._qd, self._jac, self._x)
        return self._qd


def pose_error_world(
    p_target: NDArray[np.float64],
    R_target: NDArray[np.float64],
    p_now: NDArray[np.float64],
    R_now: NDArray[np.float64],
) -> NDArray[np.float64]:
    """``[p_target - p_now, rotvec(R_target @ R_now.T)]``, shape (6,), world frame."""
    # MuJoCo's quaternion log instead of scipy's Rotation: the same rotation vector (to 1e-15
    # below pi) at a thirtieth of the cost, in an iteration that runs thousands of times a move.
    quat, rot = np.empty(4), np.empty(3)
    mujoco.mju_mat2Quat(quat, (R_target @ R_now.T).ravel())
    mujoco.mju_quat2Vel(rot, quat, 1.0)
    return np.concatenate([p_target - p_now, rot])


def solve_pose(
    model: mujoco.MjModel,
    scratch: mujoco.MjData,
    site_id: int,
    qpos_adr: NDArray[np.intp],
    dof_adr: NDArray[np.intp],
    p_target_world: NDArray[np.float64],
    R_target_world: NDArray[np.float64],
    seeds: Sequence[NDArray[np.float64]],
    lower: NDArray[np.float64],
    upper: NDArray[np.float64],
    *,
    tol: float = 1e-9,
    max_iterations: int = 200,
) -> NDArray[np.float64] | None:
    """Joint positions placing the site at a world pose, or None if no seed converges.

    Iterates damped least-squares steps from each seed in turn (kinematics only, on
    ``scratch``), clamped to ``[lower, upper]``; returns the first solution whose position error
    is below ``tol`` [m] and orientation error below ``tol`` [rad].
    """
    jacp = np.zeros((3, model.nv))
    jacr = np.zeros((3, model.nv))
    J = np.zeros((6, len(dof_adr)))
    for seed in seeds:
        q = np.clip(np.array(seed, dtype=float), lower, upper)
        for _ in range(max_iterations):
            scratch.qpos[qpos_adr] = q
            mujoco.mj_kinematics(model, scratch)
            mujoco.mj_comPos(model, scratch)
            p_now = scratch.site_xpos[site_id]
            R_now = scratch.site_xmat[site_id].reshape(3, 3)
            err = pose_error_world(p_target_world, R_target_world, p_now, R_now)
            if np.max(np.abs(err)) < tol:
                return q
            mujoco.mj_jacSite(model, scratch, jacp, jacr, site_id)
            J[:3] = jacp[:, dof_adr]
            J[3:] = jacr[:, dof_adr]
            dq = dls_joint_velocity(J, err, 1e-4)
            step = float(np.max(np.abs(dq)))
            if step > 0.3:
                dq *= 0.3 / step
            q = np.clip(q + dq, lower, upper)
    return None
