"""Frames, orientation encodings and the gravity model's geometry.

Conventions (the single source is ``docs/conventions.md``):

- ``R_a_b`` maps vectors expressed in frame ``b`` into frame ``a``.
- The world frame has z up (against gravity). The robot base is tilted from the world by
  ``R_world_base = Rx(U) @ Ry(V)`` (paper Eq. 1).
- The sensor frame's orientation in the base frame, ``R_base_sensor``, comes from one of three
  encodings: a quaternion ``qx,qy,qz,qw``, a rotation vector ``rx,ry,rz`` [rad] (as UR
  controllers report poses) or the paper's angles ``alpha_deg,beta_deg,gamma_deg`` with
  ``R = Rz(alpha) @ Ry(beta) @ Rx(gamma)`` (intrinsic Z-Y'-X'', paper Eq. 2).
- Gravity acting on the tool, in the sensor frame:
  ``R_base_sensor.T @ R_world_base.T @ [0, 0, -G]`` (paper Eq. 3 with the transpose the data
  demands).

Every orientation conversion goes through :class:`scipy.spatial.transform.Rotation`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Final, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.errors import OrientationError, ParameterError

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation

__all__ = [
    "ENCODING_COLUMNS",
    "OrientationEncoding",
    "R_base_sensor_from",
    "R_world_base_from_tilt",
    "cross3",
    "encode_orientation",
    "gravity_in_base",
    "gravity_in_sensor",
    "matrix_from_rotvec",
    "quat_from_matrix",
    "rotation_from_encoding",
    "rotvec_from_matrix",
    "tilt_from_gravity_in_base",
]

OrientationEncoding = Literal["quaternion", "rotvec", "paper_euler"]

#: Column names of each orientation encoding, in the order the values are given.
ENCODING_COLUMNS: Final[dict[OrientationEncoding, tuple[str, ...]]] = {
    "quaternion": ("qx", "qy", "qz", "qw"),
    "rotvec": ("rx", "ry", "rz"),
    "paper_euler": ("alpha_deg", "beta_deg", "gamma_deg"),
}

#: scipy's sequence for the paper's angles: upper case is intrinsic, Rz(a) @ Ry(b) @ Rx(c).
_PAPER_EULER_SEQ: Final = "ZYX"
#: scipy's sequence for the base tilt, intrinsic: Rx(U) @ Ry(V).
_TILT_SEQ: Final = "XY"


def _rotation() -> type[Rotation]:
    """scipy's :class:`~scipy.spatial.transform.Rotation`, imported on first use: importing
    scipy.spatial takes most of a second, which every command's ``--help`` paid through this
    module."""
    from scipy.spatial.transform import Rotation

    return Rotation


def rotation_from_encoding(encoding: OrientationEncoding, values: ArrayLike) -> Rotation:
    """Build ``R_base_sensor`` from one orientation encoding.

    Args:
        encoding: which encoding ``values`` holds (see :data:`ENCODING_COLUMNS`).
        values: shape (k,) or (N, k), columns in the order of ``ENCODING_COLUMNS[encoding]``;
            quaternions scalar-last ``(qx, qy, qz, qw)``, rotation vectors in rad, paper angles
            in degrees.

    Returns:
        The rotation(s) ``R_base_sensor``.

    Raises:
        OrientationError: a zero-norm or non-finite quaternion, or values of the wrong width.
    """
    if encoding not in ENCODING_COLUMNS:
        raise ParameterError(
            f"unknown orientation encoding {encoding!r}; valid: {', '.join(ENCODING_COLUMNS)}"
        )
    arr = np.asarray(values, dtype=float)
    width = len(ENCODING_COLUMNS[encoding])
    if arr.shape[-1:] != (width,) or arr.ndim > 2:
        raise OrientationError(
            f"{encoding} orientation needs shape ({width},) or (N, {width}), got {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise OrientationError(f"{encoding} orientation contains NaN or infinity")
    if encoding == "quaternion":
        norms = np.linalg.norm(np.atleast_2d(arr), axis=1)
        if np.any(norms < 1e-12):
            raise OrientationError("zero-norm quaternion (qx, qy, qz, qw) has no orientation")
        return _rotation().from_quat(arr)
    if encoding == "rotvec":
        return _rotation().from_rotvec(arr)
    return _rotation().from_euler(_PAPER_EULER_SEQ, arr, degrees=True)


def R_base_sensor_from(encoding: OrientationEncoding, values: ArrayLike) -> NDArray[np.float64]:
    """The rotation matrix ``R_base_sensor`` from a quaternion, rotation vector or paper angles.

    The matrix form of :func:`rotation_from_encoding`, ready for
    :meth:`ftcomp.GravityCompensator.compensate` and :meth:`ftcomp.GravityModel.predict`.

    Args:
        encoding: ``"quaternion"`` (``qx, qy, qz, qw``, scalar last, normalised),
            ``"rotvec"`` (axis times angle [rad], as UR controllers report a TCP pose) or
            ``"paper_euler"`` (``alpha, beta, gamma`` [deg], ``Rz(alpha) Ry(beta) Rx(gamma)``).
        values: shape (k,) for one orientation or (N, k) for N of them.

    Returns:
        Shape (3, 3), or (N, 3, 3) for (N, k) values: maps sensor-frame vectors into the base.

    Raises:
        OrientationError: a zero-norm or non-finite quaternion, or values of the wrong width.
    """
    return np.asarray(rotation_from_encoding(encoding, values).as_matrix(), dtype=float)


def encode_orientation(rotation: Rotation, encoding: OrientationEncoding) -> NDArray[np.float64]:
    """The inverse of :func:`rotation_from_encoding`: values in ``ENCODING_COLUMNS`` order.

    Quaternions come out scalar-last with ``qw >= 0``; paper angles in degrees.
    """
    if encoding == "quaternion":
        return np.asarray(rotation.as_quat(canonical=True), dtype=float)
    if encoding == "rotvec":
        return np.asarray(rotation.as_rotvec(), dtype=float)
    if encoding == "paper_euler":
        return np.asarray(rotation.as_euler(_PAPER_EULER_SEQ, degrees=True), dtype=float)
    raise ParameterError(
        f"unknown orientation encoding {encoding!r}; valid: {', '.join(ENCODING_COLUMNS)}"
    )


def R_world_base_from_tilt(U_rad: float, V_rad: float) -> NDArray[np.float64]:
    """The base's mounting tilt ``R_world_base = Rx(U) @ Ry(V)`` (paper Eq. 1), shape (3, 3)."""
    return np.asarray(_rotation().from_euler(_TILT_SEQ, [U_rad, V_rad]).as_matrix(), dtype=float)


