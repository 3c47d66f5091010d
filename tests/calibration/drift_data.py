"""Synthetic readings for the drift, re-bias and mount tests: the paper's tool, known truth."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp import paper
from ftcomp.model import GravityModel
from ftcomp.samples import Samples

#: The paper's sensor noise per reading (one resolution count): force [N], torque [N*m].
NOISE_6 = np.repeat([0.125, 0.003], 3)


def truth() -> GravityModel:
    """The paper's tool and bias (Table 4 values) with a level base."""
    return GravityModel(
        paper.TOOL_WEIGHT_N,
        np.array(paper.CENTER_OF_GRAVITY_M),
        np.array(paper.FORCE_BIAS_N),
        np.array(paper.TORQUE_BIAS_Nm),
        tilt_U_rad=0.0,
        tilt_V_rad=0.0,
    )


def tilted_poses(rng: np.random.Generator, n: int, max_tilt_deg: float = 80.0) -> NDArray:
    """``n`` orientations: the tool tilted up to ``max_tilt_deg`` from hanging down, any yaw."""
    down = Rotation.from_euler("x", 180, degrees=True)
    tilt = np.radians(rng.uniform(10.0, max_tilt_deg, n))
    azimuth = rng.uniform(0, 2 * np.pi, n)
    axis = np.column_stack([np.cos(azimuth), np.sin(azimuth), np.zeros(n)])
    spin = Rotation.from_euler("z", rng.uniform(-180, 180, (n, 1)), degrees=True)
    return np.asarray((Rotation.from_rotvec(axis * tilt[:, None]) * down * spin).as_matrix())


def readings(
    rng: np.random.Generator,
    model: GravityModel,
    R_sensor: NDArray,
    per_pose: int,
    *,
    t0_s: float = 0.0,
    pose_period_s: float = 10.0,
    rate_hz: float = 100.0,
    drift: NDArray | None = None,
    R_recorded: NDArray | None = None,
    noise_6: NDArray = NOISE_6,
) -> Samples:
    """``per_pose`` readings at each pose, pose k starting at ``t0 + k * pose_period``;
    ``drift(t)`` (a function of t [s] giving (N, 6)) added to the bias; orientations written
    as ``R_recorded`` (default: the sensor's)."""
    P = len(R_sensor)
    pose = np.repeat(np.arange(P), per_pose)
    t = t0_s + pose * pose_period_s + np.tile(np.arange(per_pose) / rate_hz, P)
    w = model.predict(R_sensor[pose]) + rng.standard_normal((len(t), 6)) * noise_6
    if drift is not None:
        w = w + drift(t)
    R_out = R_sensor if R_recorded is None else R_recorded
    return Samples(
        w,
        R_out[pose],
        "quaternion",
        pose=np.array([f"p{k}" for k in pose]),
        t=t,
        source="synthetic",
    )
