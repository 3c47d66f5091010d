"""The simulated arms: a six-axis arm close to the EPSON C4-A901S (about 0.9 m reach, the
``sim://`` cell's) and any serial chain given by a Denavit-Hartenberg table (the UR5e, the
twin's; the seven-joint Franka Research 3).

The C4-like arm (:class:`ArmSpec`) is a classic anthropomorphic arm with a spherical wrist. In
the zero configuration the upper arm points up (base z), the forearm and the flange point forward
(base x). Lengths and joint ranges follow the C4-A901S data sheet roughly; masses are plausible,
not measured (they do not enter the sensor reading: only the bodies below the sensor do).

:class:`DHArmSpec` describes an arm of any number of revolute joints as data: its DH rows
(``a``, ``d``, ``alpha``) in either convention, named (``convention``, never a default):

- ``"standard"`` (Denavit and Hartenberg; UR publishes its arms so): joint ``i`` turns about
  ``z_{i-1}`` and ``T_{i-1,i} = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``;
- ``"modified"`` (Craig's; Franka publishes its arms so): joint ``i`` turns about ``z_i`` and
  ``T_{i-1,i} = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(q_i) Tz(d_i)``, row ``i`` holding
  ``a_{i-1}, d_i, alpha_{i-1}``;

then a fixed flange row in the same convention (Franka's ``d = 0.107``), each link's mass,
centre of mass and inertia in its DH frame, joint ranges, servo gains and the start
configuration. :func:`ur5e_arm` is the UR5e from UR's page "DH Parameters for calculations of
kinematics and dynamics", :func:`fr3_arm` the Franka Research 3 from Franka's;
:func:`dh_flange_pose` is the forward kinematics of either (the pose a UR reports as its TCP
with a zero TCP offset, Franka's ``O_T_EE`` with no end effector configured).

Every joint is position-servoed, as on an industrial controller: a MuJoCo ``position`` actuator
(proportional gain ``kp`` [N*m/rad], derivative gain ``kv`` [N*m*s/rad]) plus a feedforward of the
arm's gravity and Coriolis torques and of ``kv`` times the commanded joint velocity, applied by
:class:`ftcomp.sim.cell.SimCell` every physics step.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Final, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.arrays import freeze_field
from ftcomp.errors import ParameterError

__all__ = [
    "ARMS",
    "ARM_JOINT_NAMES",
    "C4_HOME_Q_RAD",
    "DH_CONVENTIONS",
    "FR3_HOME_Q_RAD",
    "UR5E_HOME_Q_RAD",
    "ArmModel",
    "ArmSpec",
    "ChainArmSpec",
    "DHArmSpec",
    "DHConvention",
    "c4_like_arm",
    "chain_flange_pose",
    "dh_flange_pose",
    "fr3_arm",
    "joint_names",
    "ur5e_arm",
]


def joint_names(n_joints: int) -> tuple[str, ...]:
    """MJCF names of an arm's joints, base to flange: ``("j1", ..., "jN")``."""
    return tuple(f"j{i + 1}" for i in range(n_joints))


#: MJCF names of a six-joint arm's joints, base to flange (:func:`joint_names` of any arm).
ARM_JOINT_NAMES: Final = joint_names(6)
#: The two conventions of a DH table (see the module docstring).
DHConvention = Literal["standard", "modified"]
DH_CONVENTIONS: Final[tuple[DHConvention, ...]] = ("standard", "modified")
#: The C4-like arm's start configuration: tool pointing straight down in front of the robot [rad].
C4_HOME_Q_RAD: Final = (0.0, 0.0, 0.6, 0.0, math.pi / 2 - 0.6, 0.0)
#: The UR5e's start configuration [rad]: the flange's z (the tool axis) straight down, 0.45 m in
#: front of the base (base x) and 0.42 m above it, the flange's x along base x.
UR5E_HOME_Q_RAD: Final = (
    2.8408577340736927,
    -1.7049049860629095,
    1.8690368567263893,
    -1.7349281974583763,
    -math.pi / 2,
    -1.871531246310997,
)
#: The Franka Research 3's start configuration [rad]: Franka's "ready" pose (libfranka's
#: examples move there first), the flange's z (the tool axis) straight down in front of the base.
FR3_HOME_Q_RAD: Final = (0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4)


