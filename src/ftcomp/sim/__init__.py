"""The simulated robot cell on MuJoCo: an arm (the six-axis C4-like arm, or any serial arm given
by its DH table: :func:`ur5e_arm`, the seven-joint :func:`fr3_arm`; or from a URDF:
:func:`urdf_arm`), a wrist F/T sensor, a
gripper, loads, and a table with a sponge pad or a book; :class:`CellConfig` describes one.

:class:`SimCell` implements :class:`ftcomp.hardware.protocols.Robot`; ``cell.sensor`` implements
:class:`ftcomp.hardware.protocols.WrenchSensor`; ``sim://`` URIs open them (:mod:`.backend`).
The MuJoCo model is built in code (:func:`build_mjcf`); nothing is downloaded.

A placement run, as the admittance experiment drives it (1 kHz)::

    import numpy as np
    from ftcomp.sim import LoadSpec, SceneConfig, SimCell, SpongeSpec

    cell = SimCell(
        SceneConfig(surface="sponge", load=LoadSpec(0.5), sponge=SpongeSpec(1500.0, 15.0)),
        seed=1,
    )
    cell.hold_above_surface(clearance_m=0.02)  # tool down, load bottom 20 mm above the pad
    cell.grasp()                               # the load is now in the gripper (weld on)
    cell.settle()
    while cell.time() < 5.0:
        sample = cell.sensor.read()            # WrenchSample: t_ns [ns], wrench_sensor (6,)
        pose = cell.pose()                     # PoseSample: the sensor frame in the base frame
        cell.command_twist(np.array([0, 0, -0.005, 0, 0, 0]))  # base frame [m/s, rad/s]
        cell.wait_cycle()                      # 1 ms of physics
        contact_N = cell.true_contact_force_N()  # what the pad pushes up on the load
    cell.stop()
    cell.release()

Static calibration data at the paper's nine poses (Table 1), recorded through the hardware
protocols as on a real arm, with the truth behind them::

    from ftcomp.paper import paper_poses
    from ftcomp.sim import record_with_truth
    cell = SimCell(SceneConfig(), seed=0)
    samples, truth = record_with_truth(cell, paper_poses(), samples_per_pose=500)
    samples.wrench_sensor, samples.R_base_sensor, samples.pose, samples.t  # truth: GravityModel
"""

# ruff: noqa: E402  (MuJoCo is checked before the modules that import it)
from __future__ import annotations

from ftcomp.extras import require_extra

require_extra("sim", "the simulated cell (ftcomp sim, sim://)")

from ftcomp.sim.arm import (
    ARM_JOINT_NAMES,
    ARMS,
    ArmSpec,
    ChainArmSpec,
    DHArmSpec,
    c4_like_arm,
    chain_flange_pose,
    dh_flange_pose,
    fr3_arm,
    ur5e_arm,
)
from ftcomp.sim.cell import COLLECTION_POSITION_BASE_M, HOME_Q_RAD, SimCell
from ftcomp.sim.cell_config import CellConfig
from ftcomp.sim.collect import record_with_truth
from ftcomp.sim.ik import DifferentialIK, dls_joint_velocity, solve_pose
from ftcomp.sim.placement_cell import SimPlacementCell
from ftcomp.sim.scene import NAMES, SceneConfig, build_mjcf
from ftcomp.sim.sensor import SensorSpec, SimWrenchSensor
from ftcomp.sim.surfaces import SURFACE_KINDS, BookSpec, SpongeSpec, SurfaceKind, TableSpec
from ftcomp.sim.tool import LoadSpec, ToolSpec, paper_tool, table4_loads
from ftcomp.sim.urdf_arm import urdf_arm

__all__ = [
    "ARMS",
    "ARM_JOINT_NAMES",
    "COLLECTION_POSITION_BASE_M",
    "HOME_Q_RAD",
    "NAMES",
    "SURFACE_KINDS",
    "ArmSpec",
    "BookSpec",
    "CellConfig",
    "ChainArmSpec",
    "DHArmSpec",
    "DifferentialIK",
    "LoadSpec",
    "SceneConfig",
    "SensorSpec",
    "SimCell",
    "SimPlacementCell",
    "SimWrenchSensor",
    "SpongeSpec",
    "SurfaceKind",
    "TableSpec",
    "ToolSpec",
    "build_mjcf",
    "c4_like_arm",
    "chain_flange_pose",
    "dh_flange_pose",
    "dls_joint_velocity",
    "fr3_arm",
    "paper_tool",
    "record_with_truth",
    "solve_pose",
    "table4_loads",
    "ur5e_arm",
    "urdf_arm",
]
