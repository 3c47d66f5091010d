"""The simulated arm: a six-axis arm close to the EPSON C4-A901S (about 0.9 m reach).

The geometry is a classic anthropomorphic arm with a spherical wrist. In the zero configuration
the upper arm points up (base z), the forearm and the flange point forward (base x). Lengths and
joint ranges follow the C4-A901S data sheet roughly; masses are plausible, not measured (they do
not enter the sensor reading: only the bodies below the sensor do).

Every joint is position-servoed, as on an industrial controller: a MuJoCo ``position`` actuator
(proportional gain ``kp`` [N*m/rad], derivative gain ``kv`` [N*m*s/rad]) plus a feedforward of the
arm's gravity and Coriolis torques and of ``kv`` times the commanded joint velocity, applied by
:class:`ftcomp.sim.cell.SimCell` every physics step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Final

import numpy as np
from numpy.typing import NDArray

from ftcomp.arrays import freeze_field
from ftcomp.errors import ParameterError

__all__ = ["ARM_JOINT_NAMES", "ArmSpec", "c4_like_arm"]

#: MJCF names of the six arm joints, base to flange.
ARM_JOINT_NAMES: Final = ("j1", "j2", "j3", "j4", "j5", "j6")


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
        for name in (
            "link_masses_kg",
            "joint_lower_rad",
            "joint_upper_rad",
            "kp",
            "kv",
            "armature_kgm2",
        ):
            freeze_field(self, name, (6,), finite=True)
        if np.any(self.joint_lower_rad >= self.joint_upper_rad):
            raise ParameterError("ArmSpec joint_lower_rad must be below joint_upper_rad")
        if np.any(self.link_masses_kg <= 0.0) or np.any(self.kp <= 0.0) or np.any(self.kv < 0.0):
            raise ParameterError("ArmSpec masses and kp must be > 0, kv >= 0")

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
