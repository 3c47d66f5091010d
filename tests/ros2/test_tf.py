"""The transform tree of a recording: composition, interpolation, errors that name frames."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.errors import InputFileError
from ftcomp.ros2.tf import TransformRecord, TransformTree

S = 1_000_000_000


def _rec(t: int, parent: str, child: str, p, R: Rotation, static: bool = False):
    return TransformRecord(t, parent, child, tuple(p), tuple(R.as_quat()), static)


@pytest.fixture
def tree() -> TransformTree:
    """world -> base (static tilt) -> flange (turning about z, moving along x) -> sensor."""
    mount = Rotation.from_euler("y", 90, degrees=True)
    records = [
        _rec(0, "world", "base", (0, 0, 0.1), Rotation.from_euler("x", 3, degrees=True), True),
        _rec(0, "/flange", "sensor", (0, 0, 0.05), mount, True),
        _rec(0, "base", "camera", (1, 0, 1), Rotation.identity(), True),
    ]
    for k in range(11):
        turn = Rotation.from_euler("z", 9 * k, degrees=True)
        records.append(_rec(k * S, "base", "flange", (0.1 * k, 0, 0.5), turn))
    return TransformTree(reversed(records), "test.bag")


def test_lookup_composes_the_chain_and_interpolates_between_stamps(tree) -> None:
    t = np.array([0, 5 * S + S // 2, 10 * S])
    p, R, valid = tree.lookup("base", "sensor", t)
    assert valid.all()
    mount = Rotation.from_euler("y", 90, degrees=True)
    for k, tk in enumerate(t):
        turn = Rotation.from_euler("z", 9 * tk / S, degrees=True)  # slerp about one axis
        expected_R = turn * mount
        expected_p = np.array([0.1 * tk / S, 0, 0.5]) + turn.apply([0, 0, 0.05])
        np.testing.assert_allclose(p[k], expected_p, atol=1e-12)
        np.testing.assert_allclose(R[k].as_matrix(), expected_R.as_matrix(), atol=1e-12)
    assert tree.chain("base", "sensor") == ["base", "flange", "sensor"]
    assert tree.chain("camera", "sensor") == ["camera", "base", "flange", "sensor"]


def test_the_reverse_lookup_is_the_inverse(tree, rng) -> None:
    t = rng.integers(0, 10 * S, 20)
    p, R, _ = tree.lookup("world", "sensor", t)
    p_inv, R_inv, _ = tree.lookup("sensor", "world", t)
    np.testing.assert_allclose((R * R_inv).magnitude(), 0.0, atol=1e-12)
    np.testing.assert_allclose(R.apply(p_inv) + p, 0.0, atol=1e-12)


def test_stamps_outside_a_dynamic_transform_are_not_valid(tree) -> None:
    _, _, valid = tree.lookup("base", "sensor", np.array([-1, 0, 10 * S, 10 * S + 1]))
    assert valid.tolist() == [False, True, True, False]
    _, _, static_only = tree.lookup("world", "camera", np.array([-(10**12)]))
    assert static_only.all()
    assert tree.is_static("world", "camera") and not tree.is_static("base", "sensor")


def test_an_unknown_frame_is_named_with_the_frames_there_are(tree) -> None:
    with pytest.raises(InputFileError, match=r"frame 'tool0' is not in the tf tree; frames: base"):
        tree.lookup("base", "tool0", np.zeros(1, dtype=np.int64))


def test_unconnected_frames_and_two_parents_are_errors() -> None:
    records = [
        _rec(0, "a", "b", (0, 0, 0), Rotation.identity(), True),
        _rec(0, "c", "d", (0, 0, 0), Rotation.identity(), True),
    ]
    with pytest.raises(InputFileError, match="frames 'a' and 'd' are not connected"):
        TransformTree(records, "x.bag").lookup("a", "d", np.zeros(1, dtype=np.int64))
    records.append(_rec(0, "c", "b", (0, 0, 0), Rotation.identity(), True))
    with pytest.raises(InputFileError, match="frame 'b' has two parents in /tf, 'a' and 'c'"):
        TransformTree(records, "x.bag")
