"""Pose design: which orientations make the joint method's estimates most precise.

The joint method (:mod:`.methods`) is a weighted least-squares fit, so its parameter covariance
is the inverse of the Fisher information ``F = sum_i J_i^T J_i`` summed over the poses, ``J_i``
the pose's weighted Jacobian (6 x 12, analytic, the fit's own). ``F`` depends on the tool
(gravity ``a``, centre of gravity ``P``) and the noise, not on the readings, so a set of poses can
be judged before recording. :func:`design_poses` picks ``count`` orientations from a candidate
grid that maximise ``log det F`` (D-optimal: the smallest joint confidence region for all twelve
parameters): greedy additions, then Fedorov exchanges (swap a chosen pose for a candidate while
``det F`` grows) until none helps. Kept poses (``--keep``) stay in the design. A ``reachable``
check (the robot's inverse kinematics within joint limits) removes a chosen candidate the robot
cannot reach and the design is repeated. :func:`order_for_travel` then orders the poses to keep
the total rotation short (nearest neighbour from the first pose, then 2-opt).

Approximations: the information is evaluated at a nominal tool (the paper's by default), so
a very different tool gets a design that is good but not optimal for it; the candidate grid is
finite (``directions`` x ``spins``), and the exchange finds a local optimum.

``poses design`` keeps the spins about the sensor's axis within a half turn (``--max-spin-deg
90``): a full turn of spins wound the UR5e twin's wrist 3 to its 360 deg limit along
``record``'s moveLs at tilts beyond 35 deg; within the band, designs tilted up to 70 deg run
through (``tests/twin/test_design_on_ur5e.py``; at 80 deg one pose lies 18 deg from the wrist's
singularity and the arm does not settle on it), and the predicted standard errors grow by at
most 3 %.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Final

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp import paper
from ftcomp.calibration.methods import joint_jacobian
from ftcomp.errors import ParameterError
from ftcomp.frames import gravity_in_base

__all__ = [
    "MIN_POSES",
    "PARAMETER_NAMES",
    "candidate_orientations",
    "design_poses",
    "fisher_blocks",
    "nominal_theta",
    "order_for_travel",
    "predicted_std_errors",
    "tilt_from_down_rad",
]

#: Fewest poses that identify the twelve parameters (three distinct tilts; as ``calibrate``).
MIN_POSES: Final = 3
#: Named groups of the predicted standard errors.
PARAMETER_NAMES: Final = ("G", "F0", "M0", "P")
#: The paper's sensor noise per reading, force [N] x3 and torque [N*m] x3 (one resolution count).
PAPER_NOISE_6: Final = np.repeat([0.125, 0.003], 3)
_RIDGE: Final = 1e-9  # relative, keeps log det finite while a design has fewer than 3 poses


def nominal_theta(
    weight_N: float = paper.TOOL_WEIGHT_N,
    center_of_gravity_m: tuple[float, float, float] = paper.CENTER_OF_GRAVITY_M,
) -> NDArray[np.float64]:
    """``theta = [a, F0, M0, P]`` of a tool on a level base (the bias does not enter ``F``)."""
    a = gravity_in_base(weight_N, 0.0, 0.0)
    return np.concatenate([a, np.zeros(6), np.asarray(center_of_gravity_m, dtype=float)])


def tilt_from_down_rad(R_base_sensor: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angle between the sensor's z axis and straight down (base -z) [rad], shape (N,)."""
    return np.arccos(np.clip(-np.asarray(R_base_sensor)[..., 2, 2], -1.0, 1.0))


