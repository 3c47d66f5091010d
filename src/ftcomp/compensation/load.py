"""Weighing a grasped load from compensated readings (paper Eq. 23, and beyond it).

With the tool's calibration, whatever the compensated wrench still holds while the arm touches
nothing is the grasped load: its weight is ``|F'|`` (Eq. 23), and over several orientations its
centre of gravity follows too (:func:`estimate_load`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.model import skew

__all__ = ["LoadEstimate", "estimate_load", "load_weight_N"]


@dataclass(frozen=True)
class LoadEstimate:
    """A grasped load weighed from compensated readings.

    Attributes:
        weight_N: the load's weight [N].
        mass_kg: its mass at standard gravity [kg].
        center_of_gravity_m: its centre of gravity in the sensor frame [m], shape (3,); with
            readings at a single orientation only the part across gravity is observable, and
            the component along gravity is reported as 0 (``cog_fully_observed`` is False).
        cog_fully_observed: whether the readings span two or more gravity directions.
    """

    weight_N: float
    mass_kg: float
    center_of_gravity_m: NDArray[np.float64]
    cog_fully_observed: bool


def load_weight_N(
    compensator: GravityCompensator, wrench_sensor: ArrayLike, R_base_sensor: ArrayLike
) -> NDArray[np.float64]:
    """Weight of a grasped load, ``|F'|`` (Eq. 23) [N]: a float array of shape () or (N,)."""
    contact = compensator.compensate(wrench_sensor, R_base_sensor)
    return np.asarray(np.linalg.norm(contact[..., :3], axis=-1))


def estimate_load(
    compensator: GravityCompensator, wrench_sensor: ArrayLike, R_base_sensor: ArrayLike
) -> LoadEstimate:
    """Weigh a grasped load and locate its centre of gravity (beyond the paper).

    With the load's gravity along the calibrated gravity direction ``u`` (base frame), the
    compensated force at pose ``i`` is ``w R_i.T u`` and the torque ``c x F'_i``; ``w`` and
    ``c`` follow by least squares over all readings.

    Args:
        wrench_sensor: raw readings holding the load and touching nothing, (N, 6) or (6,).
        R_base_sensor: their orientations, (N, 3, 3) or (3, 3).
    """
    w = np.asarray(wrench_sensor, dtype=float).reshape(-1, 6)
    R = np.asarray(R_base_sensor, dtype=float).reshape(-1, 3, 3)
    contact = compensator.compensate(w, R)
    force, torque = contact[:, :3], contact[:, 3:]
    if compensator.gravity_dir_base is None:
        weight = float(np.mean(np.linalg.norm(force, axis=1)))
        directions = force / np.maximum(np.linalg.norm(force, axis=1, keepdims=True), 1e-12)
    else:
        directions = compensator.gravity_dir_base @ R  # unit gravity direction in sensor frame
        weight = float(np.mean(np.sum(directions * force, axis=1)))
    X = -np.concatenate([skew(f) for f in force])  # c x f = -skew(f) c
    cog, *_, sv = np.linalg.lstsq(X, torque.ravel(), rcond=None)
    spread = np.linalg.svd(directions - directions.mean(axis=0), compute_uv=False)
    return LoadEstimate(
        weight_N=weight,
        mass_kg=weight / STANDARD_GRAVITY_MPS2,
        center_of_gravity_m=np.asarray(cog, dtype=float),
        cog_fully_observed=bool(len(R) > 1 and spread[0] > 1e-3 and sv[-1] > 1e-9),
    )
