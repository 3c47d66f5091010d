"""``ftcomp.R_base_sensor_from``: the same matrix from each encoding of one orientation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftcomp
from ftcomp.errors import OrientationError
from ftcomp.frames import encode_orientation


@pytest.mark.parametrize("encoding", ["quaternion", "rotvec", "paper_euler"])
def test_every_encoding_gives_the_same_rotation_matrix(
    encoding: str, rng: np.random.Generator
) -> None:
    rotations = Rotation.random(5, rng=rng)
    values = encode_orientation(rotations, encoding)  # type: ignore[arg-type]
    R = ftcomp.R_base_sensor_from(encoding, values)  # type: ignore[arg-type]
    assert R.shape == (5, 3, 3)
    np.testing.assert_allclose(R, rotations.as_matrix(), atol=1e-12)  # exact algebra
    one = ftcomp.R_base_sensor_from(encoding, values[0])  # type: ignore[arg-type]
    np.testing.assert_allclose(one, rotations[0].as_matrix(), atol=1e-12)


def test_the_quaternion_is_scalar_last() -> None:
    """(qx, qy, qz, qw) = (1, 0, 0, 0): half a turn about x, the tool hanging down."""
    R = ftcomp.R_base_sensor_from("quaternion", [1.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(R, np.diag([1.0, -1.0, -1.0]), atol=1e-12)


def test_a_zero_quaternion_is_an_error() -> None:
    with pytest.raises(OrientationError, match="zero-norm"):
        ftcomp.R_base_sensor_from("quaternion", [0.0, 0.0, 0.0, 0.0])
