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
(:class:`ftcomp.ros2.urdf_ik.UrdfIk`).
"""

from __future__ import annotations

from collections.abc import Callable
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
    "ReachCheck",
    "Reachability",
    "design_reachable_poses",
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