def candidate_orientations(
    max_tilt_deg: float = 180.0,
    *,
    directions: int = 400,
    spins: int = 12,
    max_spin_deg: float = 180.0,
) -> NDArray[np.float64]:
    """A grid of orientations: sensor z axes spread evenly (Fibonacci sphere) within
    ``max_tilt_deg`` of straight down, each with ``spins`` rotations about that axis.

    Args:
        max_tilt_deg: largest angle of the sensor's z axis from straight down [deg].
        directions: z axes on the whole sphere (those within the tilt are kept).
        spins: rotations about each axis.
        max_spin_deg: the spins lie within +-this of the orientation the shortest tilt from
            straight down gives [deg]: 180 (the default), a full turn evenly; below, evenly
            from -max_spin_deg to +max_spin_deg. A band of half a turn (90) costs the
            design little (gravity's direction in the sensor frame depends on the tilt's
            azimuth less the spin) and keeps an arm's last wrist joint from winding to its
            limit over a sequence of linear moves (``poses design``'s default).

    Returns:
        ``R_base_sensor``, shape (M, 3, 3).
    """
    if not 0.0 < max_tilt_deg <= 180.0:
        raise ParameterError(
            f"max_tilt_deg must be in (0, 180] deg, got {max_tilt_deg:g}", field="max_tilt_deg"
        )
    if not 0.0 < max_spin_deg <= 180.0:
        raise ParameterError(
            f"max_spin_deg must be in (0, 180] deg, got {max_spin_deg:g}", field="max_spin_deg"
        )
    if max_spin_deg >= 180.0 or spins == 1:
        spin_deg = 360.0 * np.arange(spins) / spins
    else:
        spin_deg = np.linspace(-max_spin_deg, max_spin_deg, spins)
    k = np.arange(directions) + 0.5
    z = 1.0 - 2.0 * k / directions  # cos of the angle from base +z
    r = np.sqrt(1.0 - z * z)
    phi = math.pi * (3.0 - math.sqrt(5.0)) * k
    axes = np.column_stack([r * np.cos(phi), r * np.sin(phi), z])
    axes = axes[np.arccos(np.clip(-axes[:, 2], -1, 1)) <= math.radians(max_tilt_deg) + 1e-12]
    if not len(axes):  # a very small cone: at least straight down and a ring at its edge
        t = math.radians(max_tilt_deg)
        ring = np.linspace(0, 2 * math.pi, 6, endpoint=False)
        edge = np.column_stack(
            [np.sin(t) * np.cos(ring), np.sin(t) * np.sin(ring), np.full(6, -np.cos(t))]
        )
        axes = np.vstack([[0.0, 0.0, -1.0], edge])
    # The rotation taking base -z to each axis (shortest arc), then spins about the axis.
    down = np.array([0.0, 0.0, -1.0])
    rotations = []
    flip = Rotation.from_euler("x", 180, degrees=True)  # sensor z straight down
    for axis in axes:
        cross = np.cross(down, axis)
        s, c = np.linalg.norm(cross), float(down @ axis)
        tilt = (
            Rotation.from_rotvec(cross / s * math.atan2(s, c))
            if s > 1e-12
            else Rotation.identity()
            if c > 0
            else Rotation.from_euler("y", 180, degrees=True)
        )
        for angle in spin_deg:
            spin = Rotation.from_euler("z", angle, degrees=True)
            rotations.append((tilt * flip * spin).as_matrix())
    return np.asarray(rotations)


def fisher_blocks(
    R_base_sensor: NDArray[np.float64],
    theta: NDArray[np.float64],
    *,
    noise_6: NDArray[np.float64] = PAPER_NOISE_6,
    readings_per_pose: int = 500,
) -> NDArray[np.float64]:
    """Each pose's Fisher information for the joint model, shape (M, 12, 12).

    ``J_i^T J_i`` with the joint fit's analytic Jacobian, weighted by the standard deviation of
    a pose mean (``noise_6 / sqrt(readings_per_pose)``).
    """
    R = np.asarray(R_base_sensor, dtype=float)
    sigma = np.broadcast_to(noise_6 / math.sqrt(readings_per_pose), (len(R), 6))
    J = joint_jacobian(theta, R, np.zeros((len(R), 6)), sigma).reshape(len(R), 6, 12)
    return np.einsum("mki,mkj->mij", J, J)


def _logdet(F: NDArray[np.float64]) -> NDArray[np.float64]:
    sign, value = np.linalg.slogdet(F)
    return np.where(sign > 0, value, -np.inf)


def _exchange(
    blocks: NDArray[np.float64], fixed: NDArray[np.float64], chosen: list[int], ridge: NDArray
) -> list[int]:
    """Fedorov exchange: swap a chosen candidate for the best other while ``log det`` grows."""
    total = fixed + blocks[chosen].sum(axis=0)
    best = float(_logdet(total + ridge))
    improved = True
    while improved:
        improved = False
        for slot in range(len(chosen)):
            without = total - blocks[chosen[slot]]
            scores = _logdet(without[None] + blocks + ridge)
            scores[[c for k, c in enumerate(chosen) if k != slot]] = -np.inf  # no repeats
            j = int(np.argmax(scores))
            if scores[j] > best + 1e-10 and j != chosen[slot]:
                chosen[slot], total, best = j, without + blocks[j], float(scores[j])
                improved = True
    return chosen


