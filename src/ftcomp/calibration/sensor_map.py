"""A general linear sensor map: gain, crosstalk and mount misalignment beyond the paper's model.

The paper's model reads the tool's gravity through ``A(P) = [I; skew(P)]``: ``reading = bias +
A(P) g_s`` with ``g_s = R_base_sensor.T @ gravity_base``. A real sensor's calibration matrix is
off by a little (gain errors, crosstalk between channels, the sensor's axes not quite the
mount's), so here the map is ``A(P) + delta`` with ``delta`` a general (6, 3) matrix: its force
rows dimensionless (1e-2 is a 1 % gain or crosstalk), its torque rows in metres. ``delta`` has a
Gaussian prior centred on the physical model (``PRIOR_STD``), so with few poses it stays near
zero and cannot hurt; the fit (:mod:`.stochastic`, ``ftcomp calibrate --sensor-map linear``)
integrates it out for the marginal likelihood and reports, as a log Bayes factor against the
physical model, whether the data support it.

Parameters ``x = [theta (12), delta (18, row-major)]`` with ``theta`` as in :mod:`.methods`.
"""

from __future__ import annotations

from typing import Final

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.methods import joint_jacobian, predict_wrench

__all__ = ["MAP_PARAMETERS", "PRIOR_STD", "map_jacobian", "predict_mapped", "prior_precision"]

#: The map's prior standard deviation: force rows (dimensionless), torque rows [m].
PRIOR_STD: Final = (0.02, 0.002)
#: Parameters the map adds to the 12 of the tool model.
MAP_PARAMETERS: Final = 18


def predict_mapped(x: NDArray[np.float64], R: NDArray[np.float64]) -> NDArray[np.float64]:
    """The reading at orientations ``R`` (P, 3, 3): ``bias + (A(P) + delta) g_s``, (P, 6)."""
    out = predict_wrench(x[:12], R)
    if len(x) > 12:
        g_s = x[0:3] @ R  # (P, 3): R.T @ a per pose
        out = out + g_s @ x[12:30].reshape(6, 3).T
    return out


def map_jacobian(x: NDArray[np.float64], R: NDArray[np.float64]) -> NDArray[np.float64]:
    """``d reading / d x`` per pose, (P, 6, len(x)) (12 without the map, 30 with it)."""
    P = len(R)
    J12 = joint_jacobian(x[:12], R, np.zeros((P, 6)), np.ones((P, 6))).reshape(P, 6, 12)
    if len(x) == 12:
        return J12
    delta = x[12:30].reshape(6, 3)
    Rt = np.transpose(R, (0, 2, 1))
    J = np.zeros((P, 6, 30))
    J[:, :, :12] = J12
    J[:, :, 0:3] += delta @ Rt  # d (delta g_s) / d a
    g_s = x[0:3] @ R  # (P, 3)
    for row in range(6):
        J[:, row, 12 + 3 * row : 15 + 3 * row] = g_s
    return J


def prior_precision(n: int) -> NDArray[np.float64]:
    """The prior precision of each parameter, (n,): 0 for the tool model's 12 (flat), 1 / std^2
    for the map's."""
    out = np.zeros(n)
    if n > 12:
        force, torque = PRIOR_STD
        out[12:21] = 1.0 / force**2
        out[21:30] = 1.0 / torque**2
    return out
