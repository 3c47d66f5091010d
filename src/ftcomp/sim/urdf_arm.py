"""A simulated arm read from a URDF: the serial chain from a base link to a flange link, as a
:class:`~ftcomp.sim.arm.ChainArmSpec` the cell builds like any other arm.

The URDF is parsed as :mod:`ftcomp.ros2.urdf` parses it (pytransform3d, the extra ``urdf``): a
joint's ``<origin>`` places its frame in the parent link's frame, its ``<axis>`` is in its own
frame, and a link's ``<inertial>`` gives its mass, centre of mass and inertia tensor (about the
centre of mass, in the ``<inertial>`` frame's axes). Each revolute (or continuous) joint on the
path from ``base_link`` to ``flange_link`` makes one simulated link; links joined to it by fixed
joints on the path are merged into it (their masses summed, their inertias moved to the common
centre of mass), and the fixed joints after the last revolute one place the flange. What is
above the first revolute joint is the base (fixed, its mass does not matter); links off the path
(a hand, a camera, another branch) are left out: the cell mounts its own sensor and gripper on
the flange. A URDF names no servo gains: they are arguments, as is the start configuration.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.errors import InputFileError
from ftcomp.ros2.urdf import read_urdf
from ftcomp.sim.arm import ChainArmSpec

if TYPE_CHECKING:
    from pytransform3d.urdf import Joint, Link

__all__ = ["CONTINUOUS_RANGE_RAD", "urdf_arm"]

#: The range given to a continuous joint, or a revolute one whose URDF gives no finite limits
#: [rad]: the cell needs finite ranges (its IK draws seeds within them).
CONTINUOUS_RANGE_RAD: Final = 2.0 * math.pi
_REVOLUTE: Final = ("revolute", "continuous")


def urdf_arm(
    path: str | Path,
    *,
    base_link: str,
    flange_link: str,
    kp: ArrayLike,
    kv: ArrayLike,
    armature_kgm2: ArrayLike,
    home_q_rad: ArrayLike,
    name: str | None = None,
) -> ChainArmSpec:
    """The serial arm from ``base_link`` to ``flange_link`` of a URDF.

    Args:
        path: the URDF file (meshes are not loaded; a xacro file must be expanded first).
        base_link: the link the arm stands on (the robot's base frame).
        flange_link: the link whose frame is the tool flange (where the sensor is mounted).
        kp, kv, armature_kgm2: servo stiffness [N*m/rad], damping [N*m*s/rad] and reflected
            rotor inertia [kg*m^2] per revolute joint, (N,).
        home_q_rad: the start configuration [rad], (N,).
        name: the arm's name (default: the file's stem).

    Raises:
        MissingExtraError: pytransform3d (the extra ``urdf``) is not installed.
        InputFileError: an unreadable or invalid URDF, a link not in it, ``flange_link`` not
            below ``base_link``, a joint on the path that is neither fixed nor revolute, or a
            moving link without mass.
        ParameterError: gains or the start configuration of the wrong length or out of range.
    """
    links, joints = read_urdf(path)
    by_name = {str(link.name): link for link in links}
    for link in (base_link, flange_link):
        if link not in by_name:
            raise InputFileError(
                f"{path}: link {link!r} is not in the URDF; links: {', '.join(sorted(by_name))}"
            )
    path_joints = _path(path, joints, base_link, flange_link)
    placements: list[NDArray[np.float64]] = []  # each revolute joint's frame in its parent's
    axes: list[NDArray[np.float64]] = []
    limits: list[tuple[float, float]] = []
    bodies: list[list[tuple[float, NDArray[np.float64], NDArray[np.float64]]]] = []
    T = np.eye(4)  # the current frame in the last moving link's (or the base's) frame
    for joint in path_joints:
        T = T @ np.asarray(joint.child2parent, dtype=float)
        if joint.joint_type in _REVOLUTE:
            placements.append(T)
            axes.append(np.asarray(joint.joint_axis, dtype=float))
            limits.append(_limits(joint))
            bodies.append([])
            T = np.eye(4)
        elif joint.joint_type != "fixed":
            raise InputFileError(
                f"{path}: joint {joint.joint_name!r} is {joint.joint_type}; an arm's path from "
                f"{base_link!r} to {flange_link!r} may hold only revolute, continuous and fixed "
                "joints"
            )
        if bodies:  # the child link moves with the last revolute joint: its inertia joins it
            bodies[-1].append(_inertial(by_name[str(joint.child)], T))
    if not placements:
        raise InputFileError(f"{path}: no revolute joint between {base_link!r} and {flange_link!r}")
    masses, coms, inertias = [], [], []
    for joint, parts in zip(
        (j for j in path_joints if j.joint_type in _REVOLUTE), bodies, strict=True
    ):
        mass, com, inertia = _merge(parts)
        if not mass > 0.0:
            raise InputFileError(
                f"{path}: link {joint.child!r} (and the links fixed to it) has no mass; a moving "
                "body needs one"
            )
        masses.append(mass)
        coms.append(com)
        inertias.append(inertia)
    lower, upper = np.array(limits).T
    return ChainArmSpec(
        name=name if name is not None else Path(path).stem,
        p_parent_joint_m=np.array([P[:3, 3] for P in placements]),
        R_parent_joint=np.array([P[:3, :3] for P in placements]),
        joint_axis=np.array(axes),
        link_masses_kg=np.array(masses),
        link_com_m=np.array(coms),
        link_inertia_kgm2=np.array(inertias),
        joint_lower_rad=lower,
        joint_upper_rad=upper,
        kp=np.asarray(kp, dtype=float),
        kv=np.asarray(kv, dtype=float),
        armature_kgm2=np.asarray(armature_kgm2, dtype=float),
        home_q_rad=np.asarray(home_q_rad, dtype=float),
        p_link_flange_m=T[:3, 3].copy(),
        R_link_flange=T[:3, :3].copy(),
    )


def _path(path: str | Path, joints: list[Joint], base: str, flange: str) -> list[Joint]:
    """The joints from ``base`` down to ``flange``, top first."""
    parent_joint = {str(j.child): j for j in joints}
    out: list[Joint] = []
    link = flange
    while link != base:
        if link not in parent_joint:
            raise InputFileError(f"{path}: link {flange!r} is not below link {base!r}")
        joint = parent_joint[link]
        out.append(joint)
        link = str(joint.parent)
        if len(out) > len(joints):
            raise InputFileError(f"{path}: the joints form a loop through {flange!r}")
    return out[::-1]


def _limits(joint: Joint) -> tuple[float, float]:
    """A revolute joint's range [rad]; +-:data:`CONTINUOUS_RANGE_RAD` where the URDF gives none."""
    lower, upper = (float(v) for v in joint.limits)
    if joint.joint_type == "continuous" or not (math.isfinite(lower) and math.isfinite(upper)):
        return -CONTINUOUS_RANGE_RAD, CONTINUOUS_RANGE_RAD
    return lower, upper


def _inertial(
    link: Link, T_body_link: NDArray[np.float64]
) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """A link's mass, centre of mass and inertia about it, in the moving body's frame."""
    frame = T_body_link @ np.asarray(link.inertial_frame, dtype=float)
    R = frame[:3, :3]
    return float(link.mass), frame[:3, 3], R @ np.asarray(link.inertia, dtype=float) @ R.T


def _merge(
    parts: list[tuple[float, NDArray[np.float64], NDArray[np.float64]]],
) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """Rigidly joined parts as one body: total mass, centre of mass, inertia about it."""
    parts = [part for part in parts if part[0] > 0.0]
    mass = sum(m for m, _, _ in parts)
    if not mass > 0.0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    com = sum((m * c for m, c, _ in parts), np.zeros(3)) / mass
    inertia = np.zeros((3, 3))
    for m, c, I_c in parts:
        r = c - com
        inertia += I_c + m * (float(r @ r) * np.eye(3) - np.outer(r, r))  # parallel axes
    return mass, com, inertia
