"""The robot cell as MJCF, built in code: floor, tilted arm, F/T sensor, gripper, load, surfaces.

Frames: MuJoCo's world is the physical world (z up, gravity along -z). The arm's ``base`` body is
mounted with ``R_world_base = Rx(U) @ Ry(V)`` (paper Eq. 1), so a tilt changes where gravity points
in the base frame, exactly as a tilted mount does. The sensor frame is the site ``ft_site`` at the
origin of the ``sensing_end`` body, z along the tool axis away from the flange.

The arm is either the C4-like arm (:class:`~ftcomp.sim.arm.ArmSpec`) or an arm of N joints given
by its DH table (:class:`~ftcomp.sim.arm.DHArmSpec`: the UR5e, standard DH; the FR3, modified):
then the body of link ``i`` is DH frame ``i`` (standard: its joint turns about ``z_{i-1}``,
through frame ``i-1``'s origin; modified: about its own ``z``, through its origin), so MuJoCo's
forward kinematics is the DH product; the flange is ``linkN``, or a body ``flange`` in it placed
by the arm's flange row (:func:`flange_body_name`), and the sensor sits on the flange at
``SceneConfig.p_flange_sensor_m`` / ``rotvec_flange_sensor_rad``. An arm given by its joint
frames (:class:`~ftcomp.sim.arm.ChainArmSpec`, e.g. read from a URDF) is built the same way:
link ``i``'s body at joint ``i``'s frame, turning about its axis through its origin.

The arm comes first in the tree, so its joints are MuJoCo's degrees of freedom 0 .. N-1.
The subtree below the sensor is exactly ``sensing_end`` (+ ``gripper``); both are welded to their
parent (no joints, no actuators), so MuJoCo's force/torque sensors at ``ft_site`` measure their
weight plus whatever acts on them (contact, the grasp weld to a load).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Final

import numpy as np
from scipy.spatial.transform import Rotation

from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import ParameterError
from ftcomp.frames import R_world_base_from_tilt
from ftcomp.sim.arm import ArmModel, ArmSpec, ChainArmSpec, DHArmSpec
from ftcomp.sim.surfaces import SURFACE_KINDS, BookSpec, SpongeSpec, SurfaceKind, TableSpec
from ftcomp.sim.tool import LoadSpec, ToolSpec

__all__ = [
    "MAX_SENSOR_OFFSET_M",
    "MAX_TILT_DEG",
    "NAMES",
    "SceneConfig",
    "build_mjcf",
    "flange_body_name",
]

#: MJCF names the cell relies on ("flange": a six-joint arm's without a flange row; any arm's:
#: :func:`flange_body_name`).
NAMES: Final = {
    "base": "base",
    "flange": "link6",
    "sensing_end": "sensing_end",
    "gripper": "gripper",
    "load": "load",
    "load_geom": "load_geom",
    "grasp_weld": "grasp",
    "ft_site": "ft_site",
    "grasp_site": "grasp_site",
    "force_sensor": "ft_force",
    "torque_sensor": "ft_torque",
    "sponge_joint": "sponge_slide",
    "sponge_plate": "sponge_plate",
    "book": "book",
    "table": "table",
}

#: The base's mounting tilt must be below this about either axis [deg].
MAX_TILT_DEG: Final = 30.0
#: The sensor frame's origin lies within this of the flange's on every axis [m].
MAX_SENSOR_OFFSET_M: Final = 0.5
#: Mass [kg] and half-height [m] of the sensor's fixed housing (above the sensing end).
_HOUSING_MASS_KG: Final = 0.25
_HOUSING_HALF_HEIGHT_M: Final = 0.015
#: Contact settings of stiff surfaces: time constant 8 ms, critically damped: the stiffest that
#: stays chatter-free with the 1 ms step and the stiff position-servoed arm (2-6 ms chatter).
_STIFF_SOLREF: Final = "0.008 1"
_STIFF_SOLIMP: Final = "0.95 0.99 0.001"


@dataclass(frozen=True)
class SceneConfig:
    """Everything that changes the MuJoCo model of the cell.

    Attributes:
        tilt_U_rad: base mounting tilt about the world x axis [rad] (paper Eq. 1).
        tilt_V_rad: base mounting tilt about the tilted y axis [rad].
        gripper: whether the gripper is mounted (False: bare sensing end, as the paper's
            no-gripper calibration).
        load: the graspable load in the scene, or None.
        surface: ``"none"``, ``"sponge"`` or ``"book"`` on the table (the table is always there).
        arm, tool, table, sponge, book: the parts' specifications (``arm``: the C4-like
            :class:`~ftcomp.sim.arm.ArmSpec`, a :class:`~ftcomp.sim.arm.DHArmSpec` or a
            :class:`~ftcomp.sim.arm.ChainArmSpec`).
        p_flange_sensor_m: with a DH or chain arm, the sensor frame's origin in the flange frame
            [m], (3,); the sensor's housing lies behind it. Zero with the C4-like arm (its
            sensor sits on its flange, z along the flange's x).
        rotvec_flange_sensor_rad: with a DH or chain arm, the sensor frame's axes in the flange
            frame, a rotation vector [rad], (3,).
        timestep_s: physics step [s]; the cell's control period must be a whole multiple.
        noslip_iterations: MuJoCo no-slip solver iterations (stops a held contact from creeping).
        integrator: MuJoCo's integrator. ``"implicitfast"`` (default) is the most stable with
            stiff contacts, but its sensors report forces of the explicit acceleration, not the
            one the arm performs (the implicit damping of the servos changes it); ``"Euler"``
            keeps the F/T sensor consistent with the motion, as dynamic experiments need.
    """

    tilt_U_rad: float = 0.0
    tilt_V_rad: float = 0.0
    gripper: bool = True
    load: LoadSpec | None = None
    surface: SurfaceKind = "none"
    arm: ArmModel = field(default_factory=ArmSpec)
    tool: ToolSpec = field(default_factory=ToolSpec)
    table: TableSpec = field(default_factory=TableSpec)
    sponge: SpongeSpec = field(default_factory=SpongeSpec)
    book: BookSpec = field(default_factory=BookSpec)
    timestep_s: float = 0.001
    noslip_iterations: int = 2
    integrator: str = "implicitfast"
    p_flange_sensor_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotvec_flange_sensor_rad: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        for name in ("p_flange_sensor_m", "rotvec_flange_sensor_rad"):
            value = tuple(float(v) for v in getattr(self, name))
            if len(value) != 3 or not all(math.isfinite(v) for v in value):
                raise ParameterError(f"SceneConfig.{name} must be 3 finite numbers")
            if any(value) and isinstance(self.arm, ArmSpec):
                raise ParameterError(
                    f"SceneConfig.{name} needs an arm given by a DH table or its joint frames"
                )
        if max(map(abs, self.p_flange_sensor_m)) > MAX_SENSOR_OFFSET_M:
            raise ParameterError(
                f"SceneConfig.p_flange_sensor_m must be within {MAX_SENSOR_OFFSET_M:g} m per axis"
            )
        if math.hypot(*self.rotvec_flange_sensor_rad) > math.pi:
            raise ParameterError("SceneConfig.rotvec_flange_sensor_rad must have norm <= pi")
        for name in ("tilt_U_rad", "tilt_V_rad"):
            value = getattr(self, name)
            if not math.isfinite(value) or abs(value) >= math.radians(MAX_TILT_DEG):
                raise ParameterError(
                    f"SceneConfig.{name} must be within +-{MAX_TILT_DEG:g} deg, got {value}"
                )
        if self.surface not in SURFACE_KINDS:
            raise ParameterError(
                f"unknown surface {self.surface!r}; valid: {', '.join(SURFACE_KINDS)}"
            )
        if self.load is not None and not self.gripper:
            raise ParameterError("a load needs the gripper (SceneConfig.gripper=True)")
        if not math.isfinite(self.timestep_s) or not 0.0 < self.timestep_s <= 0.002:
            raise ParameterError(f"timestep_s must be in (0, 0.002] s, got {self.timestep_s}")
        if self.integrator not in ("implicitfast", "implicit", "Euler", "RK4"):
            raise ParameterError(f"unknown integrator {self.integrator!r}")
        if self.noslip_iterations < 0:
            raise ParameterError(f"noslip_iterations must be >= 0, got {self.noslip_iterations}")

    @property
    def R_world_base(self) -> np.ndarray:
        """The base's mounting rotation ``Rx(U) @ Ry(V)``, shape (3, 3)."""
        return R_world_base_from_tilt(self.tilt_U_rad, self.tilt_V_rad)

    @property
    def surface_top_height_m(self) -> float:
        """World height of the top of the placement surface (table top if none) [m]."""
        top = self.table.top_height_m
        if self.surface == "sponge":
            return top + self.sponge.thickness_m
        if self.surface == "book":
            return top + self.book.thickness_m
        return top