@dataclass(frozen=True)
class ArmSpec:
    """Geometry, inertia and servo gains of the six-axis arm.

    Attributes:
        base_height_m: height of the shoulder (J2) above the base plate [m].
        shoulder_offset_m: J1 to J2 offset along the base x axis at zero [m].
        upper_arm_m: J2 to J3 distance [m].
        elbow_offset_m: J3 to forearm axis offset (perpendicular) [m].
        forearm_m: J3 to wrist centre (J5) along the forearm [m].
        wrist_to_flange_m: J5 to the flange face [m].
        link_masses_kg: masses of links 1..6 [kg], shape (6,).
        joint_lower_rad, joint_upper_rad: joint ranges [rad], shape (6,).
        kp: servo stiffness per joint [N*m/rad], shape (6,).
        kv: servo damping per joint [N*m*s/rad], shape (6,).
        armature_kgm2: reflected rotor inertia per joint [kg*m^2], shape (6,).
        home_q_rad: the start configuration [rad], shape (6,).
    """

    base_height_m: float = 0.32
    shoulder_offset_m: float = 0.10
    upper_arm_m: float = 0.40
    elbow_offset_m: float = 0.02
    forearm_m: float = 0.40
    wrist_to_flange_m: float = 0.065
    link_masses_kg: NDArray[np.float64] = field(
        default_factory=lambda: np.array([8.0, 6.0, 3.0, 1.5, 0.8, 0.3])
    )
    joint_lower_rad: NDArray[np.float64] = field(
        default_factory=lambda: np.radians([-170.0, -65.0, -51.0, -200.0, -135.0, -360.0])
    )
    joint_upper_rad: NDArray[np.float64] = field(
        default_factory=lambda: np.radians([170.0, 160.0, 225.0, 200.0, 135.0, 360.0])
    )
    kp: NDArray[np.float64] = field(
        default_factory=lambda: np.array([2.0e4, 2.0e4, 2.0e4, 5.0e3, 5.0e3, 5.0e3])
    )
    kv: NDArray[np.float64] = field(
        default_factory=lambda: np.array([600.0, 600.0, 400.0, 60.0, 60.0, 40.0])
    )
    armature_kgm2: NDArray[np.float64] = field(
        default_factory=lambda: np.array([1.0, 1.0, 0.5, 0.1, 0.1, 0.05])
    )
    home_q_rad: NDArray[np.float64] = field(default_factory=lambda: np.array(C4_HOME_Q_RAD))

    def __post_init__(self) -> None:
        for name in (
            "base_height_m",
            "shoulder_offset_m",
            "upper_arm_m",
            "elbow_offset_m",
            "forearm_m",
            "wrist_to_flange_m",
        ):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0.0:
                raise ParameterError(f"ArmSpec.{name} must be finite and >= 0, got {value}")
        _freeze_and_check_joints(self, 6)

    @property
    def n_joints(self) -> int:
        """Six."""
        return 6

    @property
    def joint_names(self) -> tuple[str, ...]:
        """MJCF names of the joints, base to flange."""
        return ARM_JOINT_NAMES

    @property
    def reach_m(self) -> float:
        """Distance from the J2 axis to the flange with the arm stretched out [m]."""
        return (
            self.upper_arm_m
            + math.hypot(self.forearm_m, self.elbow_offset_m)
            + (self.wrist_to_flange_m)
        )


def c4_like_arm() -> ArmSpec:
    """The default arm, close to the EPSON C4-A901S: 0.9 m reach from J1, its joint ranges."""
    return ArmSpec()


