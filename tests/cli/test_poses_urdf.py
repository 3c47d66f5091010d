"""``ftcomp poses design --urdf``: reachable designs from a robot description, bad input."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from ftcomp.chain_ik import ChainIk
from ftcomp.cli import main
from ftcomp.io.poses_csv import read_pose_file
from ftcomp.ros2.urdf import UrdfChain
from ros2.simbag import urdf_of_cell


@pytest.fixture(scope="module")
def arm(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The simulated six-joint arm as URDF (base -> ... -> flange -> ft_sensor)."""
    from ftcomp.sim import SceneConfig, SimCell

    path = tmp_path_factory.mktemp("urdf") / "arm.urdf"
    path.write_text(urdf_of_cell(SimCell(SceneConfig())))
    return path


def _error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: "), err[:300]
    return err


def test_a_urdf_design_lists_orientations_the_arm_reaches_at_the_stated_position(
    arm, tmp_path, capsys
) -> None:
    out = tmp_path / "poses.csv"
    args = ["poses", "design", "--count", "9", "--urdf", str(arm), "-o", str(out)]
    assert main([*args, "--position-mm", "450", "0", "420"]) == 0
    printed = capsys.readouterr().out
    assert "base -> ft_sensor (6 joints), tip at [0.45, 0.0, 0.42] m" in printed
    poses = read_pose_file(out)
    assert len(poses) == 9
    assert poses.positions_base_m is not None
    np.testing.assert_array_equal(poses.positions_base_m, np.tile([0.45, 0.0, 0.42], (9, 1)))
    # Every orientation, checked again by forward kinematics of an IK solution within the
    # limits: the file's quaternions have 12 decimals, so the pose is met to ~1e-9 (1e-6 with
    # margin, far below the IK's acceptance of 1 mm and 0.1 deg).
    ik = ChainIk(UrdfChain(arm, "base", "ft_sensor"))
    lower, upper = ik.chain.joint_limits.T
    for p, R in zip(poses.positions_base_m, poses.rotations.as_matrix(), strict=True):
        q = ik.solve(p, R)
        assert q is not None and np.all(q >= lower) and np.all(q <= upper)
        dp, angle = ik.errors(q, p, R)
        assert dp < 1e-6 and angle < 1e-6


def test_the_default_position_and_links_come_from_the_chain(arm, tmp_path, capsys) -> None:
    out = tmp_path / "poses.csv"
    args = ["poses", "design", "--count", "4", "--max-tilt-deg", "60", "--urdf", str(arm)]
    assert main([*args, "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "base -> ft_sensor (6 joints), tip at [0.6251, 0.0, 0.32] m" in printed
    poses = read_pose_file(out)
    assert poses.positions_base_m is not None
    np.testing.assert_allclose(poses.positions_base_m[:, 1:], np.tile([0.0, 0.32], (4, 1)))


@pytest.mark.parametrize(
    ("extra", "expected"),
    [
        (["--robot", "sim://"], "argument --robot: not allowed with argument --urdf"),
        (["--position-mm", "400", "zero", "400"], "--position-mm: invalid float value: 'zero'"),
        (["--position-mm", "400", "nan", "400"], r"--position-mm \[400.0, nan, 400.0\]: need"),
        (["--position-mm", "3000", "0", "0"], "tip link 'ft_sensor' of .*arm.urdf cannot reach it"),
        (["--position-mm", "-3000", "0", "0"], r"--position-mm -3000 0 0 \[-3.0, 0.0, 0.0\] m"),
        (["--tip-link", "tool0"], r"arm\.urdf: link 'tool0' is not in the URDF; links: base"),
        (["--base-link", "nope"], r"arm\.urdf: link 'nope' is not in the URDF"),
    ],
)
def test_bad_urdf_options_are_one_line_and_exit_2(arm, tmp_path, capsys, extra, expected) -> None:
    out = tmp_path / "poses.csv"
    argv = ["poses", "design", "--count", "9", "--urdf", str(arm), "-o", str(out), *extra]
    if extra[0] == "--robot" or "zero" in extra:  # usage errors: the parser exits at once
        with pytest.raises(SystemExit) as exc:
            main(argv)
        assert exc.value.code == 2
    else:
        assert main(argv) == 2
    assert re.search(expected, _error_line(capsys))
    assert not out.exists()


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        (None, r"missing\.urdf: cannot read the URDF"),
        ("<robot><link name='a'/>", r"bad\.urdf: not a valid URDF"),
    ],
)
def test_an_unreadable_or_invalid_urdf_is_named(tmp_path, capsys, content, expected) -> None:
    urdf = tmp_path / ("missing.urdf" if content is None else "bad.urdf")
    if content is not None:
        urdf.write_text(content)
    argv = ["poses", "design", "--count", "9", "--urdf", str(urdf), "-o", str(tmp_path / "o.csv")]
    assert main(argv) == 2
    assert re.search(expected, _error_line(capsys))


def test_link_options_need_urdf(tmp_path, capsys) -> None:
    argv = ["poses", "design", "--count", "9", "-o", str(tmp_path / "o.csv"), "--tip-link", "x"]
    assert main(argv) == 2
    assert "--tip-link needs --urdf" in _error_line(capsys)


