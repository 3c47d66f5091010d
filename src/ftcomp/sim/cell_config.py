"""What a simulated cell is built from, as one typed record: :class:`CellConfig`.

The ``sim://`` backend parses its URI into a :class:`CellConfig`
(:func:`ftcomp.sim.backend.cell_config_from_uri`), the twin and ``ftcomp sim collect`` build one
from their options; :meth:`CellConfig.open_cell` builds the cell. Each field's range, unit and help
is declared once, on the field (:func:`ftcomp.config_fields.param`, from the constants
:data:`MAX_LOAD_KG`, :data:`MAX_CLEARANCE_MM`, ...), and checked in
:meth:`CellConfig.__post_init__`; a :class:`~ftcomp.errors.ParameterError` names the field (its
``fields``), not a URI option or a flag, and the caller adds where the value came from (the CLI
builds its options from the same declarations: :func:`ftcomp.config_fields.spec_of`).

Units are those a user types (degrees, millimetres, percent, per minute), named in each field;
:meth:`CellConfig.scene` and :meth:`CellConfig.sensor_spec` turn them into the SI records the
cell is built from (:class:`~ftcomp.sim.scene.SceneConfig`,
:class:`~ftcomp.sim.sensor.SensorSpec`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Final

import numpy as np

from ftcomp.config_fields import check_fields, param
from ftcomp.errors import ParameterError
from ftcomp.sim.arm import ArmModel, c4_like_arm
from ftcomp.sim.cell import COLLECTION_POSITION_BASE_M, SimCell
from ftcomp.sim.scene import MAX_SENSOR_OFFSET_M, MAX_TILT_DEG, SceneConfig
from ftcomp.sim.sensor import SensorSpec
from ftcomp.sim.surfaces import SURFACE_KINDS, SurfaceKind
from ftcomp.sim.tool import LoadSpec

__all__ = [
    "MAX_CLEARANCE_MM",
    "MAX_GAIN_ERROR_PERCENT",
    "MAX_LOAD_KG",
    "MAX_REALISTIC_DRIFT",
    "MAX_SENSOR_OFFSET_M",
    "MAX_TILT_DEG",
    "CellConfig",
]

#: Largest load the simulated arm takes [kg] (the C4-A901S is rated for 4 kg).
MAX_LOAD_KG: Final = 4.0
#: Largest start clearance of a held load above the surface [mm].
MAX_CLEARANCE_MM: Final = 100.0
#: The sensor's gain error must be below this on every axis [%].
MAX_GAIN_ERROR_PERCENT: Final = 50.0
#: Largest scale of a real sensor's drift (:meth:`SensorSpec.realistic_drift`).
MAX_REALISTIC_DRIFT: Final = 100.0
#: The twin's and ``sim://``'s start pose of the sensor when it sits off the flange: tool axis
#: (sensor z) straight down, sensor x along base x.
_TOOL_DOWN: Final = np.diag([1.0, -1.0, -1.0])
#: Durations of the start moves [s]: to the start pose, to 20 mm above the surface (empty),
#: then down to the clearance (holding the load).
_START_MOVE_S: Final = 0.5
#: A joint start (``start_q_deg``) moves there at about this speed [rad/s] (a UR's moveJ
#: default), at least :data:`_START_MOVE_S`.
_START_JOINT_SPEED_RAD_S: Final = 1.05
_LOWER_MOVE_S: Final = 0.3
#: A load is grasped at least this far above the surface [m] (then lowered to the clearance).
_GRASP_CLEARANCE_M: Final = 0.02


@dataclass(frozen=True)
class CellConfig:
    """A simulated cell: arm, mount, tool, load, surface and the sensor's realism.

    Attributes:
        arm: the arm (:func:`~ftcomp.sim.arm.c4_like_arm` by default, or any
            :class:`~ftcomp.sim.arm.ArmSpec` / :class:`~ftcomp.sim.arm.DHArmSpec`, e.g.
            :func:`~ftcomp.sim.arm.ur5e_arm`, :func:`~ftcomp.sim.arm.fr3_arm`).
        tilt_deg: the base's mounting tilt ``(U, V)`` [deg], each within
            +-:data:`MAX_TILT_DEG` (paper Eq. 1; ``sim://`` defaults to the paper's).
        gripper: the paper's gripper on the sensor (False: the bare sensing end).
        load_kg: a graspable load of this mass [kg] in (0, :data:`MAX_LOAD_KG`], or None.
        grasp: start with the load in the gripper (needs ``load_kg``).
        surface: what lies on the table: ``"none"``, ``"sponge"`` or ``"book"``.
        clearance_mm: start holding the grasped load this far above the surface [mm], in
            [0, :data:`MAX_CLEARANCE_MM`] (needs ``grasp`` and a surface), or None: the load
            is grasped where the arm starts.
        p_flange_sensor_m: the sensor frame's origin in the flange frame [m], (3,) (an arm
            given by a DH table only; the TCP offset of a UR). The cell then starts with the
            sensor at the start pose, tool down, wherever the offset puts it.
        rotvec_flange_sensor_rad: the sensor frame's axes in the flange frame, a rotation
            vector [rad], (3,).
        seed: seeds the sensor noise (>= 0): the same config gives the same readings.
        gain_error_percent: the sensor's gain error per axis [%], 6 values (or one for all),
            each within +-:data:`MAX_GAIN_ERROR_PERCENT`.
        drift_N_per_min: force-bias drift rate, x y z [N/min].
        drift_Nm_per_min: torque-bias drift rate, x y z [N*m/min].
        drift_walk_N: force-bias random walk, its standard deviation after one minute [N]
            (>= 0); the torque walk gets this times the torque/force noise ratio.
        realistic_drift: a real sensor's drift (wander and warm-up,
            :meth:`~ftcomp.sim.sensor.SensorSpec.realistic_drift`) times this, in
            [0, :data:`MAX_REALISTIC_DRIFT`]; 0: none.
        start_q_deg: start the arm at these joint positions [deg], one per joint, within the
            joint ranges, instead of at the start pose; None: the start pose.

    Raises:
        ParameterError: a value out of its range or a combination that cannot be built,
            naming the field.
    """

    arm: ArmModel = field(default_factory=c4_like_arm)
    tilt_deg: tuple[float, float] = param(
        (0.0, 0.0),
        length=2,
        gt=-MAX_TILT_DEG,
        lt=MAX_TILT_DEG,
        unit="deg",
        help="the base's mounting tilt (U, V), paper Eq. 1",
    )
    gripper: bool = True
    load_kg: float | None = param(
        None, gt=0.0, le=MAX_LOAD_KG, unit="kg", optional=True, help="a graspable load's mass"
    )
    grasp: bool = False
    surface: SurfaceKind = param("none", choices=SURFACE_KINDS, help="what lies on the table")
    clearance_mm: float | None = param(
        None,
        ge=0.0,
        le=MAX_CLEARANCE_MM,
        unit="mm",
        optional=True,
        help="start holding the grasped load this far above the surface",
    )
    p_flange_sensor_m: tuple[float, float, float] = param(
        (0.0, 0.0, 0.0),
        length=3,
        ge=-MAX_SENSOR_OFFSET_M,
        le=MAX_SENSOR_OFFSET_M,
        unit="m",
        help="the sensor frame's origin in the flange frame",
    )
    rotvec_flange_sensor_rad: tuple[float, float, float] = param(
        (0.0, 0.0, 0.0),
        length=3,
        ge=-math.pi,
        le=math.pi,
        unit="rad",
        help="the sensor frame's axes in the flange frame, a rotation vector",
    )
    seed: int = param(0, integer=True, ge=0, help="the sensor noise's seed")
    gain_error_percent: float | tuple[float, ...] = param(
        0.0,
        length=6,
        gt=-MAX_GAIN_ERROR_PERCENT,
        lt=MAX_GAIN_ERROR_PERCENT,
        unit="%",
        help="the sensor's gain error per axis",
    )
    drift_N_per_min: tuple[float, float, float] = param(
        (0.0, 0.0, 0.0), length=3, unit="N/min", help="the force bias's drift rate, x y z"
    )
    drift_Nm_per_min: tuple[float, float, float] = param(
        (0.0, 0.0, 0.0), length=3, unit="N*m/min", help="the torque bias's drift rate, x y z"
    )
    drift_walk_N: float = param(
        0.0, ge=0.0, unit="N", help="the force bias's random walk, its std after one minute"
    )
    realistic_drift: float = param(
        0.0,
        ge=0.0,
        le=MAX_REALISTIC_DRIFT,
        help="a real sensor's drift (wander and warm-up) times this, 0: none",
    )
    #: As many values as the arm has joints: checked by ``_check_start_q``, not by a param.
    start_q_deg: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        gain = self.gain_error_percent
        if isinstance(gain, int | float) and not isinstance(gain, bool):
            object.__setattr__(self, "gain_error_percent", (gain,) * 6)  # one for every axis
        check_fields(self)
        if self.load_kg is not None and not self.gripper:
            raise ParameterError("load_kg needs the gripper (gripper=True)", field="load_kg")
        if self.grasp and self.load_kg is None:
            raise ParameterError("grasp needs a load (load_kg)", field="grasp")
        if self.clearance_mm is not None and (not self.grasp or self.surface == "none"):
            raise ParameterError("clearance_mm needs grasp and a surface", field="clearance_mm")
        # (arm None: a copy made for a record of the fields, serve_twin's truth file)
        if self.start_q_deg is not None and self.arm is not None:
            self._check_start_q(self.start_q_deg)
        self.scene()  # the scene's own checks (the sensor offset needs a DH arm, ...) now

    def _check_start_q(self, q_deg: tuple[float, ...]) -> None:
        """``start_q_deg``: one finite value per joint, each within its range."""
        arm = self.arm
        n = len(arm.joint_names)
        if len(q_deg) != n or not all(math.isfinite(v) for v in q_deg):
            raise ParameterError(
                f"start_q_deg must be {n} finite joint positions [deg] (one per joint), "
                f"got {q_deg!r}",
                field="start_q_deg",
            )
        lower, upper = np.degrees(arm.joint_lower_rad), np.degrees(arm.joint_upper_rad)
        for j, v in enumerate(q_deg):
            if not lower[j] <= v <= upper[j]:
                raise ParameterError(
                    f"start_q_deg: joint {j + 1} at {v:g} deg is outside its range "
                    f"[{lower[j]:g}, {upper[j]:g}] deg",
                    field="start_q_deg",
                )

    @property
    def sensor_offset(self) -> bool:
        """Whether the sensor frame sits off the flange frame (a DH arm with a TCP offset)."""
        return any(self.p_flange_sensor_m) or any(self.rotvec_flange_sensor_rad)

    def scene(self) -> SceneConfig:
        """The MuJoCo scene this config describes (SI units)."""
        return SceneConfig(
            tilt_U_rad=math.radians(self.tilt_deg[0]),
            tilt_V_rad=math.radians(self.tilt_deg[1]),
            gripper=self.gripper,
            load=LoadSpec(self.load_kg) if self.load_kg is not None else None,
            surface=self.surface,
            arm=self.arm,
            p_flange_sensor_m=self.p_flange_sensor_m,
            rotvec_flange_sensor_rad=self.rotvec_flange_sensor_rad,
        )

    def sensor_spec(self) -> SensorSpec:
        """The wrist sensor's model: the paper's sensor with this gain error and bias drift."""
        base = (
            SensorSpec().realistic_drift(self.realistic_drift)
            if self.realistic_drift
            else SensorSpec()
        )
        walk = self.drift_walk_N
        walk_6 = np.repeat([walk, walk * base.torque_noise_std_Nm / base.force_noise_std_N], 3)
        return replace(
            base,
            gain_error_fraction=np.array(self.gain_error_percent) / 100.0,
            bias_drift_rate_per_s=np.array([*self.drift_N_per_min, *self.drift_Nm_per_min]) / 60.0,
            bias_walk_per_sqrt_s=walk_6 / math.sqrt(60.0),
        )

    def open_cell(self) -> SimCell:
        """A fresh cell as described, ready at its start: the arm at ``start_q_deg`` if given,
        else the sensor at the start pose (with an offset sensor), the load grasped if asked,
        held ``clearance_mm`` above the surface if given (grasped 20 mm up, empty on the way,
        then lowered).

        Raises:
            UnreachablePoseError: the arm cannot reach the start pose or the surface.
        """
        cell = SimCell(self.scene(), self.sensor_spec(), seed=self.seed)
        if self.start_q_deg is not None:
            q = np.radians(self.start_q_deg)
            way = float(np.max(np.abs(q - cell.q_command_rad)))
            cell.move_joints(q, max(_START_MOVE_S, way / _START_JOINT_SPEED_RAD_S))
        elif self.sensor_offset:
            # The sensor (the TCP) at the start pose whatever the offset: tool down in front.
            cell.move_pose(COLLECTION_POSITION_BASE_M, _TOOL_DOWN, _START_MOVE_S)
        if not self.grasp:
            return cell
        if self.clearance_mm is None:
            cell.grasp()
            return cell
        clearance_m = self.clearance_mm * 1e-3
        cell.hold_above_surface(max(clearance_m, _GRASP_CLEARANCE_M), _START_MOVE_S)
        cell.grasp()
        cell.hold_above_surface(clearance_m, _LOWER_MOVE_S)
        return cell
