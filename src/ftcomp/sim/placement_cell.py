"""The MuJoCo cell as a placement cell: a grasped load held above a sponge or a book.

The scene has the same tilted base as the calibration scene (the paper's identified tilt by
default), so a calibration identified on one holds on the other. The cell can identify its own
tool first (the empty gripper at the paper's nine poses, through the hardware protocols, exactly
as ``ftcomp record`` does on a real arm) and then grasp the load: the placement then runs on the
*identified* parameters, and the simulator's truth is used only to score the result.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ftcomp import paper
from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import Robot, WrenchSensor
from ftcomp.model import GravityModel
from ftcomp.sim.arm import ArmModel, ArmSpec
from ftcomp.sim.cell import COLLECTION_POSITION_BASE_M, SimCell
from ftcomp.sim.scene import SceneConfig
from ftcomp.sim.sensor import SensorSpec
from ftcomp.sim.tool import LoadSpec

if TYPE_CHECKING:
    from ftcomp.calibration_record import Calibration

__all__ = ["PLACEMENT_SURFACES", "SimPlacementCell"]

#: The surfaces a load can be placed on.
PLACEMENT_SURFACES = ("sponge", "book")


class SimPlacementCell:
    """The MuJoCo cell (:class:`~ftcomp.sim.cell.SimCell`) as a placement cell.

    Args:
        surface: ``"sponge"`` or ``"book"``.
        load_kg: mass of the grasped load [kg].
        seed: sensor-noise seed.
        tilt_deg: the base's mounting tilt (U, V) [deg]; the paper's by default.
        sensor_spec: the sensor model (default: the paper's).
        identify_samples_per_pose: if given, first identify the empty gripper on this cell at
            the paper's nine poses with this many readings each (joint method); the result is
            :attr:`identified`.
        arm: the arm (default: the C4-like arm; :func:`~ftcomp.sim.arm.ur5e_arm`, the twin's).

    Attributes:
        cell: the underlying :class:`~ftcomp.sim.cell.SimCell`.
        identified: the calibration identified on this cell, or None.
        true_tool_model: the simulator's truth for the tool *without* the load (what a
            calibration of the empty gripper should find), taken before grasping: for scoring
            only.
    """

    def __init__(
        self,
        surface: str,
        load_kg: float = 0.5,
        *,
        seed: int | None = 0,
        tilt_deg: tuple[float, float] = paper.TILT_DEG,
        sensor_spec: SensorSpec | None = None,
        identify_samples_per_pose: int | None = None,
        arm: ArmModel | None = None,
    ) -> None:
        if surface not in PLACEMENT_SURFACES:
            raise ParameterError(
                f"surface must be 'sponge' or 'book', got {surface!r}", field="surface"
            )
        if not (math.isfinite(load_kg) and load_kg > 0.0):
            raise ParameterError(f"load_kg must be > 0, got {load_kg}", field="load_kg")
        if seed is not None and not (isinstance(seed, int) and seed >= 0):
            raise ParameterError(f"seed must be an integer >= 0, got {seed!r}", field="seed")
        load = LoadSpec(load_kg)
        self._weight_N = load.weight_N
        scene = SceneConfig(
            tilt_U_rad=math.radians(tilt_deg[0]),
            tilt_V_rad=math.radians(tilt_deg[1]),
            load=load,
            surface=surface,  # type: ignore[arg-type]
            arm=arm if arm is not None else ArmSpec(),
        )
        self.cell = SimCell(scene, sensor_spec, seed=seed)
        self.identified: Calibration | None = None
        if identify_samples_per_pose is not None:
            self.identified = self._identify(identify_samples_per_pose)
        self.cell.hold_above_surface(0.02, 0.5)
        self.true_tool_model: GravityModel = self.cell.true_gravity_model()
        self.cell.grasp()

    def _identify(self, samples_per_pose: int) -> Calibration:
        from ftcomp.calibration.collect import record_static
        from ftcomp.calibration.identify import calibrate

        samples = record_static(
            self.cell,
            self.cell.sensor,
            paper.paper_poses(),
            samples_per_pose,
            position_base_m=COLLECTION_POSITION_BASE_M,
            move_duration_s=0.6,
        )
        return calibrate(samples, method="joint", leave_one_out=False)

    @property
    def robot(self) -> Robot:
        """The arm."""
        return self.cell

    @property
    def sensor(self) -> WrenchSensor:
        """The wrist F/T sensor."""
        return self.cell.sensor

    def move_to_clearance(self, clearance_m: float) -> None:
        """Blocking move holding the load ``clearance_m`` [m] above the surface."""
        self.cell.hold_above_surface(clearance_m, 0.3)

    def true_contact_force_N(self) -> float:
        """The simulator's vertical contact force on the load [N]."""
        return self.cell.true_contact_force_N()

    def true_contact_wrench_N(self) -> NDArray[np.float64]:
        """The wrench the surface exerts on the load, base frame, six axes: force [N] and
        torque about the TCP (the sensor origin) [N*m], shape (6,)."""
        return self.cell.true_contact_wrench_base(self.cell.sensor_pose()[0])

    def load_weight_N(self) -> float:
        """The load's weight [N]."""
        return self._weight_N

    def release(self) -> None:
        """Open the gripper."""
        self.cell.release()