def design_poses(
    count: int,
    candidates: NDArray[np.float64],
    theta: NDArray[np.float64],
    *,
    keep: NDArray[np.float64] | None = None,
    reachable: Callable[[NDArray[np.float64]], bool] | None = None,
    noise_6: NDArray[np.float64] = PAPER_NOISE_6,
) -> NDArray[np.float64]:
    """``count`` new orientations from ``candidates`` (M, 3, 3) maximising ``log det F`` with the
    ``keep`` poses (K, 3, 3) already in the set; returns them, shape (count, 3, 3).

    Raises:
        ParameterError: fewer than :data:`MIN_POSES` in all, or too few reachable candidates.
    """
    kept = np.zeros((0, 3, 3)) if keep is None else np.asarray(keep, dtype=float)
    if count < 1 or count + len(kept) < MIN_POSES:
        raise ParameterError(
            f"count {count}: the design needs at least {MIN_POSES} poses in all (with "
            f"{len(kept)} kept) to identify the 12 parameters (bias, weight, centre of "
            "gravity, tilt)",
            field="count",
        )
    blocks = fisher_blocks(candidates, theta, noise_6=noise_6)
    fixed = (
        fisher_blocks(kept, theta, noise_6=noise_6).sum(axis=0) if len(kept) else np.zeros((12, 12))
    )
    scale = np.trace(blocks.mean(axis=0)) / 12.0
    ridge = _RIDGE * scale * np.eye(12)
    usable = np.ones(len(candidates), dtype=bool)
    checked: dict[int, bool] = {}
    while True:
        if usable.sum() < count:
            raise ParameterError(
                f"only {int(usable.sum())} reachable candidate orientations for count {count}",
                field="count",
            )
        allowed = np.flatnonzero(usable)
        sub = blocks[allowed]
        picked: list[int] = []
        total = fixed.copy()
        for _ in range(count):  # greedy
            scores = _logdet(total[None] + sub + ridge)
            scores[picked] = -np.inf
            j = int(np.argmax(scores))
            picked.append(j)
            total = total + sub[j]
        chosen = [int(allowed[j]) for j in _exchange(sub, fixed, picked, ridge)]
        if reachable is None:
            break
        bad = [j for j in chosen if not checked.setdefault(j, reachable(candidates[j]))]
        if not bad:
            break
        usable[bad] = False
    return np.asarray(candidates[chosen])


def predicted_std_errors(
    R_base_sensor: NDArray[np.float64],
    theta: NDArray[np.float64],
    *,
    noise_6: NDArray[np.float64] = PAPER_NOISE_6,
    readings_per_pose: int = 500,
) -> dict[str, NDArray[np.float64]]:
    """The joint method's predicted standard errors at these poses: ``G`` (1,) [N], ``F0`` (3,)
    [N], ``M0`` (3,) [N*m], ``P`` (3,) [m], ``a`` (3,) [N] (``G = |a|`` to first order)."""
    F = fisher_blocks(R_base_sensor, theta, noise_6=noise_6, readings_per_pose=readings_per_pose)
    cov = np.linalg.pinv(F.sum(axis=0))
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    a = theta[:3]
    g = a / np.linalg.norm(a)
    return {
        "G": np.array([math.sqrt(max(float(g @ cov[:3, :3] @ g), 0.0))]),
        "F0": se[3:6],
        "M0": se[6:9],
        "P": se[9:12],
        "a": se[0:3],
    }


def _angle(Ra: NDArray[np.float64], Rb: NDArray[np.float64]) -> float:
    c = (np.trace(Ra.T @ Rb) - 1.0) / 2.0
    return math.acos(min(1.0, max(-1.0, c)))


def order_for_travel(
    R_base_sensor: NDArray[np.float64], *, first: int = 0, fixed_prefix: int = 0
) -> NDArray[np.intp]:
    """An order of the poses with a short total rotation between consecutive ones.

    Nearest neighbour from ``first``, then 2-opt moves while the total shrinks. The first
    ``fixed_prefix`` poses keep their order (kept poses the user has already recorded).
    """
    R = np.asarray(R_base_sensor, dtype=float)
    n = len(R)
    D = np.array([[_angle(R[i], R[j]) for j in range(n)] for i in range(n)])
    order = list(range(fixed_prefix))
    rest = [i for i in range(fixed_prefix, n)]
    current = order[-1] if order else first
    if not order:
        order, rest = [first], [i for i in rest if i != first]
    while rest:
        nxt = min(rest, key=lambda j: D[current, j])
        order.append(nxt)
        rest.remove(nxt)
        current = nxt
    improved = True
    start = max(fixed_prefix, 1)
    while improved:
        improved = False
        for i in range(start, n - 1):
            for k in range(i + 1, n):
                before = D[order[i - 1], order[i]] + (D[order[k], order[k + 1]] if k + 1 < n else 0)
                after = D[order[i - 1], order[k]] + (D[order[i], order[k + 1]] if k + 1 < n else 0)
                if after < before - 1e-12:
                    order[i : k + 1] = order[i : k + 1][::-1]
                    improved = True
    return np.asarray(order, dtype=np.intp)