def _f(values: object) -> str:
    return " ".join(f"{float(v):.17g}" for v in np.ravel(np.asarray(values, dtype=float)))


def _wxyz(rotation: Rotation) -> str:
    x, y, z, w = rotation.as_quat()
    return _f([w, x, y, z])


def _box_inertia(mass: float, half: np.ndarray) -> np.ndarray:
    a, b, c = (2.0 * half) ** 2
    return mass / 12.0 * np.array([b + c, a + c, a + b])


_ARM_GEOM: Final = 'contype="0" conaffinity="0" rgba="0.85 0.85 0.9 1"'


def flange_body_name(arm: ArmModel) -> str:
    """The MJCF body of the arm's tool flange: ``linkN``, or ``flange`` with a flange row."""
    if (isinstance(arm, DHArmSpec) and arm.has_flange_row) or (
        isinstance(arm, ChainArmSpec) and arm.has_flange_offset
    ):
        return "flange"
    return f"link{arm.n_joints}"


def _joint_xml(arm: ArmModel, i: int, axis: str, pos: str = "0 0 0") -> str:
    lo, hi = arm.joint_lower_rad[i], arm.joint_upper_rad[i]
    return (
        f'<joint name="{arm.joint_names[i]}" pos="{pos}" axis="{axis}" range="{_f([lo, hi])}" '
        f'armature="{arm.armature_kgm2[i]:.12g}"/>'
    )


