"""Blocking moves of the simulated arm: minimum-jerk joint moves and Cartesian moves by IK.

:class:`ArmMotion` is a part of :class:`ftcomp.sim.cell.SimCell` (a mixin over the cell's MuJoCo
model and state), kept apart from the 1 kHz control cycle: what a robot controller's ``moveJ``
and ``moveL`` do. Poses are of the sensor frame in the robot's base frame.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Final

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ftcomp.errors import ParameterError, UnreachablePoseError
from ftcomp.sim.arm import C4_HOME_Q_RAD
from ftcomp.sim.ik import solve_pose

if TYPE_CHECKING:
    from ftcomp.sim.scene import SceneConfig

__all__ = ["HOME_Q_RAD", "ArmMotion", "CycleCallback"]

#: The C4-like arm's start configuration: tool pointing straight down in front of the robot
#: [rad]. A cell starts at its arm's ``home_q_rad``, also the second seed of every IK solve.
HOME_Q_RAD: Final = C4_HOME_Q_RAD

#: Seeds the random IK starts of a reachability check (its own generator, so a check does not
#: change the starts of later moves).
_REACH_CHECK_SEED: Final = 20200302

#: Called after every control cycle of a blocking move (e.g. to record readings).
CycleCallback = Callable[[Any], None]


def _min_jerk(tau: float) -> tuple[float, float]:
    """Minimum-jerk profile s(tau) and ds/dtau on tau in [0, 1]."""
    s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau * tau)
    ds = 30.0 * tau * tau * (1.0 - tau) ** 2
    return s, ds


class ArmMotion:
    """Blocking joint and Cartesian moves of the simulated arm (see the module docstring)."""

    # Set by SimCell.__init__.
    _config: SceneConfig
    _model: mujoco.MjModel
    _data: mujoco.MjData
    _scratch: mujoco.MjData
    _site: int
    _qpos_adr: NDArray[np.intp]
    _dof_adr: NDArray[np.intp]
    _lower: NDArray[np.float64]
    _upper: NDArray[np.float64]
    _period: float
    _q_cmd: NDArray[np.float64]
    _qd_cmd: NDArray[np.float64]
    _R_world_base: NDArray[np.float64]
    _ik_rng: np.random.Generator

    def stop(self) -> None:
        """Zero the commanded velocity (the cell's)."""
        raise NotImplementedError

    def _physics(self) -> None:
        raise NotImplementedError

    def _check_joints(self, q: NDArray[np.float64], name: str) -> None:
        raise NotImplementedError

    def move_joints(
        self,
        q_rad: ArrayLike,
        duration_s: float,
        *,
        on_cycle: CycleCallback | None = None,
    ) -> None:
        """Blocking minimum-jerk joint move to ``q_rad`` [rad] in ``duration_s`` [s].

        ``on_cycle(cell)``, if given, runs after every control cycle (to record readings).
        A commanded twist is stopped first.

        Raises:
            ParameterError: ``q_rad`` outside the joint ranges or ``duration_s`` not positive.
        """
        q1 = np.array(q_rad, dtype=float)
        self._check_joints(q1, "q_rad")
        if not math.isfinite(duration_s) or duration_s <= 0.0:
            raise ParameterError(f"duration_s must be finite and > 0, got {duration_s}")
        self.stop()
        q0 = self._q_cmd.copy()
        n = max(1, round(duration_s / self._period))
        T = n * self._period
        for i in range(1, n + 1):
            s, ds = _min_jerk(i / n)
            self._q_cmd = q0 + (q1 - q0) * s
            self._qd_cmd = (q1 - q0) * (ds / T)
            self._physics()
            if on_cycle is not None:
                on_cycle(self)
        self._q_cmd = q1
        self._qd_cmd = np.zeros(q1.shape[0])

    def move_pose(
        self,
        p_base_sensor: ArrayLike,
        R_base_sensor: ArrayLike,
        duration_s: float,
        *,
        on_cycle: CycleCallback | None = None,
        label: str = "",
    ) -> None:
        """Blocking move of the sensor frame to a pose: inverse kinematics, then a joint move.

        Args:
            p_base_sensor: target position [m], base frame, shape (3,).
            R_base_sensor: target orientation, shape (3, 3).
            duration_s: duration of the move [s].
            on_cycle: as in :meth:`move_joints`.
            label: names the pose in an error message (e.g. ``"pose 4"``).

        Raises:
            UnreachablePoseError: no joint configuration within the joint ranges reaches it.
        """
        q = self.solve_ik(p_base_sensor, R_base_sensor, label=label)
        self.move_joints(q, duration_s, on_cycle=on_cycle)

    # ----------------------------------------------------------------- kinematics
    def is_reachable(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64]
    ) -> bool:
        """Whether inverse kinematics puts the TCP (the sensor frame) at this base-frame pose
        within the joint ranges (the :class:`~ftcomp.hardware.protocols.ChecksReachability`
        capability). Checking moves nothing and leaves later moves' IK seeds as they were.

        Raises:
            ParameterError: not a position (3,) [m] and a rotation (3, 3).
        """
        try:
            self.solve_ik(p_base_tcp, R_base_tcp, rng=np.random.default_rng(_REACH_CHECK_SEED))
        except UnreachablePoseError:
            return False
        return True

    def solve_ik(
        self,
        p_base_sensor: ArrayLike,
        R_base_sensor: ArrayLike,
        *,
        label: str = "",
        rng: np.random.Generator | None = None,
    ) -> NDArray[np.float64]:
        """Joint positions [rad] putting the sensor frame at a base-frame pose.

        Tries the current command first (the nearest solution), then fixed and random seeds
        (a fixed generator: the same pose gives the same answer whatever the noise seed).

        Args:
            p_base_sensor: position [m], base frame, (3,).
            R_base_sensor: orientation, (3, 3).
            label: names the pose in an error message.
            rng: draws the random seeds (default: the cell's own generator, which advances).

        Raises:
            UnreachablePoseError: no seed converges within the joint ranges.
        """
        p = np.asarray(p_base_sensor, dtype=float)
        R = np.asarray(R_base_sensor, dtype=float)
        finite = bool(np.isfinite(p).all() and np.isfinite(R).all())
        if p.shape != (3,) or R.shape != (3, 3) or not finite:
            raise ParameterError(f"{label or 'pose'}: need p (3,) and R (3, 3), finite")
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise ParameterError(f"{label or 'pose'}: R_base_sensor is not a rotation matrix")
        Rwb = self._R_world_base
        span = self._upper - self._lower
        draw = self._ik_rng if rng is None else rng
        seeds = [self._q_cmd, np.array(self._config.arm.home_q_rad)]
        seeds += [self._lower + span * draw.random(span.shape[0]) for _ in range(30)]
        mujoco.mj_copyData(self._scratch, self._model, self._data)
        q = solve_pose(
            self._model,
            self._scratch,
            self._site,
            self._qpos_adr,
            self._dof_adr,
            Rwb @ p,
            Rwb @ R,
            seeds,
            self._lower,
            self._upper,
        )
        if q is None:
            euler = Rotation.from_matrix(R).as_euler("ZYX", degrees=True)
            raise UnreachablePoseError(
                f"{label or 'pose'} is unreachable: no joint configuration within the joint "
                f"ranges puts the sensor at p_base={np.round(p, 4).tolist()} m, "
                f"(alpha, beta, gamma)={np.round(euler, 3).tolist()} deg"
            )
        return q
