"""What the simulated gripper holds and touches: grasping, the contact forces, and the truth.

:class:`GripperAndSurfaces` is a part of :class:`ftcomp.sim.cell.SimCell` (a mixin over the
cell's MuJoCo model and state), kept apart from the cell's motion and sensing: grasping and
releasing the load, the true contact forces of the surfaces, the placement pose, and the
gravity model a calibration should find. Positions here speak of the *world* (z up, level).
"""

from __future__ import annotations

import math
from typing import Final

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.errors import ParameterError, SimulationError
from ftcomp.model import GravityModel
from ftcomp.sim.scene import SceneConfig
from ftcomp.sim.sensor import SensorSpec

__all__ = ["SURFACE_GEOMS", "GripperAndSurfaces"]

#: The geoms a load can be placed on (their contacts count as the surface's).
SURFACE_GEOMS: Final = ("floor", "table", "book", "sponge_top")


class GripperAndSurfaces:
    """Grasp, contact and truth queries of the simulated cell (see the module docstring)."""

    # Set by SimCell.__init__.
    _model: mujoco.MjModel
    _data: mujoco.MjData
    _config: SceneConfig
    _sensor_spec: SensorSpec
    _site: int
    _sensing_end: int
    _gripper: int
    _load: int
    _load_geom: int
    _weld: int
    _load_qadr: int
    _load_dadr: int
    _surface_set: frozenset[int]  # the geom ids of SURFACE_GEOMS in the model
    _contact_buffer: NDArray[np.float64]  # mj_contactForce's output, (6,)
    _sponge_qadr: int
    _R_world_base: NDArray[np.float64]
    _gravity: float

    def move_pose(
        self,
        p_base_sensor: ArrayLike,
        R_base_sensor: ArrayLike,
        duration_s: float,
        *,
        label: str = "",
    ) -> None:
        """Blocking move of the sensor frame (the cell's)."""
        raise NotImplementedError

    @property
    def holding(self) -> bool:
        """Whether the gripper holds the load (grasp weld active)."""
        return self._weld >= 0 and bool(self._data.eq_active[self._weld])

    def true_gravity_model(self) -> GravityModel:
        """The truth calibration should find now: what hangs below the sensor, its bias, tilt.

        Weight and centre of gravity of the sensing end, the gripper and the held load, from
        the MuJoCo model's masses and the current body positions; bias from the sensor spec.
        """
        d = self._data
        bodies = [self._sensing_end]
        if self._gripper >= 0:
            bodies.append(self._gripper)
        if self.holding:
            bodies.append(self._load)
        mass = self._model.body_mass[bodies]
        total = float(mass.sum())
        com_world = mass @ d.xipos[bodies] / total
        R_ws = d.site_xmat[self._site].reshape(3, 3)
        cog = R_ws.T @ (com_world - d.site_xpos[self._site])
        return GravityModel(
            total * self._gravity,
            cog,
            self._sensor_spec.force_bias_N,
            self._sensor_spec.torque_bias_Nm,
            tilt_U_rad=self._config.tilt_U_rad,
            tilt_V_rad=self._config.tilt_V_rad,
        )

    # ----------------------------------------------------------------- grasping and placement
    def _require_load(self, what: str) -> None:
        if self._load < 0:
            raise SimulationError(f"cannot {what}: the scene has no load (SceneConfig.load)")

    def grasp(self) -> None:
        """Take the load into the gripper: put it at the grasp point and switch the weld on.

        The load's centre sits at ``ToolSpec.grasp_point_m``, its axes along the sensor's.
        Grasp in free air (the load is moved there, whatever is in the way).
        """
        self._require_load("grasp")
        m, d = self._model, self._data
        R_ws = d.site_xmat[self._site].reshape(3, 3)
        pos = d.site_xpos[self._site] + R_ws @ self._config.tool.grasp_point_m
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, d.site_xmat[self._site])
        a = self._load_qadr
        d.qpos[a : a + 3] = pos
        d.qpos[a + 3 : a + 7] = quat
        d.qvel[self._load_dadr : self._load_dadr + 6] = 0.0
        # Weld data: anchor (3), relative pose of the load in the gripper frame (pos 3, quat 4).
        # The gripper frame is the sensor frame.
        m.eq_data[self._weld, 0:3] = 0.0
        m.eq_data[self._weld, 3:6] = self._config.tool.grasp_point_m
        m.eq_data[self._weld, 6:10] = (1.0, 0.0, 0.0, 0.0)
        d.eq_active[self._weld] = 1
        mujoco.mj_forward(m, d)

    def release(self) -> None:
        """Open the gripper: switch the grasp weld off (the load is then free)."""
        self._require_load("release")
        self._data.eq_active[self._weld] = 0

    def true_contact_force_world_N(self) -> NDArray[np.float64]:
        """Total force the surfaces (table, book, sponge, floor) exert on the load [N], world."""
        return self._contact_wrench_world(np.zeros(3))[:3]

    def true_contact_wrench_base(self, point_base_m: ArrayLike) -> NDArray[np.float64]:
        """The wrench the surfaces (table, book, sponge, floor) exert on the load, base frame:
        force [N] and torque about ``point_base_m`` [N*m] (e.g. the TCP), shape (6,).

        All six axes: every contact's force and its torsional and rolling torques, with the
        moment of each force about the point (the contact's position in the base frame).
        """
        point_world = self._R_world_base @ np.asarray(point_base_m, dtype=float)
        wrench = self._contact_wrench_world(point_world)
        R_base_world = self._R_world_base.T
        return np.concatenate([R_base_world @ wrench[:3], R_base_world @ wrench[3:]])

    def _contact_wrench_world(self, point_world: NDArray[np.float64]) -> NDArray[np.float64]:
        """The surfaces' wrench on the load, world frame, torque about ``point_world``.

        On Python floats, contact by contact: a load on the sponge or the book has four, and
        numpy's cost per call on arrays that small was most of the time (100-130 us a call
        alone on this machine, three times that in the twin's loop under a client: its largest
        part in contact; now 15 us, the same numbers).
        """
        wrench = [0.0] * 6
        n = self._data.ncon
        if self._load_geom < 0 or n == 0:
            return np.zeros(6)
        m, d, load, surfaces = self._model, self._data, self._load_geom, self._surface_set
        px, py, pz = point_world.tolist()
        local = self._contact_buffer
        contact = d.contact
        geoms, frames, positions = (
            contact.geom[:n].tolist(),
            contact.frame[:n].tolist(),
            contact.pos[:n].tolist(),
        )
        for i, ((g1, g2), frame, pos) in enumerate(zip(geoms, frames, positions, strict=True)):
            # MuJoCo's contact force acts on geom2 from geom1: on the load when it is geom2.
            if g2 == load and g1 in surfaces:
                sign = 1.0
            elif g1 == load and g2 in surfaces:
                sign = -1.0
            else:
                continue
            mujoco.mj_contactForce(m, d, i, local)
            f0, f1, f2, t0, t1, t2 = local.tolist()
            # the frame's rows are the contact's axes in the world
            ax, ay, az, bx, by, bz, cx, cy, cz = frame
            fx = sign * (f0 * ax + f1 * bx + f2 * cx)
            fy = sign * (f0 * ay + f1 * by + f2 * cy)
            fz = sign * (f0 * az + f1 * bz + f2 * cz)
            lx, ly, lz = pos[0] - px, pos[1] - py, pos[2] - pz
            wrench[0] += fx
            wrench[1] += fy
            wrench[2] += fz
            wrench[3] += ly * fz - lz * fy + sign * (t0 * ax + t1 * bx + t2 * cx)
            wrench[4] += lz * fx - lx * fz + sign * (t0 * ay + t1 * by + t2 * cy)
            wrench[5] += lx * fy - ly * fx + sign * (t0 * az + t1 * bz + t2 * cz)
        return np.array(wrench)

    def true_contact_force_N(self) -> float:
        """Vertical force the table and the surface on it push up on the load [N] (>= 0).

        The sum of MuJoCo touch sensors over the top faces (normal contact force; the tops
        are level, so it is the vertical force). Cheap enough for every control cycle.
        """
        return float(self._data.sensordata[6:].sum())

    def surface_compression_m(self) -> float:
        """How far the sponge is pressed in [m] (0 for other surfaces)."""
        if self._sponge_qadr < 0:
            return 0.0
        return float(-self._data.qpos[self._sponge_qadr])

    def surface_top_height_m(self) -> float:
        """World height of the uncompressed placement surface's top [m]."""
        return self._config.surface_top_height_m

    def placement_pose(self, clearance_m: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The sensor pose (base frame) holding the load ``clearance_m`` above the surface.

        Tool pointing straight down (sensor z along world -z, sensor x along world x), above
        the table's placement spot; the load's bottom ``clearance_m`` [m] above the surface top.
        """
        self._require_load("compute a placement pose")
        if not math.isfinite(clearance_m):
            raise ParameterError(f"clearance_m must be finite, got {clearance_m}")
        load = self._config.load
        assert load is not None  # _require_load checked it
        reach_down = float(self._config.tool.grasp_point_m[2] + load.half_size_m[2])
        cx, cy = self._config.table.center_xy_m
        p_world = np.array([cx, cy, self.surface_top_height_m() + clearance_m + reach_down])
        R_world_sensor = np.diag([1.0, -1.0, -1.0])
        Rwb = self._R_world_base
        return Rwb.T @ p_world, Rwb.T @ R_world_sensor

    def hold_above_surface(self, clearance_m: float, duration_s: float = 1.0) -> None:
        """Move so the load would be ``clearance_m`` [m] above the surface, then settle."""
        p, R = self.placement_pose(clearance_m)
        self.move_pose(p, R, duration_s, label=f"placement pose {clearance_m * 1000:.1f} mm up")