#: The fields every arm has per joint, shape (n_joints,).
_PER_JOINT: Final = (
    "link_masses_kg",
    "joint_lower_rad",
    "joint_upper_rad",
    "kp",
    "kv",
    "armature_kgm2",
    "home_q_rad",
)


def _freeze_and_check_joints(arm: ArmSpec | DHArmSpec | ChainArmSpec, n_joints: int) -> None:
    """Freeze an arm's per-joint fields and check their ranges (either arm's __post_init__)."""
    for field_name in _PER_JOINT:
        freeze_field(arm, field_name, (n_joints,), finite=True)
    name = type(arm).__name__
    if np.any(arm.joint_lower_rad >= arm.joint_upper_rad):
        raise ParameterError(f"{name} joint_lower_rad must be below joint_upper_rad")
    if np.any(arm.link_masses_kg <= 0.0) or np.any(arm.kp <= 0.0) or np.any(arm.kv < 0.0):
        raise ParameterError(f"{name} masses and kp must be > 0, kv >= 0")
    if np.any(arm.armature_kgm2 < 0.0):
        raise ParameterError(f"{name} armature_kgm2 must be >= 0")
    outside = (arm.home_q_rad < arm.joint_lower_rad) | (arm.home_q_rad > arm.joint_upper_rad)
    if np.any(outside):
        raise ParameterError(f"{name} home_q_rad must lie within the joint ranges")


