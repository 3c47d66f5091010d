"""Orientation encodings, the base tilt and the gravity geometry (docs/conventions.md)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.errors import OrientationError, ParameterError
from ftcomp.frames import (
    ENCODING_COLUMNS,
    R_world_base_from_tilt,
    cross3,
    encode_orientation,
    gravity_in_base,
    gravity_in_sensor,
    rotation_from_encoding,
    tilt_from_gravity_in_base,
)

ENCODINGS = tuple(ENCODING_COLUMNS)


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_every_encoding_round_trips_through_rotation(encoding, rng) -> None:
    rotations = Rotation.random(50, rng=rng)
    values = encode_orientation(rotations, encoding)
    back = rotation_from_encoding(encoding, values)
    np.testing.assert_allclose(back.as_matrix(), rotations.as_matrix(), atol=1e-12)


@pytest.mark.parametrize("first", ENCODINGS)
@pytest.mark.parametrize("second", ENCODINGS)
def test_all_encodings_agree_on_the_same_orientation(first, second, rng) -> None:
    rotations = Rotation.random(20, rng=rng)
    via_first = rotation_from_encoding(first, encode_orientation(rotations, first))
    via_second = rotation_from_encoding(second, encode_orientation(via_first, second))
    np.testing.assert_allclose(via_second.as_matrix(), rotations.as_matrix(), atol=1e-12)


def test_paper_angles_are_intrinsic_z_y_x() -> None:
    alpha, beta, gamma = np.radians([64.447, -0.721, -160.420])

    def rz(a):
        return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])

    def ry(b):
        return np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])

    def rx(c):
        return np.array([[1, 0, 0], [0, np.cos(c), -np.sin(c)], [0, np.sin(c), np.cos(c)]])

    R = rotation_from_encoding("paper_euler", [64.447, -0.721, -160.420]).as_matrix()
    np.testing.assert_allclose(R, rz(alpha) @ ry(beta) @ rx(gamma), atol=1e-12)


def test_tilt_is_rx_then_ry_and_gravity_in_base_matches_eq_3() -> None:
    U, V, G = np.radians(-3.0), np.radians(5.0), 4.2
    c, s = np.cos, np.sin
    Rx = np.array([[1, 0, 0], [0, c(U), -s(U)], [0, s(U), c(U)]])
    Ry = np.array([[c(V), 0, s(V)], [0, 1, 0], [-s(V), 0, c(V)]])
    np.testing.assert_allclose(R_world_base_from_tilt(U, V), Rx @ Ry, atol=1e-12)
    expected = [G * c(U) * s(V), -G * s(U), -G * c(U) * c(V)]
    np.testing.assert_allclose(gravity_in_base(G, U, V), expected, atol=1e-12)


def test_tilt_from_gravity_inverts_gravity_in_base(rng) -> None:
    for _ in range(100):
        G = rng.uniform(0.1, 100)
        U, V = rng.uniform(-1.4, 1.4, size=2)
        np.testing.assert_allclose(
            tilt_from_gravity_in_base(gravity_in_base(G, U, V)), (G, U, V), atol=1e-9
        )


def test_gravity_in_sensor_is_the_transpose_rotation_for_one_and_many(rng) -> None:
    R = Rotation.random(7, rng=rng).as_matrix()
    g = np.array([0.1, -0.2, -3.0])
    many = gravity_in_sensor(g, R)
    np.testing.assert_allclose(many, np.einsum("nji,j->ni", R, g), atol=1e-12)
    np.testing.assert_allclose(gravity_in_sensor(g, R[0]), R[0].T @ g, atol=1e-12)


def test_zero_norm_quaternion_is_rejected() -> None:
    with pytest.raises(OrientationError, match="zero-norm quaternion"):
        rotation_from_encoding("quaternion", [0, 0, 0, 0])


def test_wrong_width_and_unknown_encoding_are_rejected() -> None:
    with pytest.raises(OrientationError, match=r"shape \(3,\)"):
        rotation_from_encoding("rotvec", [0, 0, 0, 1])
    with pytest.raises(ParameterError, match="unknown orientation encoding 'euler'"):
        rotation_from_encoding("euler", [0, 0, 0])  # type: ignore[arg-type]


def test_zero_gravity_has_no_tilt() -> None:
    with pytest.raises(ParameterError, match="zero vector"):
        tilt_from_gravity_in_base([0, 0, 0])


def test_quat_from_matrix_is_scipys_quaternion_sign_included() -> None:
    from ftcomp.frames import quat_from_matrix

    # Random rotations and the four branches' edge cases (identity, half turns about each axis).
    matrices = [*Rotation.random(2000, rng=5).as_matrix(), np.eye(3)]
    matrices += [np.diag(d) for d in ([1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0])]
    for R in matrices:
        np.testing.assert_allclose(
            quat_from_matrix(R), Rotation.from_matrix(R).as_quat(), rtol=0, atol=1e-12
        )


def test_rotvec_conversions_on_floats_are_scipys() -> None:
    from ftcomp.frames import matrix_from_rotvec, rotvec_from_matrix

    rng = np.random.default_rng(6)
    # Random rotations (angles up to pi) and tiny ones (the series branch).
    rotvecs = [*Rotation.random(2000, rng=rng).as_rotvec(), *(rng.normal(size=(50, 3)) * 1e-8)]
    for r in rotvecs:
        R = Rotation.from_rotvec(r).as_matrix()
        np.testing.assert_allclose(matrix_from_rotvec(r), R, rtol=0, atol=1e-14)
        expected = Rotation.from_matrix(R).as_rotvec()
        np.testing.assert_allclose(rotvec_from_matrix(R), expected, rtol=0, atol=1e-14)


def test_cross3_is_numpys_cross_of_one_pair() -> None:
    rng = np.random.default_rng(3)
    for a, b in rng.normal(size=(100, 2, 3)):
        np.testing.assert_allclose(cross3(a, b), np.cross(a, b), rtol=0, atol=1e-15)
