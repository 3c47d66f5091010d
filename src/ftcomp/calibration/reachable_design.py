"""Pose design on an arm that does not reach every orientation.

:func:`~.design.design_poses` asks a ``reachable`` check of every orientation it chooses and
designs again without the ones the arm cannot reach. A D-optimal design prefers the most tilted
orientations, the ones an arm reaches least, so on a cramped arm it could ask for hundreds of
inverse kinematics (each tens of ms when out of reach). :class:`Reachability` bounds that: after
:data:`FEW_MISSES` unreachable choices it stops the design, and :func:`design_reachable_poses`
designs among reachable candidates sampled at random instead (a seeded order, until it has
:data:`POOL_PER_POSE` reachable ones per designed pose and at least :data:`MIN_SAMPLE` checked,
or has checked :data:`MAX_SAMPLE`). The sample gives the reachable fraction, which
:meth:`Reachability.summary` reports.

The check itself is any ``(p_base_m, R_base_sensor) -> bool``: a robot's own
(:class:`~ftcomp.hardware.protocols.ChecksReachability`) or a URDF chain's inverse kinematics
(:class:`ftcomp.chain_ik.ChainIk`).

Each orientation reachable is not yet a visit the arm can make: joint moves between them may
wind a joint to its end. :func:`plan_visit` checks the whole visit as a robot that moves in
joint space makes it (:class:`~ftcomp.hardware.protocols.MovesInJointSpace`: each move to the
inverse kinematics nearest the joints before it, within the joint ranges), from the arm's
joints now, and orders it to keep the joint travel short: from where the arm is, the next pose
is the one whose solution is nearest in its largest joint move. A pose without a solution from
there is left out, with the reason.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.design import design_poses
from ftcomp.errors import ParameterError

__all__ = [
    "FEW_MISSES",
    "MAX_SAMPLE",
    "MIN_SAMPLE",
    "POOL_PER_POSE",
    "NearestIk",
    "ReachCheck",
    "Reachability",
    "Visit",
    "design_reachable_poses",
    "plan_visit",
]

#: Unreachable choices of the design after which it samples instead.
FEW_MISSES: Final = 20
#: Reachable candidates the sample looks for, per designed pose.
POOL_PER_POSE: Final = 4
#: Fewest candidates the sample checks (for the reachable fraction).
MIN_SAMPLE: Final = 20
#: Most candidates the sample checks (the time bound).
MAX_SAMPLE: Final = 200

#: ``(p_base_m (3,), R_base_sensor (3, 3)) -> whether the tip reaches that pose``.
ReachCheck = Callable[[NDArray[np.float64], NDArray[np.float64]], bool]


#: ``(p_base_m (3,), R_base_sensor (3, 3), q_near_rad (N,)) -> joints [rad] (N,) or None``:
#: the inverse kinematics nearest ``q_near_rad`` within the joint ranges.
NearestIk = Callable[
    [NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64] | None
]


class _BudgetSpentError(Exception):
    """The design's own choices missed :data:`FEW_MISSES` times: sample the candidates instead."""


class Reachability:
    """``R -> bool``: whether the tip reaches orientation ``R`` at one position ``p`` [m].

    Counts the candidates checked, remembers the answers (the design asks again for what a
    round before chose) and estimates the reachable fraction.

    Args:
        check: the reach check.
        p_base_m: the tip's position for every designed pose, base frame [m], (3,).
        source: the option that names the check, for messages (``"--urdf arm.urdf"``).
        who: what checks, for the summary and warnings (``"ur://127.0.0.1"``).
    """

    def __init__(
        self, check: ReachCheck, p_base_m: NDArray[np.float64], *, source: str, who: str
    ) -> None:
        self.check = check
        self.p = np.asarray(p_base_m, dtype=float)
        self.source = source
        self.who = who
        self.checked = self.reached = 0
        self.sampled = self.sampled_reached = 0
        self._known: dict[bytes, bool] = {}

    def reaches(self, p_base_m: NDArray[np.float64], R_base_sensor: NDArray[np.float64]) -> bool:
        """Whether the tip reaches ``R_base_sensor`` at ``p_base_m`` (not counted)."""
        return bool(self.check(p_base_m, R_base_sensor))

    def _check(self, R: NDArray[np.float64]) -> bool:
        key = np.asarray(R, dtype=float).tobytes()
        if key not in self._known:
            self.checked += 1
            self._known[key] = self.reaches(self.p, R)
            self.reached += self._known[key]
        return self._known[key]

    def __call__(self, R: NDArray[np.float64]) -> bool:
        ok = self._check(R)
        if self.checked - self.reached >= FEW_MISSES:
            raise _BudgetSpentError
        return ok

    def reachable_sample(self, candidates: NDArray[np.float64], count: int) -> NDArray[np.float64]:
        """The reachable candidates among a seeded random sample (and those found before).

        Raises:
            ParameterError: fewer than ``count`` reachable ones (with the fraction).
        """
        order = np.random.default_rng(0).permutation(len(candidates))[:MAX_SAMPLE]
        pool = [R for R in candidates if self._known.get(np.asarray(R).tobytes(), False)]
        for j in order:
            if len(pool) >= POOL_PER_POSE * count and self.sampled >= MIN_SAMPLE:
                break
            self.sampled += 1
            ok = self._check(candidates[j])
            self.sampled_reached += ok
            if ok and not any(np.array_equal(candidates[j], R) for R in pool):
                pool.append(candidates[j])
        if len(pool) < count:
            raise ParameterError(
                f"{self.source}: {self.sampled - self.sampled_reached} of {self.sampled} "
                "candidate orientations sampled at random are out of reach with the tip at "
                f"{np.round(self.p, 4).tolist()} m ({self.fraction()} reachable); too few "
                f"reachable ones for count {count}: give a position_mm where the arm turns "
                "the tip more freely, or a smaller max_tilt_deg",
                field=("count", "position_mm", "max_tilt_deg"),
            )
        return np.asarray(pool)

    def fraction(self) -> str:
        """The reachable fraction of the random sample, as text."""
        if not self.sampled:
            return "no sample"
        return f"{self.sampled_reached / self.sampled:.0%} of {self.sampled}"

    def summary(self, describe: str) -> str:
        """One line: what checked (``describe``), where, how many reached, and the sample."""
        text = (
            f"reachability: {describe}, tip at {np.round(self.p, 4).tolist()} m: "
            f"{self.reached} of {self.checked} candidate orientations checked reached by "
            "inverse kinematics"
        )
        if self.sampled:
            text += (
                f"; the design's own choices missed {FEW_MISSES} times, so it chose among "
                f"reachable candidates sampled at random: {self.fraction()} sampled are reachable"
            )
        return text


