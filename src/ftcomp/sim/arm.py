"""The simulated arms: a six-axis arm close to the EPSON C4-A901S (about 0.9 m reach, the
``sim://`` cell's) and arms given by a Denavit-Hartenberg table (the UR5e, the twin's).

The geometry is a classic anthropomorphic arm with a spherical wrist. In the zero configuration
the upper arm points up (base z), the forearm and the flange point forward (base x). Lengths and
joint ranges follow the C4-A901S data sheet roughly; masses are plausible, not measured (they do
not enter the sensor reading: only the bodies below the sensor do).

:class:`DHArmSpec` describes an arm as its standard DH rows (``a``, ``d``, ``alpha``: each joint
``i`` adds ``Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``) with each link's mass and centre of mass in
its DH frame, as Universal Robots publishes them; :func:`ur5e_arm` is the UR5e from UR's page
"DH Parameters for calculations of kinematics and dynamics" and :func:`dh_flange_pose` its
forward kinematics (the pose a UR reports as its TCP with a zero TCP offset).

Every joint is position-servoed, as on an industrial controller: a MuJoCo ``position`` actuator
(proportional gain ``kp`` [N*m/rad], derivative gain ``kv`` [N*m*s/rad]) plus a feedforward of the
arm's gravity and Coriolis torques and of ``kv`` times the commanded joint velocity, applied by
:class:`ftcomp.sim.cell.SimCell` every physics step.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.arrays import freeze_field
from ftcomp.errors import ParameterError

__all__ = [
    "ARMS",
    "ARM_JOINT_NAMES",
    "C4_HOME_Q_RAD",
    "UR5E_HOME_Q_RAD",
    "ArmModel",
    "ArmSpec",
    "DHArmSpec",
    "c4_like_arm",
    "dh_flange_pose",
    "ur5e_arm",
]

#: MJCF names of the six arm joints, base to flange.
ARM_JOINT_NAMES: Final = ("j1", "j2", "j3", "j4", "j5", "j6")
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
        _freeze_and_check_joints(self)

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


#: The fields every arm has per joint, shape (6,).
_PER_JOINT: Final = (
    "link_masses_kg",
    "joint_lower_rad",
    "joint_upper_rad",
    "kp",
    "kv",
    "armature_kgm2",
    "home_q_rad",
)


def _freeze_and_check_joints(arm: ArmSpec | DHArmSpec) -> None:
    """Freeze an arm's per-joint fields and check their ranges (either arm's __post_init__)."""
    for field_name in _PER_JOINT:
        freeze_field(arm, field_name, (6,), finite=True)
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
    """A six-axis arm from its standard Denavit-Hartenberg table, link masses and servo gains.

    Joint ``i`` (1..6) turns about ``z_{i-1}``; the DH frame ``i`` is
    ``T_{i-1,i} = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)`` in frame ``i-1`` (frame 0: the base,
    frame 6: the tool flange). The MuJoCo body of link ``i`` *is* DH frame ``i``, so the
    centres of mass and inertias below are given in those frames (as UR publishes them).

    Attributes:
        name: the arm's name (e.g. ``"ur5e"``).
        dh_a_m: ``a`` of the six rows [m], shape (6,).
        dh_d_m: ``d`` of the six rows [m], shape (6,).
        dh_alpha_rad: ``alpha`` of the six rows [rad], shape (6,).
        link_masses_kg: masses of links 1..6 [kg], shape (6,).
        link_com_m: centre of mass of each link in its DH frame [m], shape (6, 3).
        link_inertia_kgm2: principal moments of each link about its centre of mass, along its
            DH frame's axes [kg*m^2], shape (6, 3).
        joint_lower_rad, joint_upper_rad: joint ranges [rad], shape (6,).
        kp, kv, armature_kgm2: servo stiffness [N*m/rad], damping [N*m*s/rad] and reflected
            rotor inertia [kg*m^2] per joint, shape (6,) (as :class:`ArmSpec`).
        home_q_rad: the start configuration [rad], shape (6,).
    """

    name: str
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

    def __post_init__(self) -> None:
        if not self.name:
            raise ParameterError("DHArmSpec.name must not be empty")
        for name in ("dh_a_m", "dh_d_m", "dh_alpha_rad"):
            freeze_field(self, name, (6,), finite=True)
        _freeze_and_check_joints(self)
        freeze_field(self, "link_com_m", (6, 3), finite=True)
        freeze_field(self, "link_inertia_kgm2", (6, 3), finite=True)
        if np.any(self.link_inertia_kgm2 <= 0.0):
            raise ParameterError("DHArmSpec.link_inertia_kgm2 must be > 0")

    def transforms(self, q_rad: NDArray[np.float64]) -> list[NDArray[np.float64]]:
        """``T_{i-1,i}`` of the six rows at joint positions ``q_rad`` [rad], each (4, 4)."""
        out = []
        for q, a, d, alpha in zip(q_rad, self.dh_a_m, self.dh_d_m, self.dh_alpha_rad, strict=True):
            cq, sq, ca, sa = math.cos(q), math.sin(q), math.cos(alpha), math.sin(alpha)
            out.append(
                np.array(
                    [
                        [cq, -sq * ca, sq * sa, a * cq],
                        [sq, cq * ca, -cq * sa, a * sq],
                        [0.0, sa, ca, d],
                        [0.0, 0.0, 0.0, 1.0],
                    ]
                )
            )
        return out


#: Any arm the cell can carry.
ArmModel = ArmSpec | DHArmSpec


def dh_flange_pose(
    arm: DHArmSpec, q_rad: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Forward kinematics: ``(p_base_flange [m] (3,), R_base_flange (3, 3))`` of DH frame 6.

    For a UR this is the TCP pose the controller reports (``actual_TCP_pose``, the pendant's
    Move tab) with a zero TCP offset.

    Raises:
        ParameterError: ``q_rad`` is not 6 finite joint angles.
    """
    q = np.asarray(q_rad, dtype=float)
    if q.shape != (6,) or not np.isfinite(q).all():
        raise ParameterError(f"q_rad must be 6 finite joint angles [rad], got {q_rad!r}")
    T = np.eye(4)
    for Ti in arm.transforms(q):
        T = T @ Ti
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


#: The arms a cell can be built with, by name (``sim://?arm=NAME``).
ARMS: Final[Mapping[str, Callable[[], ArmModel]]] = {"c4": c4_like_arm, "ur5e": ur5e_arm}
