"""Closed-form inverse kinematics of a UR-shaped arm: up to eight joint configurations for a
flange pose, as a UR controller's solver finds them.

A UR arm (UR3e, UR5e, UR10e, ...) is six revolute joints in standard Denavit-Hartenberg form
with ``alpha = (pi/2, 0, 0, pi/2, -pi/2, 0)``, ``a = (0, a2, a3, 0, 0, 0)`` and
``d = (d1, 0, 0, d4, d5, d6)``: joints 2-4 turn about one axis, so the wrist's position fixes
joint 1 (two ways: shoulder left or right), the tool's orientation then fixes joint 5 (wrist
up or down) and joint 6, and joints 2 and 3 are a planar two-link arm (elbow up or down),
joint 4 the rest of their common rotation. The derivation, in the frames of
:class:`~ftcomp.sim.arm.DHArmSpec` (``T_{i-1,i} = Rz(q) Tz(d) Tx(a) Rx(alpha)``):

- the wrist centre ``p5 = p6 - d6 z6`` lies on the plane ``d4`` from the base's ``z`` along
  frame 1's ``z`` axis ``(sin q1, -cos q1, 0)``: ``p5x sin q1 - p5y cos q1 = d4``;
- the third row of ``R_16`` is ``(sin q5 cos q6, -sin q5 sin q6, cos q5)``;
- with ``q1, q5, q6`` known, ``T_14 = T_01^-1 T_06 T_56^-1 T_45^-1``; frame 3's origin, ``d4``
  back along ``T_14``'s ``y`` axis, is the planar arm's ``a2 (cos q2, sin q2) + a3 (cos q23,
  sin q23)``.

At a wrist singularity (``sin q5 = 0``) joint 6 is free; the caller's ``q6`` is taken. Each
branch is returned with its angles in ``(-pi, pi]``; turning a joint by whole turns within its
range is the caller's choice (the twin's controller: nearest ``qnear``).
"""

from __future__ import annotations

import math
from typing import TypeGuard

import numpy as np
from numpy.typing import NDArray

from ftcomp.sim.arm import DHArmSpec

__all__ = ["is_ur_shaped", "ur_inverse_kinematics"]

_ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)
#: Below this, ``|sin q5|`` is taken for zero (the wrist's singularity) [-].
_SINGULAR = 1e-10
#: A cosine this far beyond 1, or the wrist this far inside joint 1's cylinder [m], is rounding
#: (a pose on the edge of a branch, such as the arm stretched straight up), not out of reach.
_ROUNDING = 1e-12


def is_ur_shaped(arm: object) -> TypeGuard[DHArmSpec]:
    """Whether ``arm`` has a UR arm's kinematic structure (module docstring)."""
    if not isinstance(arm, DHArmSpec) or arm.convention != "standard" or arm.n_joints != 6:
        return False
    a, d = arm.dh_a_m, arm.dh_d_m
    return (
        bool(np.allclose(arm.dh_alpha_rad, _ALPHA, rtol=0.0, atol=1e-12))
        and a[0] == a[3] == a[4] == a[5] == 0.0
        and d[1] == d[2] == 0.0
        and a[1] != 0.0
        and a[2] != 0.0
        and not arm.has_flange_row
    )


def _wrap(angle: float) -> float:
    """``angle`` [rad] in ``(-pi, pi]``."""
    wrapped = math.remainder(angle, 2.0 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped


def ur_inverse_kinematics(
    arm: DHArmSpec,
    p_base_flange: NDArray[np.float64],
    R_base_flange: NDArray[np.float64],
    q6_if_singular: float = 0.0,
) -> list[NDArray[np.float64]]:
    """Every joint configuration [rad] (each angle in ``(-pi, pi]``) placing the flange at a
    base-frame pose, up to eight; empty when the pose is out of reach.

    ``arm`` must be UR-shaped (:func:`is_ur_shaped`). The answers are exact up to rounding;
    a caller that needs a guarantee checks them by forward kinematics.
    """
    d4, d6 = float(arm.dh_d_m[3]), float(arm.dh_d_m[5])
    a2, a3 = float(arm.dh_a_m[1]), float(arm.dh_a_m[2])
    p = np.asarray(p_base_flange, dtype=float)
    R = np.asarray(R_base_flange, dtype=float)
    wrist = p - d6 * R[:, 2]
    r = math.hypot(wrist[0], wrist[1])
    if r < abs(d4) - _ROUNDING or r == 0.0:
        return []
    psi = math.atan2(wrist[1], wrist[0])
    lean = math.asin(max(-1.0, min(1.0, d4 / r)))
    T06 = _pose(p, R)
    solutions: list[NDArray[np.float64]] = []
    for q1 in (psi + lean, psi + math.pi - lean):
        s1, c1 = math.sin(q1), math.cos(q1)
        # R_16's third row is R_06's columns dotted with frame 1's z axis (s1, -c1, 0); its
        # angle (not acos of its last entry, which loses half the digits near the singularity)
        row = R[0, :] * s1 - R[1, :] * c1
        s5 = math.hypot(row[0], row[1])  # |sin q5|
        base5 = math.atan2(s5, row[2])
        T16 = np.linalg.inv(arm.row_transform(0, q1)) @ T06
        for side in (1.0, -1.0):
            q5 = side * base5
            singular = s5 < _SINGULAR
            q6 = q6_if_singular if singular else math.atan2(-side * row[1], side * row[0])
            T14 = (
                T16
                @ np.linalg.inv(arm.row_transform(5, q6))
                @ np.linalg.inv(arm.row_transform(4, q5))
            )
            x, y = T14[:2, 3] - d4 * T14[:2, 1]
            c3 = (x * x + y * y - a2 * a2 - a3 * a3) / (2.0 * a2 * a3)
            if abs(c3) > 1.0 + _ROUNDING:
                continue
            base3 = math.acos(max(-1.0, min(1.0, c3)))
            for q3 in (base3, -base3):
                q2 = math.atan2(y, x) - math.atan2(a3 * math.sin(q3), a2 + a3 * math.cos(q3))
                T34 = np.linalg.inv(arm.row_transform(1, q2) @ arm.row_transform(2, q3)) @ T14
                q4 = math.atan2(T34[1, 0], T34[0, 0])
                solutions.append(np.array([_wrap(q) for q in (q1, q2, q3, q4, q5, q6)]))
    return solutions


def _pose(p: NDArray[np.float64], R: NDArray[np.float64]) -> NDArray[np.float64]:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T