@dataclass(frozen=True)
class DHArmSpec:
    """An arm of ``N`` revolute joints from its Denavit-Hartenberg table, link masses and
    inertias, joint ranges and servo gains.

    The MuJoCo body of link ``i`` *is* DH frame ``i`` (frame 0: the base), so the centres of
    mass and inertias below are given in those frames, as UR and Franka publish them. After
    the last joint, a fixed flange row (``flange_a_m``, ``flange_d_m``, ``flange_alpha_rad``,
    in the same convention with ``q = 0``) places the tool flange, where the sensor is mounted;
    all zero: the flange is DH frame ``N`` (a UR's).

    Attributes:
        name: the arm's name (e.g. ``"ur5e"``).
        convention: ``"standard"`` or ``"modified"`` (Craig) DH, as the module docstring
            defines them.
        dh_a_m: ``a`` of the rows [m], shape (N,) (modified: ``a_{i-1}`` in row ``i``).
        dh_d_m: ``d`` of the rows [m], shape (N,).
        dh_alpha_rad: ``alpha`` of the rows [rad], shape (N,) (modified: ``alpha_{i-1}``).
        link_masses_kg: masses of links 1..N [kg], shape (N,).
        link_com_m: centre of mass of each link in its DH frame [m], shape (N, 3).
        link_inertia_kgm2: each link's inertia about its centre of mass in its DH frame's
            axes [kg*m^2]: principal moments along those axes, shape (N, 3), or the full
            symmetric tensors, shape (N, 3, 3).
        joint_lower_rad, joint_upper_rad: joint ranges [rad], shape (N,).
        kp, kv, armature_kgm2: servo stiffness [N*m/rad], damping [N*m*s/rad] and reflected
            rotor inertia [kg*m^2] per joint, shape (N,) (as :class:`ArmSpec`).
        home_q_rad: the start configuration [rad], shape (N,).
        flange_a_m, flange_d_m, flange_alpha_rad: the fixed flange row [m, m, rad].
    """

    name: str
    convention: DHConvention
    dh_a_m: NDArray[np.float64]
    dh_d_m: NDArray[np.float64]
    dh_alpha_rad: NDArray[np.float64]
    link_masses_kg: NDArray[np.float64]
    link_com_m: NDArray[np.float64]
    link_inertia_kgm2: NDArray[np.float64]
    joint_lower_rad: NDArray[np.float64]
    joint_upper_rad: NDArray[np.float64]
    kp: NDArray[np.float64]
    kv: NDArray[np.float64]
    armature_kgm2: NDArray[np.float64]
    home_q_rad: NDArray[np.float64]
    flange_a_m: float = 0.0
    flange_d_m: float = 0.0
    flange_alpha_rad: float = 0.0

    def __post_init__(self) -> None:
        if not self.name:
            raise ParameterError("DHArmSpec.name must not be empty")
        if self.convention not in DH_CONVENTIONS:
            raise ParameterError(
                f"DHArmSpec.convention: unknown {self.convention!r}; "
                f"valid: {', '.join(DH_CONVENTIONS)}"
            )
        n = int(np.size(self.dh_a_m))
        if n < 1:
            raise ParameterError("DHArmSpec needs at least one joint (dh_a_m is empty)")
        for name in ("dh_a_m", "dh_d_m", "dh_alpha_rad"):
            freeze_field(self, name, (n,), finite=True)
        _freeze_and_check_joints(self, n)
        freeze_field(self, "link_com_m", (n, 3), finite=True)
        inertia = np.asarray(self.link_inertia_kgm2, dtype=float)
        freeze_field(
            self, "link_inertia_kgm2", (n, 3, 3) if inertia.ndim == 3 else (n, 3), finite=True
        )
        if inertia.ndim == 2 and np.any(inertia <= 0.0):
            raise ParameterError("DHArmSpec.link_inertia_kgm2 must be > 0")
        if inertia.ndim == 3 and (
            not np.allclose(inertia, np.swapaxes(inertia, 1, 2), rtol=0.0, atol=1e-15)
            or np.any(np.linalg.eigvalsh(inertia) <= 0.0)
        ):
            raise ParameterError(
                "DHArmSpec.link_inertia_kgm2 tensors must be symmetric and positive definite"
            )
        for name in ("flange_a_m", "flange_d_m", "flange_alpha_rad"):
            if not math.isfinite(getattr(self, name)):
                raise ParameterError(f"DHArmSpec.{name} must be finite, got {getattr(self, name)}")

    @property
    def n_joints(self) -> int:
        """The number of joints, N."""
        return int(self.dh_a_m.shape[0])

    @property
    def joint_names(self) -> tuple[str, ...]:
        """MJCF names of the joints, base to flange."""
        return joint_names(self.n_joints)

    @property
    def has_flange_row(self) -> bool:
        """Whether the flange sits off DH frame N (a non-zero flange row)."""
        return bool(self.flange_a_m or self.flange_d_m or self.flange_alpha_rad)

    def transforms(self, q_rad: NDArray[np.float64]) -> list[NDArray[np.float64]]:
        """``T_{i-1,i}`` of the N rows at joint positions ``q_rad`` [rad], each (4, 4)."""
        rows = zip(q_rad, self.dh_a_m, self.dh_d_m, self.dh_alpha_rad, strict=True)
        return [self._row(q, a, d, alpha) for q, a, d, alpha in rows]

    def row_transform(self, i: int, q: float) -> NDArray[np.float64]:
        """``T_{i,i+1}``: row ``i`` (0-based) of the table at joint position ``q`` [rad], (4, 4)."""
        return self._row(q, self.dh_a_m[i], self.dh_d_m[i], self.dh_alpha_rad[i])

    def flange_transform(self) -> NDArray[np.float64]:
        """``T_{N,flange}``: the fixed flange row, (4, 4) (the identity without one)."""
        return self._row(0.0, self.flange_a_m, self.flange_d_m, self.flange_alpha_rad)

    def _row(self, q: float, a: float, d: float, alpha: float) -> NDArray[np.float64]:
        cq, sq, ca, sa = math.cos(q), math.sin(q), math.cos(alpha), math.sin(alpha)
        if self.convention == "standard":  # Rz(q) Tz(d) Tx(a) Rx(alpha)
            return np.array(
                [
                    [cq, -sq * ca, sq * sa, a * cq],
                    [sq, cq * ca, -cq * sa, a * sq],
                    [0.0, sa, ca, d],
                    [0.0, 0.0, 0.0, 1.0],
                ]
            )
        return np.array(  # Rx(alpha) Tx(a) Rz(q) Tz(d)
            [
                [cq, -sq, 0.0, a],
                [sq * ca, cq * ca, -sa, -sa * d],
                [sq * sa, cq * sa, ca, ca * d],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )


@dataclass(frozen=True)
class ChainArmSpec:
    """An arm of ``N`` revolute joints as its joint frames: any serial chain, e.g. a URDF's
    (:func:`ftcomp.sim.urdf_arm.urdf_arm`).

    Link ``i``'s frame is joint ``i``'s frame (as in a URDF): placed in link ``i-1``'s frame
    (link 0: the base) at ``p_parent_joint_m[i]``, ``R_parent_joint[i]`` when the joint is at
    zero, turning link ``i`` about ``joint_axis[i]`` (a unit vector in its own frame) through
    its origin. The MuJoCo body of link ``i`` is that frame; the flange sits in link N's frame
    at ``p_link_flange_m``, ``R_link_flange``.

    Attributes:
        name: the arm's name.
        p_parent_joint_m: each joint frame's origin in its parent link's frame [m], (N, 3).
        R_parent_joint: each joint frame's axes in its parent link's frame, (N, 3, 3).
        joint_axis: each joint's axis in its own frame, (N, 3) (normalised here).
        link_masses_kg: masses of links 1..N [kg], (N,).
        link_com_m: each link's centre of mass in its frame [m], (N, 3).
        link_inertia_kgm2: each link's inertia tensor about its centre of mass, in its frame's
            axes [kg*m^2], (N, 3, 3).
        joint_lower_rad, joint_upper_rad, kp, kv, armature_kgm2, home_q_rad: as
            :class:`DHArmSpec`'s, (N,).
        p_link_flange_m: the flange's origin in link N's frame [m], (3,).
        R_link_flange: the flange's axes in link N's frame, (3, 3).
    """

    name: str
    p_parent_joint_m: NDArray[np.float64]
    R_parent_joint: NDArray[np.float64]
    joint_axis: NDArray[np.float64]
    link_masses_kg: NDArray[np.float64]
    link_com_m: NDArray[np.float64]
    link_inertia_kgm2: NDArray[np.float64]
    joint_lower_rad: NDArray[np.float64]
    joint_upper_rad: NDArray[np.float64]
    kp: NDArray[np.float64]
    kv: NDArray[np.float64]
    armature_kgm2: NDArray[np.float64]
    home_q_rad: NDArray[np.float64]
    p_link_flange_m: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    R_link_flange: NDArray[np.float64] = field(default_factory=lambda: np.eye(3))

    def __post_init__(self) -> None:
        if not self.name:
            raise ParameterError("ChainArmSpec.name must not be empty")
        n = int(np.shape(self.p_parent_joint_m)[0]) if np.ndim(self.p_parent_joint_m) else 0
        if n < 1:
            raise ParameterError("ChainArmSpec needs at least one joint")
        freeze_field(self, "p_parent_joint_m", (n, 3), finite=True)
        freeze_field(self, "R_parent_joint", (n, 3, 3), finite=True)
        axis = np.array(self.joint_axis, dtype=float)
        norm = np.linalg.norm(axis, axis=-1, keepdims=True) if axis.shape == (n, 3) else None
        if norm is None or not np.all(norm > 1e-9):
            raise ParameterError("ChainArmSpec.joint_axis must be N non-zero vectors, (N, 3)")
        object.__setattr__(self, "joint_axis", axis / norm)
        freeze_field(self, "joint_axis", (n, 3), finite=True)
        _freeze_and_check_joints(self, n)
        freeze_field(self, "link_com_m", (n, 3), finite=True)
        freeze_field(self, "link_inertia_kgm2", (n, 3, 3), finite=True)
        freeze_field(self, "p_link_flange_m", (3,), finite=True)
        freeze_field(self, "R_link_flange", (3, 3), finite=True)
        for name, R in (
            ("R_parent_joint", self.R_parent_joint),
            ("R_link_flange", self.R_link_flange),
        ):
            R3 = R.reshape(-1, 3, 3)
            if not np.allclose(R3 @ np.swapaxes(R3, 1, 2), np.eye(3), atol=1e-9) or np.any(
                np.linalg.det(R3) < 0.0
            ):
                raise ParameterError(f"ChainArmSpec.{name} must be rotation matrices")
        inertia = self.link_inertia_kgm2
        if not np.allclose(inertia, np.swapaxes(inertia, 1, 2), rtol=0.0, atol=1e-15) or np.any(
            np.linalg.eigvalsh(inertia) <= 0.0
        ):
            raise ParameterError(
                "ChainArmSpec.link_inertia_kgm2 tensors must be symmetric and positive definite"
            )

    @property
    def n_joints(self) -> int:
        """The number of joints, N."""
        return int(self.p_parent_joint_m.shape[0])

    @property
    def joint_names(self) -> tuple[str, ...]:
        """MJCF names of the joints, base to flange."""
        return joint_names(self.n_joints)

    @property
    def has_flange_offset(self) -> bool:
        """Whether the flange sits off link N's frame."""
        return bool(np.any(self.p_link_flange_m) or np.any(self.R_link_flange != np.eye(3)))


#: Any arm the cell can carry.
ArmModel = ArmSpec | DHArmSpec | ChainArmSpec


def chain_flange_pose(
    arm: ChainArmSpec, q_rad: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Forward kinematics of a :class:`ChainArmSpec`: ``(p_base_flange [m] (3,),
    R_base_flange (3, 3))``, each joint's fixed placement, then its turn (Rodrigues).

    Raises:
        ParameterError: ``q_rad`` is not N finite joint angles.
    """
    q = np.asarray(q_rad, dtype=float)
    n = arm.n_joints
    if q.shape != (n,) or not np.isfinite(q).all():
        raise ParameterError(f"q_rad must be {n} finite joint angles [rad], got {q_rad!r}")
    p, R = np.zeros(3), np.eye(3)
    for p_i, R_i, axis, angle in zip(
        arm.p_parent_joint_m, arm.R_parent_joint, arm.joint_axis, q, strict=True
    ):
        K = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
        turn = np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)
        p, R = p + R @ p_i, R @ R_i @ turn
    return p + R @ arm.p_link_flange_m, R @ arm.R_link_flange


def dh_flange_pose(
    arm: DHArmSpec, q_rad: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Forward kinematics: ``(p_base_flange [m] (3,), R_base_flange (3, 3))`` of the flange
    (DH frame N times the flange row).

    For a UR this is the TCP pose the controller reports (``actual_TCP_pose``, the pendant's
    Move tab) with a zero TCP offset; for a Franka, ``O_T_EE`` with no end effector set.

    Raises:
        ParameterError: ``q_rad`` is not N finite joint angles.
    """
    q = np.asarray(q_rad, dtype=float)
    n = arm.n_joints
    if q.shape != (n,) or not np.isfinite(q).all():
        raise ParameterError(f"q_rad must be {n} finite joint angles [rad], got {q_rad!r}")
    T = np.eye(4)
    for Ti in arm.transforms(q):
        T = T @ Ti
    if arm.has_flange_row:
        T = T @ arm.flange_transform()
    return T[:3, 3].copy(), T[:3, :3].copy()


def ur5e_arm() -> DHArmSpec:
    """The Universal Robots UR5e.

    Kinematics (DH ``a``, ``d``, ``alpha``), link masses and centres of mass from UR's article
    "DH Parameters for calculations of kinematics and dynamics"
    (https://www.universal-robots.com/articles/ur/application-installation/dh-parameters-for-calculations-of-kinematics-and-dynamics/);
    the same values as ``Universal_Robots_ROS2_Description``'s ``config/ur5e/*.yaml``. The
    inertias are that description's principal moments turned to the DH frames (UR calls the
    UR5e's negligible and publishes none). Joint ranges +-360 deg on every joint, as UR's
    UR5e user manual states (ROS's description limits the elbow to +-180 deg for its planners;
    the controller does not). Servo gains: stiff position servos, four times the C4-like
    arm's stiffness (its longer links would sag 0.22 mm under a held 0.5 kg at the C4's
    gains; at these 46 um, as the C4-like arm's) and twice its damping (the same damping
    ratio); the armature as the C4-like arm's.
    """
    pi2 = math.pi / 2
    return DHArmSpec(
        name="ur5e",
        convention="standard",
        dh_a_m=np.array([0.0, -0.425, -0.3922, 0.0, 0.0, 0.0]),
        dh_d_m=np.array([0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996]),
        dh_alpha_rad=np.array([pi2, 0.0, 0.0, pi2, -pi2, 0.0]),
        link_masses_kg=np.array([3.761, 8.058, 2.846, 1.37, 1.3, 0.365]),
        link_com_m=np.array(
            [
                [0.0, -0.02561, 0.00193],
                [0.2125, 0.0, 0.11336],
                [0.15, 0.0, 0.0265],
                [0.0, -0.0018, 0.01634],
                [0.0, 0.0018, 0.01634],
                [0.0, 0.0, -0.001159],
            ]
        ),
        link_inertia_kgm2=np.array(
            [
                [0.00700210, 0.00657286, 0.00648091],
                [0.01505885, 0.33388086, 0.33247207],
                [0.00399632, 0.07879254, 0.07848510],
                [0.00165491, 0.00126279, 0.00135962],
                [0.00135617, 0.00096614, 0.00127827],
                [0.00018694, 0.00018908, 0.00025756],
            ]
        ),
        joint_lower_rad=np.full(6, -2.0 * math.pi),
        joint_upper_rad=np.full(6, 2.0 * math.pi),
        kp=np.array([8.0e4, 8.0e4, 8.0e4, 2.0e4, 2.0e4, 2.0e4]),
        kv=np.array([1200.0, 1200.0, 800.0, 120.0, 120.0, 80.0]),
        armature_kgm2=np.array([1.0, 1.0, 0.5, 0.1, 0.1, 0.05]),
        home_q_rad=np.array(UR5E_HOME_Q_RAD),
    )


def _symmetric(
    xx: float, yy: float, zz: float, xy: float, xz: float, yz: float
) -> list[list[float]]:
    return [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]


def fr3_arm() -> DHArmSpec:
    """The Franka Research 3 (seven joints, modified DH).

    Kinematics from Franka's "Robot and interface specifications" (FCI documentation,
    https://frankaemika.github.io/docs/control_parameters.html, Denavit-Hartenberg parameters):
    ``a = 0, 0, 0, 0.0825, -0.0825, 0, 0.088``, ``d = 0.333, 0, 0.316, 0, 0.384, 0, 0``,
    ``alpha = 0, -pi/2, pi/2, pi/2, -pi/2, pi/2, pi/2`` [m, rad], and the flange ``d = 0.107``;
    the same joint origins as ``franka_description``'s ``robots/fr3/fr3.urdf.xacro``, whose link
    frames are these DH frames. Joint ranges from the same page (FR3 column), as
    ``franka_description``'s ``robots/fr3/joint_limits.yaml``: q1 +-2.7437, q2 +-1.7837,
    q3 +-2.9007, q4 -3.0421 .. -0.1518, q5 +-2.8065, q6 0.5445 .. 4.5169, q7 +-3.0159 rad.
    Link masses, centres of mass and full inertia tensors (links 1-7, in the link frames)
    from ``franka_description``'s ``robots/fr3/inertials.yaml``
    (https://github.com/frankaemika/franka_description, commit 14c5d63). The start
    configuration is Franka's ready pose :data:`FR3_HOME_Q_RAD`. Servo gains: as the UR5e's,
    the stiff gains on the four big joints and the wrist's on the last three; the armature as
    the UR5e's, joint 4 as joint 3 (Franka publishes no rotor inertias).
    """
    pi2 = math.pi / 2
    return DHArmSpec(
        name="fr3",
        convention="modified",
        dh_a_m=np.array([0.0, 0.0, 0.0, 0.0825, -0.0825, 0.0, 0.088]),
        dh_d_m=np.array([0.333, 0.0, 0.316, 0.0, 0.384, 0.0, 0.0]),
        dh_alpha_rad=np.array([0.0, -pi2, pi2, pi2, -pi2, pi2, pi2]),
        link_masses_kg=np.array(
            [
                2.9274653454,
                2.9355370338,
                2.2449013699,
                2.6155955791,
                2.3271207594,
                1.8170376524,
                0.6271432862,
            ]
        ),
        link_com_m=np.array(
            [
                [0.0000004128, -0.0181251324, -0.0386035970],
                [0.0031828864, -0.0743221644, 0.0088146084],
                [0.0407015686, -0.0048200565, -0.0289730823],
                [-0.0459100965, 0.0630492960, -0.0085187868],
                [-0.0016039605, 0.0292536262, -0.0972965990],
                [0.0597131221, -0.0410294666, -0.0101692726],
                [0.0045225817, 0.0086261921, -0.0161633251],
            ]
        ),
        # (xx, yy, zz, xy, xz, yz) of each link, about its centre of mass [kg*m^2].
        link_inertia_kgm2=np.array(
            [
                _symmetric(
                    0.023927316485107913,
                    0.0224821613275756,
                    0.006350098258530016,
                    1.3317903455714081e-05,
                    -0.00011404774918616684,
                    -0.0019950320628240115,
                ),
                _symmetric(
                    0.041938946257609425,
                    0.02514514885014724,
                    0.06170214472888839,
                    0.00020257331521090626,
                    0.004077784227179924,
                    -0.0042252158006570156,
                ),
                _symmetric(
                    0.02410142547240885,
                    0.01974053266708178,
                    0.019044494482244823,
                    0.002404694559042109,
                    -0.002856269270114313,
                    -0.002104212683891874,
                ),
                _symmetric(
                    0.03452998321913202,
                    0.028881621933049058,
                    0.04125471171146641,
                    0.01322552265982813,
                    0.01015142998484113,
                    -0.0009762833870704552,
                ),
                _symmetric(
                    0.051610278463662895,
                    0.04787729713371481,
                    0.016423625579357254,
                    -0.005715173387783472,
                    -0.0035673167625872135,
                    0.010673985108535986,
                ),
                _symmetric(
                    0.005412333594383447,
                    0.014058329545509979,
                    0.016080817924212554,
                    0.006193456360285834,
                    0.0014219289306117652,
                    -0.0013140753741120031,
                ),
                _symmetric(
                    0.00021092389150104718,
                    0.00017718568002411474,
                    5.993190599659971e-05,
                    -2.433299114461931e-05,
                    4.564480393778983e-05,
                    8.744070223226438e-05,
                ),
            ]
        ),
        joint_lower_rad=np.array([-2.7437, -1.7837, -2.9007, -3.0421, -2.8065, 0.5445, -3.0159]),
        joint_upper_rad=np.array([2.7437, 1.7837, 2.9007, -0.1518, 2.8065, 4.5169, 3.0159]),
        kp=np.array([8.0e4, 8.0e4, 8.0e4, 8.0e4, 2.0e4, 2.0e4, 2.0e4]),
        kv=np.array([1200.0, 1200.0, 800.0, 800.0, 120.0, 120.0, 80.0]),
        armature_kgm2=np.array([1.0, 1.0, 0.5, 0.5, 0.1, 0.1, 0.05]),
        home_q_rad=np.array(FR3_HOME_Q_RAD),
        flange_d_m=0.107,
    )


#: The arms a cell can be built with, by name (``sim://?arm=NAME``).
ARMS: Final[Mapping[str, Callable[[], ArmModel]]] = {
    "c4": c4_like_arm,
    "fr3": fr3_arm,
    "ur5e": ur5e_arm,
}