def _inertial_xml(arm: DHArmSpec | ChainArmSpec, i: int) -> str:
    inertia = arm.link_inertia_kgm2[i]
    if inertia.ndim == 1:
        moments = f'diaginertia="{_f(inertia)}"'
    else:  # MuJoCo's order: xx yy zz xy xz yz
        moments = f'fullinertia="{_f([inertia[j, k] for j, k in _FULL_INERTIA_ORDER])}"'
    return f"""<inertial pos="{_f(arm.link_com_m[i])}" mass="{arm.link_masses_kg[i]:.17g}"
                    {moments}/>"""


_FULL_INERTIA_ORDER: Final = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def _dh_arm_xml(arm: DHArmSpec, tool_xml: str) -> str:
    """Link ``i``'s body at DH frame ``i``, placed in frame ``i-1`` as its row puts it at q = 0.

    Standard: at ``Tz(d) Tx(a) Rx(alpha)``, its joint about ``z_{i-1}`` through frame ``i-1``'s
    origin, both given in frame ``i``: the axis ``Rx(alpha)^T e_z`` and the point
    ``-Rx(alpha)^T (a, 0, d)``. Modified: at ``Rx(alpha) Tx(a) Tz(d)``, its joint about its own
    z through its origin. A flange row adds a body ``flange`` in the last link, the tool in it.
    """
    xml = tool_xml
    if arm.has_flange_row:
        T = arm.flange_transform()
        quat = _wxyz(Rotation.from_matrix(T[:3, :3]))
        xml = f"""
        <body name="flange" pos="{_f(T[:3, 3])}" quat="{quat}">{xml}
        </body>"""
    for i in reversed(range(arm.n_joints)):
        a, d, alpha = arm.dh_a_m[i], arm.dh_d_m[i], arm.dh_alpha_rad[i]
        ca, sa = math.cos(alpha), math.sin(alpha)
        quat = _wxyz(Rotation.from_rotvec([alpha, 0.0, 0.0]))
        if arm.convention == "standard":
            joint_pos = np.array([-a, -sa * d, -ca * d])
            xml = f"""
        <body name="link{i + 1}" pos="{_f([a, 0.0, d])}" quat="{quat}">
          {_joint_xml(arm, i, _f([0.0, sa, ca]), _f(joint_pos))}
          {_inertial_xml(arm, i)}
          <geom type="capsule" fromto="{_f(joint_pos)} 0 0 0" size="0.045" {_ARM_GEOM}/>{xml}
        </body>"""
            continue
        # The parent frame's origin, seen from this one: -Rx(alpha)^T (a, -sa d, ca d).
        parent = _f([-a, 0.0, -d])
        geom = (
            f'<geom type="capsule" fromto="{parent} 0 0 0" size="0.045" {_ARM_GEOM}/>'
            if math.hypot(a, d) > 1e-6
            else f'<geom type="sphere" size="0.045" {_ARM_GEOM}/>'
        )
        xml = f"""
        <body name="link{i + 1}" pos="{_f([a, -sa * d, ca * d])}" quat="{quat}">
          {_joint_xml(arm, i, "0 0 1")}
          {_inertial_xml(arm, i)}
          {geom}{xml}
        </body>"""
    return xml