def test_too_few_reachable_orientations_stop_the_design_with_one_line(tmp_path, capsys) -> None:
    """A wrist that only turns about the vertical: of 84 candidates within 1 deg of hanging
    down, the 12 straight down are reachable, the 72 tilted by 1 deg are not."""
    urdf = tmp_path / "wrist.urdf"
    urdf.write_text(
        '<robot name="wrist"><link name="base"/><link name="flange"/><link name="sensor"/>'
        '<joint name="roll" type="continuous"><parent link="base"/><child link="flange"/>'
        '<origin xyz="0.5 0 0.4" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>'
        '<joint name="mount" type="fixed"><parent link="flange"/><child link="sensor"/>'
        '<origin xyz="0 0 -0.05" rpy="3.141592653589793 0 0"/></joint></robot>'
    )
    out = tmp_path / "o.csv"
    argv = ["poses", "design", "--count", "13", "--max-tilt-deg", "1", "--urdf", str(urdf)]
    assert main([*argv, "-o", str(out)]) == 2
    line = _error_line(capsys)
    assert "out of reach with the tip at [0.5, 0.0, 0.35] m" in line
    assert not out.exists()


def test_kept_poses_keep_their_positions_and_an_unreachable_one_is_warned(
    arm, tmp_path, capsys
) -> None:
    keep = tmp_path / "keep.csv"
    tilted = [-0.846908209064, -0.226928370682, 0.410623090210, 0.250277201890]
    keep.write_text(f"pose,qx,qy,qz,qw\nk1,1,0,0,0\nk2,{','.join(map(str, tilted))}\n")
    ik = ChainIk(UrdfChain(arm))
    high = np.array([0.595, 0.0, 0.74])
    assert ik.solve(high, np.diag([1.0, -1.0, -1.0])) is not None  # k1: straight down
    assert ik.solve(high, read_pose_file(keep).rotations.as_matrix()[1]) is None  # k2
    out = tmp_path / "poses.csv"
    argv = ["poses", "design", "--count", "3", "--keep", str(keep), "--urdf", str(arm)]
    assert main([*argv, "--position-mm", "595", "0", "740", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert (
        err == "warning: kept pose k2: the URDF's inverse kinematics does not reach it with "
        "the tip at [0.595, 0.0, 0.74] m\n"
    )
    poses = read_pose_file(out)
    assert poses.ids[:2] == ("k1", "k2") and len(poses) == 5
    assert poses.positions_base_m is not None
    np.testing.assert_array_equal(poses.positions_base_m, np.tile(high, (5, 1)))


@pytest.mark.parametrize("named_xacro", [True, False])
def test_a_xacro_file_is_named_and_the_way_to_expand_it_given(tmp_path, capsys, named_xacro):
    urdf = tmp_path / ("robot.urdf.xacro" if named_xacro else "robot.urdf")
    urdf.write_text(
        '<?xml version="1.0"?>\n<robot name="ur" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
        '  <xacro:include filename="$(find ur_description)/urdf/ur_macro.xacro"/>\n'
        '  <xacro:ur_robot name="ur" tf_prefix=""/>\n  <link name="world"/>\n</robot>\n'
    )
    argv = ["poses", "design", "--count", "9", "--urdf", str(urdf), "--tip-link", "tool0"]
    assert main([*argv, "-o", str(tmp_path / "o.csv")]) == 2
    line = _error_line(capsys)
    assert "a xacro file" in line and "expand it first: xacro" in line
    assert "is not in the URDF" not in line


def test_a_design_whose_best_poses_are_out_of_reach_samples_the_reachable_ones(
    tmp_path, capsys
) -> None:
    """A spherical wrist whose middle joint turns only +-1.6 rad: about half of all
    orientations are reachable, but the D-optimal design asks for the most tilted ones first.
    It used to give up after 150 misses (or when most of its own choices missed); now it
    designs among reachable candidates sampled at random and reports the fraction."""
    urdf = tmp_path / "wrist.urdf"
    urdf.write_text(
        '<robot name="wrist"><link name="base"/><link name="l1"/><link name="l2"/>'
        '<link name="l3"/><link name="sensor"/>'
        '<joint name="a" type="continuous"><parent link="base"/><child link="l1"/>'
        '<origin xyz="0.5 0 0.4" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>'
        '<joint name="b" type="revolute"><parent link="l1"/><child link="l2"/>'
        '<origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/>'
        '<limit lower="-1.6" upper="1.6" effort="1" velocity="1"/></joint>'
        '<joint name="c" type="continuous"><parent link="l2"/><child link="l3"/>'
        '<origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>'
        '<joint name="m" type="fixed"><parent link="l3"/><child link="sensor"/>'
        '<origin xyz="0 0 0" rpy="3.141592653589793 0 0"/></joint></robot>'
    )
    out = tmp_path / "o.csv"
    argv = ["poses", "design", "--count", "9", "--urdf", str(urdf), "--position-mm", "500", "0"]
    assert main([*argv, "400", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    match = re.search(r"(\d+)% of (\d+) sampled are reachable", printed)
    assert match is not None, printed
    assert 20 <= int(match.group(1)) <= 80 and int(match.group(2)) >= 20
    poses = read_pose_file(out)
    chain_ik = ChainIk(UrdfChain(urdf))
    for R in poses.rotations.as_matrix():  # every designed pose is reachable
        assert chain_ik.solve(np.array([0.5, 0.0, 0.4]), R) is not None