def gravity_in_base(weight_N: float, U_rad: float, V_rad: float) -> NDArray[np.float64]:
    """Gravity on a body of weight ``weight_N`` [N], in the tilted base frame [N], shape (3,).

    Equals ``R_world_base.T @ [0, 0, -G] = [G cosU sinV, -G sinU, -G cosU cosV]`` (paper Eq. 3, 5).
    """
    return R_world_base_from_tilt(U_rad, V_rad).T @ np.array([0.0, 0.0, -weight_N])


def tilt_from_gravity_in_base(gravity_base: ArrayLike) -> tuple[float, float, float]:
    """Invert :func:`gravity_in_base`: ``(G [N], U [rad], V [rad])`` (paper Eq. 10-11).

    Uses ``V = atan2(a_x, -a_z)``, which equals the paper's ``arctan(-a_x / a_z)`` whenever the
    base is tilted by less than 90 degrees, and stays right beyond.
    """
    a = np.asarray(gravity_base, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ParameterError(f"gravity_base must be 3 finite numbers, got {a!r}")
    weight = float(np.linalg.norm(a))
    if weight == 0.0:
        raise ParameterError("gravity_base is the zero vector: no weight, no tilt")
    U = float(np.arcsin(np.clip(-a[1] / weight, -1.0, 1.0)))
    V = float(np.arctan2(a[0], -a[2]))
    return weight, U, V


def gravity_in_sensor(gravity_base: ArrayLike, R_base_sensor: ArrayLike) -> NDArray[np.float64]:
    """Express a base-frame gravity vector in the sensor frame: ``R_base_sensor.T @ g``.

    Args:
        gravity_base: shape (3,), [N] in the base frame.
        R_base_sensor: shape (3, 3) or (N, 3, 3).

    Returns:
        Shape (3,) or (N, 3), [N] in the sensor frame.
    """
    g = np.asarray(gravity_base, dtype=float)
    R = np.asarray(R_base_sensor, dtype=float)
    # g @ R == R.T @ g, and broadcasts over a stack of rotations.
    return np.asarray(g @ R, dtype=float)


def quat_from_matrix(R: NDArray[np.float64]) -> list[float]:
    """One rotation matrix (3, 3) as a unit quaternion ``[x, y, z, w]``, on floats.

    What ``Rotation.from_matrix(R).as_quat()`` gives for a proper rotation (the same branch by
    the largest of the diagonal and the trace, so the same sign), at a small fraction of its
    cost for a single matrix (scipy's is about 0.1 ms): for per-cycle logging.
    """
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = R.tolist()
    trace = m00 + m11 + m22
    largest = max(m00, m11, m22, trace)
    if largest == m00:  # ties go to the first, as numpy's argmax in scipy's
        q = [1.0 - trace + 2.0 * m00, m10 + m01, m20 + m02, m21 - m12]
    elif largest == m11:
        q = [m10 + m01, 1.0 - trace + 2.0 * m11, m21 + m12, m02 - m20]
    elif largest == m22:
        q = [m20 + m02, m21 + m12, 1.0 - trace + 2.0 * m22, m10 - m01]
    else:
        q = [m21 - m12, m02 - m20, m10 - m01, 1.0 + trace]
    norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return [q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm]


def matrix_from_rotvec(rotvec: ArrayLike) -> NDArray[np.float64]:
    """One rotation vector [rad] (3,) as a rotation matrix (3, 3), by Rodrigues' formula on
    floats: ``Rotation.from_rotvec(r).as_matrix()`` to rounding, without scipy's per-call cost
    (for a robot driver's per-cycle pose)."""
    x, y, z = (float(v) for v in np.asarray(rotvec, dtype=float).reshape(3))
    theta2 = x * x + y * y + z * z
    if theta2 < 1e-12:  # sin(t)/t and (1 - cos(t))/t^2 by their series, exact to rounding
        a, b = 1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0
    else:
        theta = math.sqrt(theta2)
        a, b = math.sin(theta) / theta, (1.0 - math.cos(theta)) / theta2
    return np.array(
        [
            [1.0 - b * (y * y + z * z), b * x * y - a * z, b * x * z + a * y],
            [b * x * y + a * z, 1.0 - b * (x * x + z * z), b * y * z - a * x],
            [b * x * z - a * y, b * y * z + a * x, 1.0 - b * (x * x + y * y)],
        ]
    )


def rotvec_from_matrix(R: NDArray[np.float64]) -> list[float]:
    """One rotation matrix (3, 3) as a rotation vector [rad], angle in [0, pi]: what
    ``Rotation.from_matrix(R).as_rotvec()`` gives, through :func:`quat_from_matrix`."""
    qx, qy, qz, qw = quat_from_matrix(R)
    if qw < 0.0:  # the same rotation with the angle in [0, pi]
        qx, qy, qz, qw = -qx, -qy, -qz, -qw
    s = math.sqrt(qx * qx + qy * qy + qz * qz)
    angle = 2.0 * math.atan2(s, qw)
    scale = angle / s if s > 1e-12 else 2.0 / qw  # small angles: 2 / cos(angle / 2) -> 2
    return [qx * scale, qy * scale, qz * scale]


def cross3(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a x b`` of two 3-vectors, shape (3,): :func:`numpy.cross` without its axis handling,
    about 20x faster on one pair (the live loop moves a lever every cycle: a twist from the
    sensor to the TCP, a torque from the flange to the TCP; ``bench/bench_cycle.py``)."""
    a0, a1, a2 = a.tolist()
    b0, b1, b2 = b.tolist()
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