def _chain_arm_xml(arm: ChainArmSpec, tool_xml: str) -> str:
    """Link ``i``'s body at joint ``i``'s frame, its joint about its axis through its origin;
    the tool in a body ``flange`` when the flange sits off link N's frame."""
    xml = tool_xml
    if arm.has_flange_offset:
        quat = _wxyz(Rotation.from_matrix(arm.R_link_flange))
        xml = f"""
        <body name="flange" pos="{_f(arm.p_link_flange_m)}" quat="{quat}">{xml}
        </body>"""
    for i in reversed(range(arm.n_joints)):
        p = arm.p_parent_joint_m[i]
        quat = _wxyz(Rotation.from_matrix(arm.R_parent_joint[i]))
        # The parent frame's origin, seen from this one.
        parent = _f(-arm.R_parent_joint[i].T @ p)
        geom = (
            f'<geom type="capsule" fromto="{parent} 0 0 0" size="0.045" {_ARM_GEOM}/>'
            if np.linalg.norm(p) > 1e-6
            else f'<geom type="sphere" size="0.045" {_ARM_GEOM}/>'
        )
        xml = f"""
        <body name="link{i + 1}" pos="{_f(p)}" quat="{quat}">
          {_joint_xml(arm, i, _f(arm.joint_axis[i]))}
          {_inertial_xml(arm, i)}
          {geom}{xml}
        </body>"""
    return xml


