"""A simulated recording whose sensor bias follows the sensor's temperature (the idea of
``bench/bench_temperature.py``, as readings with a ``temperature_C`` channel): shared by the
library's and the command's tests of ``--bias-drift temperature``."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ftcomp.model import GravityModel
from ftcomp.samples import Samples

#: The tool and the bias at 25 degC (a 0.8 kg tool 4 cm off axis, a small base tilt).
TOOL = GravityModel(
    0.8 * 9.80665,
    np.array([0.04, -0.01, 0.06]),
    np.array([0.5, -0.3, 1.2]),
    np.array([0.02, 0.01, -0.03]),
    tilt_U_rad=0.002,
    tilt_V_rad=-0.003,
)
T0_C = 25.0
#: The bias's slopes: [N/degC]*3 + [N*m/degC]*3 (Bota-like sizes, as the bench's).
SLOPES = np.array([0.08, -0.05, 0.12, 0.004, -0.003, 0.002])
#: Each reading's noise: [N]*3 + [N*m]*3.
NOISE = np.array([0.05] * 3 + [0.002] * 3)


def recording(
    seed: int,
    poses: int = 16,
    readings: int = 20,
    *,
    follows: bool = True,
    with_temperature: bool = True,
    low_C: float = 22.0,
    high_C: float = 28.0,
) -> Samples:
    """Readings at ``poses`` random orientations, 5 s apart, ``readings`` each (10 ms apart).

    The sensor's temperature jumps from pose to pose (a fan switching, a motor heating the
    wrist): evenly spread over ``low_C .. high_C`` in a random order, read to 0.01 degC. A bias
    that follows it does not follow time, so a drift in time cannot stand in for it; the
    extremes are visited, so held-out readings between them lie inside the calibrated range.
    ``follows``: the bias moves with the temperature by :data:`SLOPES` (else it is constant and
    the temperature a bystander).
    """
    rng = np.random.default_rng(seed)
    R_pose = Rotation.random(poses, random_state=rng).as_matrix()
    T_pose = rng.permutation(np.linspace(low_C, high_C, poses))
    R = np.repeat(R_pose, readings, axis=0)
    T_true = np.repeat(T_pose, readings)
    t = (5.0 * np.arange(poses)[:, None] + 0.01 * np.arange(readings)[None]).ravel()
    wrench = TOOL.predict(R) + rng.normal(size=(len(R), 6)) * NOISE
    if follows:
        wrench += np.multiply.outer(T_true - T0_C, SLOPES)
    extras = {"temperature_C": T_true + rng.normal(0.0, 0.01, len(R))} if with_temperature else {}
    return Samples(
        wrench,
        R,
        "quaternion",
        pose=np.repeat([f"p{k}" for k in range(poses)], readings),
        t=t,
        extras=extras,
        source=f"temperature recording {seed}",
    )


def floor_N(readings: int = 20) -> float:
    """The noise of one pose mean's force per axis [N]: what no model can beat."""
    return float(NOISE[0] / np.sqrt(readings))