def design_reachable_poses(
    count: int,
    candidates: NDArray[np.float64],
    theta: NDArray[np.float64],
    *,
    keep: NDArray[np.float64] | None,
    reach: Reachability,
) -> NDArray[np.float64]:
    """:func:`~.design.design_poses` with the reach check, falling back to a design among
    reachable candidates sampled at random once the design's own choices miss too often.

    Returns:
        ``count`` orientations the tip reaches at ``reach.p``, (count, 3, 3).

    Raises:
        ParameterError: too few reachable candidates (with the fraction found).
    """
    try:
        return design_poses(count, candidates, theta, keep=keep, reachable=reach)
    except _BudgetSpentError:
        pool = reach.reachable_sample(candidates, count)
        return design_poses(count, pool, theta, keep=keep)


@dataclass(frozen=True)
class Visit:
    """A visit of poses by joint moves, checked from a start configuration.

    Attributes:
        order: the poses visited, as indices into the poses given, in visit order.
        q_rad: the joints at each visited pose [rad], (len(order), N).
        left_out: ``(index, why)`` of each pose the visit cannot reach.
        largest_move_rad: the largest single joint move of the visit [rad].
    """

    order: tuple[int, ...]
    q_rad: NDArray[np.float64]
    left_out: tuple[tuple[int, str], ...]
    largest_move_rad: float


def plan_visit(
    p_base_m: Sequence[NDArray[np.float64]] | NDArray[np.float64],
    R_base_sensor: NDArray[np.float64],
    q_start_rad: NDArray[np.float64],
    ik: NearestIk,
) -> Visit:
    """Order poses into a visit by joint moves from ``q_start_rad`` (module docstring).

    Args:
        p_base_m: each pose's position [m], base frame, (K, 3).
        R_base_sensor: each pose's orientation, (K, 3, 3).
        q_start_rad: the arm's joints now [rad], (N,).
        ik: the inverse kinematics nearest a configuration, within the joint ranges.

    Raises:
        ParameterError: mismatched shapes.
    """
    R = np.asarray(R_base_sensor, dtype=float)
    p = np.asarray(p_base_m, dtype=float)
    q = np.asarray(q_start_rad, dtype=float)
    if R.ndim != 3 or R.shape[1:] != (3, 3) or p.shape != (len(R), 3) or q.ndim != 1:
        raise ParameterError(
            f"plan_visit needs K positions (K, 3), K rotations (K, 3, 3) and joints (N,); got "
            f"{p.shape}, {R.shape}, {q.shape}"
        )
    remaining = list(range(len(R)))
    order: list[int] = []
    solutions: list[NDArray[np.float64]] = []
    left_out: list[tuple[int, str]] = []
    largest = 0.0
    while remaining:
        best: tuple[float, int, NDArray[np.float64]] | None = None
        for i in list(remaining):
            sol = ik(p[i], R[i], q)
            if sol is None:
                continue
            move = float(np.max(np.abs(sol - q)))
            if best is None or move < best[0]:
                best = (move, i, sol)
        if best is None:  # none reachable from here: each left out
            joints = np.round(np.degrees(q), 1).tolist()
            for i in remaining:
                left_out.append(
                    (i, f"no inverse kinematics within the joint ranges near {joints} deg")
                )
            break
        move, i, q = best
        largest = max(largest, move)
        order.append(i)
        solutions.append(q)
        remaining.remove(i)
    q_all = np.array(solutions) if solutions else np.zeros((0, len(q_start_rad)))
    return Visit(tuple(order), q_all, tuple(left_out), largest)