def _arm_xml(arm: ArmModel, tool_xml: str) -> str:
    if isinstance(arm, DHArmSpec):
        return _dh_arm_xml(arm, tool_xml)
    if isinstance(arm, ChainArmSpec):
        return _chain_arm_xml(arm, tool_xml)
    m = arm.link_masses_kg
    arm_geom = _ARM_GEOM

    def joint(i: int, axis: str) -> str:
        return _joint_xml(arm, i, axis)

    h, s, u, e, f, w = (
        arm.base_height_m,
        arm.shoulder_offset_m,
        arm.upper_arm_m,
        arm.elbow_offset_m,
        arm.forearm_m,
        arm.wrist_to_flange_m,
    )
    return f"""
      <body name="link1">
        {joint(0, "0 0 1")}
        <inertial pos="0 0 {h / 2:.6g}" mass="{m[0]:.6g}" diaginertia="0.2 0.2 0.1"/>
        <geom type="capsule" fromto="0 0 0.05 0 0 {h:.6g}" size="0.07" {arm_geom}/>
        <body name="link2" pos="{s:.6g} 0 {h:.6g}">
          {joint(1, "0 1 0")}
          <inertial pos="0 0 {u / 2:.6g}" mass="{m[1]:.6g}" diaginertia="0.1 0.1 0.02"/>
          <geom type="capsule" fromto="0 0 0 0 0 {u:.6g}" size="0.055" {arm_geom}/>
          <body name="link3" pos="0 0 {u:.6g}">
            {joint(2, "0 1 0")}
            <inertial pos="0.05 0 {e:.6g}" mass="{m[2]:.6g}" diaginertia="0.02 0.03 0.03"/>
            <geom type="capsule" fromto="0 0 0 0.1 0 {e:.6g}" size="0.05" {arm_geom}/>
            <body name="link4" pos="0 0 {e:.6g}">
              {joint(3, "1 0 0")}
              <inertial pos="{f / 2:.6g} 0 0" mass="{m[3]:.6g}" diaginertia="0.005 0.02 0.02"/>
              <geom type="capsule" fromto="0.1 0 0 {f - 0.04:.6g} 0 0" size="0.04" {arm_geom}/>
              <body name="link5" pos="{f:.6g} 0 0">
                {joint(4, "0 1 0")}
                <inertial pos="0.02 0 0" mass="{m[4]:.6g}" diaginertia="0.002 0.002 0.002"/>
                <geom type="cylinder" fromto="0 -0.04 0 0 0.04 0" size="0.04" {arm_geom}/>
                <body name="link6" pos="{w:.6g} 0 0">
                  {joint(5, "1 0 0")}
                  <inertial pos="-0.01 0 0" mass="{m[5]:.6g}" diaginertia="5e-4 5e-4 5e-4"/>
                  <geom type="cylinder" fromto="-0.02 0 0 0 0 0" size="0.035" {arm_geom}/>
                  {tool_xml}
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>"""


def _tool_xml(config: SceneConfig) -> str:
    tool = config.tool
    g = STANDARD_GRAVITY_MPS2
    se_mass = tool.sensing_end_weight_N / g
    grey = 'contype="0" conaffinity="0" rgba="0.3 0.3 0.35 1"'
    gripper = ""
    if config.gripper:
        gr_mass = tool.gripper_weight_N / g
        fl = tool.finger_length_m
        z0 = 0.02
        gripper = f"""
            <body name="gripper">
              <inertial pos="{_f(tool.gripper_cog_m)}" mass="{gr_mass:.17g}"
                        diaginertia="6e-4 6e-4 3e-4"/>
              <geom type="box" pos="0 0 {z0 + 0.015:.6g}" size="0.04 0.025 0.015" {grey}/>
              <geom type="box" pos="0.035 0 {z0 + 0.03 + fl / 2:.6g}"
                    size="0.005 0.012 {fl / 2:.6g}" {grey}/>
              <geom type="box" pos="-0.035 0 {z0 + 0.03 + fl / 2:.6g}"
                    size="0.005 0.012 {fl / 2:.6g}" {grey}/>
              <site name="grasp_site" pos="{_f(tool.grasp_point_m)}" size="0.005"/>
            </body>"""
    hh = _HOUSING_HALF_HEIGHT_M
    if not isinstance(config.arm, ArmSpec):
        # The sensor frame where the config puts it, its housing just behind it.
        R_flange_sensor = Rotation.from_rotvec(config.rotvec_flange_sensor_rad)
        housing_pos = np.asarray(config.p_flange_sensor_m) - R_flange_sensor.apply([0, 0, 2 * hh])
    else:
        # Sensor frame = flange frame turned so that its z is the flange's x (the tool axis).
        R_flange_sensor = Rotation.from_euler("y", 90.0, degrees=True)
        housing_pos = np.zeros(3)
    return f"""
          <body name="sensor_housing" pos="{_f(housing_pos)}" quat="{_wxyz(R_flange_sensor)}">
            <inertial pos="0 0 {hh:.6g}" mass="{_HOUSING_MASS_KG:.6g}"
                      diaginertia="1e-4 1e-4 1e-4"/>
            <geom type="cylinder" pos="0 0 {hh:.6g}" size="0.04 {hh:.6g}"
                  contype="0" conaffinity="0" rgba="0.2 0.4 0.8 1"/>
            <body name="sensing_end" pos="0 0 {2 * hh:.6g}">
              <inertial pos="{_f(tool.sensing_end_cog_m)}" mass="{se_mass:.17g}"
                        diaginertia="5e-5 5e-5 8e-5"/>
              <geom type="cylinder" pos="0 0 0.005" size="0.04 0.005"
                    contype="0" conaffinity="0" rgba="0.2 0.5 0.9 1"/>
              <site name="ft_site" size="0.006"/>{gripper}
            </body>
          </body>"""


