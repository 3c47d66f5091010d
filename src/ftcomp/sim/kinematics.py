"""The simulator's truth of the sensor frame's motion (to check kinematics computed from poses),
of what an accelerometer in the sensor reads, and of the tool's inertia tensor (to score its
identification).

MuJoCo's ``mj_objectAcceleration`` gives a body's acceleration *minus* gravity (what an
accelerometer feels); :func:`true_sensor_motion` adds gravity back, so that its linear
acceleration is the sensor origin's true acceleration, as :func:`ftcomp.kinematics.sensor_motion`
computes from poses.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from ftcomp.sim.cell import SimCell
from ftcomp.sim.scene import NAMES

__all__ = ["true_sensor_motion", "true_specific_force", "true_tool_inertia"]


def true_sensor_motion(cell: SimCell) -> NDArray[np.float64]:
    """``[a (m/s^2), w (rad/s), alpha (rad/s^2)]`` of the sensor frame, sensor axes, (9,).

    Of the state the cell's latest :meth:`~SimCell.pose` reports (MuJoCo computes both before
    integrating a step).
    """
    m, d = cell.model, cell.data
    site = m.site(NAMES["ft_site"]).id
    acc = np.empty(6)
    vel = np.empty(6)
    mujoco.mj_objectAcceleration(m, d, mujoco.mjtObj.mjOBJ_SITE, site, acc, 1)
    mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, site, vel, 1)
    R_world_sensor = d.site_xmat[site].reshape(3, 3)
    accel = acc[3:] + R_world_sensor.T @ m.opt.gravity
    return np.concatenate([accel, vel[:3], acc[:3]])


def true_specific_force(cell: SimCell) -> NDArray[np.float64]:
    """What an accelerometer at the sensor frame's origin, on its axes, reads [m/s^2], (3,):
    the specific force, the origin's acceleration less gravity (of the same state as
    :func:`true_sensor_motion`)."""
    m, d = cell.model, cell.data
    acc = np.empty(6)
    site = m.site(NAMES["ft_site"]).id
    mujoco.mj_objectAcceleration(m, d, mujoco.mjtObj.mjOBJ_SITE, site, acc, 1)
    return acc[3:].copy()


def true_tool_inertia(cell: SimCell) -> NDArray[np.float64]:
    """Inertia tensor of everything below the sensing element (sensing end, gripper, a held
    load) about its centre of gravity, sensor axes [kg m^2], (3, 3)."""
    m, d = cell.model, cell.data
    names = [NAMES["sensing_end"]]
    if cell.config.gripper:
        names.append(NAMES["gripper"])
    if cell.holding:
        names.append(NAMES["load"])
    ids = [m.body(n).id for n in names]
    mass = m.body_mass[ids]
    com = mass @ d.xipos[ids] / mass.sum()
    site = m.site(NAMES["ft_site"]).id
    R_world_sensor = d.site_xmat[site].reshape(3, 3)
    total = np.zeros((3, 3))
    for body, mb in zip(ids, mass, strict=True):
        R = d.ximat[body].reshape(3, 3)  # principal axes of the body's inertia, world
        r = d.xipos[body] - com
        total += R @ np.diag(m.body_inertia[body]) @ R.T + mb * (r @ r * np.eye(3) - np.outer(r, r))
    return np.asarray(R_world_sensor.T @ total @ R_world_sensor)
