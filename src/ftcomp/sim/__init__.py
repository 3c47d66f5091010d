"""The simulated robot cell on MuJoCo: a six-axis arm, a wrist F/T sensor, a gripper, loads,
and a table with a sponge pad or a book.

:class:`SimCell` implements :class:`ftcomp.interfaces.Robot`; ``cell.sensor`` implements
:class:`ftcomp.interfaces.WrenchSensor`. The MuJoCo model is built in code
(:func:`build_mjcf`); nothing is downloaded.

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
        sample = cell.sensor.read()            # WrenchSample: t [s], wrench_sensor (6,)
        p, R = cell.sensor_pose()              # base frame
        cell.command_twist(np.array([0, 0, -0.005, 0, 0, 0]))  # base frame [m/s, rad/s]
        cell.wait_cycle()                      # 1 ms of physics
        contact_N = cell.true_contact_force_N()  # what the pad pushes up on the load
    cell.stop()
    cell.release()

Static calibration data at the paper's nine poses (Table 1)::

    from ftcomp.sim import collect_static_samples, paper_poses
    cell = SimCell(SceneConfig(), seed=0)
    data = collect_static_samples(cell, paper_poses(), samples_per_pose=500)
    data.wrench_sensor, data.rotations, data.pose, data.t, data.truth  # truth: GravityModel
"""

from __future__ import annotations

from ftcomp.sim.arm import ARM_JOINT_NAMES, ArmSpec, c4_like_arm
from ftcomp.sim.cell import HOME_Q_RAD, SimCell
from ftcomp.sim.collect import (
    COLLECTION_POSITION_BASE_M,
    PoseList,
    StaticCollection,
    collect_static_samples,
    paper_poses,
    read_pose_file,
)
from ftcomp.sim.ik import DifferentialIK, dls_joint_velocity, solve_pose
from ftcomp.sim.scene import NAMES, SceneConfig, build_mjcf
from ftcomp.sim.sensor import (
    PAPER_FORCE_BIAS_N,
    PAPER_TORQUE_BIAS_Nm,
    SensorSpec,
    SimWrenchSensor,
)
from ftcomp.sim.surfaces import SURFACE_KINDS, BookSpec, SpongeSpec, SurfaceKind, TableSpec
from ftcomp.sim.tool import (
    TABLE4_LOAD_WEIGHTS_N,
    LoadSpec,
    ToolSpec,
    paper_tool,
    table4_loads,
)

__all__ = [
    "ARM_JOINT_NAMES",
    "COLLECTION_POSITION_BASE_M",
    "HOME_Q_RAD",
    "NAMES",
    "PAPER_FORCE_BIAS_N",
    "SURFACE_KINDS",
    "TABLE4_LOAD_WEIGHTS_N",
    "ArmSpec",
    "BookSpec",
    "DifferentialIK",
    "LoadSpec",
    "PAPER_TORQUE_BIAS_Nm",
    "PoseList",
    "SceneConfig",
    "SensorSpec",
    "SimCell",
    "SimWrenchSensor",
    "SpongeSpec",
    "StaticCollection",
    "SurfaceKind",
    "TableSpec",
    "ToolSpec",
    "build_mjcf",
    "c4_like_arm",
    "collect_static_samples",
    "dls_joint_velocity",
    "paper_poses",
    "paper_tool",
    "read_pose_file",
    "solve_pose",
    "table4_loads",
]