def _surface_xml(config: SceneConfig) -> str:
    table = config.table
    cx, cy = table.center_xy_m
    top = table.top_height_m
    hx, hy = table.half_size_xy_m
    surf = f'contype="2" conaffinity="1" solref="{_STIFF_SOLREF}" solimp="{_STIFF_SOLIMP}"'
    # Touch sites: a thin box over each top face; MuJoCo sums the normal contact forces there.
    xml = f"""
    <geom name="table" type="box" pos="{cx:.6g} {cy:.6g} {top / 2:.6g}"
          size="{hx:.6g} {hy:.6g} {top / 2:.6g}" rgba="0.6 0.45 0.3 1" {surf}/>
    <site name="table_touch" type="box" pos="{cx:.6g} {cy:.6g} {top:.6g}"
          size="{hx + 0.01:.6g} {hy + 0.01:.6g} 0.01" rgba="0 0 0 0"/>"""
    if config.surface == "book":
        b = config.book
        xml += f"""
    <geom name="book" type="box" pos="{cx:.6g} {cy:.6g} {top + b.thickness_m / 2:.6g}"
          size="{_f(b.half_size_xy_m)} {b.thickness_m / 2:.6g}" rgba="0.7 0.1 0.1 1" {surf}/>
    <site name="book_touch" type="box" pos="{cx:.6g} {cy:.6g} {top + b.thickness_m:.6g}"
          size="{_f(np.add(b.half_size_xy_m, 0.01))} 0.01" rgba="0 0 0 0"/>"""
    elif config.surface == "sponge":
        s = config.sponge
        plate_half = 0.002
        sx, sy = s.half_size_xy_m
        plate_z = top + s.thickness_m - plate_half
        plate_inertia = _box_inertia(s.plate_mass_kg, np.array([sx, sy, plate_half]))
        shear = "".join(
            f"""
      <joint name="sponge_shear_{axis}" type="slide" axis="{direction}" range="-0.005 0.005"
             stiffness="{s.shear_stiffness_N_per_m:.12g}" damping="{s.damping_N_s_per_m:.12g}"/>"""
            for axis, direction in (("x", "1 0 0"), ("y", "0 1 0"))
            if math.isfinite(s.shear_stiffness_N_per_m)
        )
        xml += f"""
    <geom name="sponge_pad" type="box" pos="{cx:.6g} {cy:.6g} {top + s.thickness_m / 2:.6g}"
          size="{sx:.6g} {sy:.6g} {s.thickness_m / 2:.6g}" contype="0" conaffinity="0"
          rgba="0.95 0.85 0.2 0.6"/>
    <body name="sponge_plate" pos="{cx:.6g} {cy:.6g} {plate_z:.6g}" gravcomp="1">
      <joint name="sponge_slide" type="slide" axis="0 0 1"
             range="{-0.9 * s.thickness_m:.6g} 0.001"
             stiffness="{s.stiffness_N_per_m:.12g}" damping="{s.damping_N_s_per_m:.12g}"/>{shear}
      <inertial pos="0 0 0" mass="{s.plate_mass_kg:.12g}" diaginertia="{_f(plate_inertia)}"/>
      <geom name="sponge_top" type="box" size="{sx:.6g} {sy:.6g} {plate_half:.6g}"
            rgba="0.95 0.85 0.2 1" {surf}/>
      <site name="sponge_touch" type="box" pos="0 0 {plate_half:.6g}"
            size="{sx + 0.01:.6g} {sy + 0.01:.6g} 0.01" rgba="0 0 0 0"/>
    </body>"""
    return xml


def _load_xml(config: SceneConfig) -> str:
    load = config.load
    if load is None:
        return ""
    half = load.half_size_m
    inertia = _box_inertia(load.mass_kg, half)
    # Parked on the floor beside the robot until grasped.
    return f"""
    <body name="load" pos="0 -0.6 {half[2]:.6g}">
      <freejoint name="load_free"/>
      <inertial pos="0 0 0" mass="{load.mass_kg:.17g}" diaginertia="{_f(inertia)}"/>
      <geom name="load_geom" type="box" size="{_f(half)}" contype="1" conaffinity="3"
            friction="1 0.01 0.001" solref="{_STIFF_SOLREF}" solimp="{_STIFF_SOLIMP}"
            rgba="0.2 0.7 0.3 1"/>
    </body>"""


def _touch_sites(surface: SurfaceKind) -> tuple[str, ...]:
    """Touch sensors after the F/T sensor's 6 values: the table's, then the surface's."""
    if surface == "none":
        return ("table_touch",)
    return ("table_touch", f"{surface}_touch")


def build_mjcf(config: SceneConfig) -> str:
    """The MJCF text of the cell described by ``config``."""
    R_world_base = Rotation.from_matrix(config.R_world_base)
    arm = config.arm
    actuators = "\n".join(
        f'    <position name="{name}_servo" joint="{name}" kp="{arm.kp[i]:.12g}" '
        f'kv="{arm.kv[i]:.12g}"/>'
        for i, name in enumerate(arm.joint_names)
    )
    equality = ""
    if config.load is not None:
        equality = """
  <equality>
    <weld name="grasp" body1="gripper" body2="load" active="false"
          solref="0.002 1" solimp="0.99 0.999 0.0001"/>
  </equality>"""
    touch = "".join(
        f'\n    <touch name="{site}" site="{site}"/>' for site in _touch_sites(config.surface)
    )
    return f"""<mujoco model="ftcomp_cell">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{config.timestep_s:.12g}" integrator="{config.integrator}" cone="elliptic"
          impratio="10" noslip_iterations="{config.noslip_iterations}" tolerance="1e-6"
          gravity="0 0 {-STANDARD_GRAVITY_MPS2:.12g}"/>
  <worldbody>
    <light pos="0 -1 2" dir="0 0.5 -1"/>
    <geom name="floor" type="plane" size="2 2 0.1" contype="2" conaffinity="1"
          rgba="0.9 0.9 0.9 1"/>
    <body name="base" quat="{_wxyz(R_world_base)}">
      <geom type="cylinder" pos="0 0 0.04" size="0.1 0.04" contype="0" conaffinity="0"/>
      {_arm_xml(arm, _tool_xml(config))}
    </body>{_surface_xml(config)}{_load_xml(config)}
  </worldbody>{equality}
  <actuator>
{actuators}
  </actuator>
  <sensor>
    <force name="ft_force" site="ft_site"/>
    <torque name="ft_torque" site="ft_site"/>{touch}
  </sensor>
</mujoco>
"""
