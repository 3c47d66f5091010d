"""Blocking moves of the simulated arm: minimum-jerk joint moves and Cartesian moves by IK.

:class:`ArmMotion` is a part of :class:`ftcomp.sim.cell.SimCell` (a mixin over the cell's MuJoCo
model and state), kept apart from the 1 kHz control cycle: what a robot controller's ``moveJ``
and ``moveL`` do. Poses are of the sensor frame in the robot's base frame.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any, Final

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ftcomp.errors import ParameterError, UnreachablePoseError
from ftcomp.sim.arm import C4_HOME_Q_RAD
from ftcomp.sim.ik import solve_pose

__all__ = ["HOME_Q_RAD", "ArmMotion", "CycleCallback"]

#: The C4-like arm's start configuration: tool pointing straight down in front of the robot
#: [rad]. A cell starts at its arm's ``home_q_rad``, also the first fixed start of every IK solve.
HOME_Q_RAD: Final = C4_HOME_Q_RAD

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
    #: The IK's fixed starts [rad], (K, N), read-only: the arm's ``home_q_rad``, then random
    #: configurations within the joint ranges drawn once per cell.
    _ik_starts: NDArray[np.float64]

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
        capability). Checking moves nothing and changes nothing.

        The verdict does not depend on where the arm is: the check tries the cell's fixed starts
        only, which every :meth:`solve_ik` tries too, so a pose found reachable here is one
        :meth:`move_pose` reaches from wherever the arm then is (a pose design checked on one
        cell is visited by another of the same arm, whatever its path).

        Raises:
            ParameterError: not a position (3,) [m] and a rotation (3, 3).
        """
        try:
            self._solve(p_base_tcp, R_base_tcp, list(self._ik_starts), "")
        except UnreachablePoseError:
            return False
        return True

    def solve_ik(
        self, p_base_sensor: ArrayLike, R_base_sensor: ArrayLike, *, label: str = ""
    ) -> NDArray[np.float64]:
        """Joint positions [rad] putting the sensor frame at a base-frame pose.

        Tries the current command first (the nearest solution), then the cell's fixed starts:
        the arm's ``home_q_rad`` and random configurations drawn once when the cell was built
        (the same starts for every solve, so the answer depends on the pose and the current
        command only, and a pose :meth:`is_reachable` accepts is always solved).

        Args:
            p_base_sensor: position [m], base frame, (3,).
            R_base_sensor: orientation, (3, 3).
            label: names the pose in an error message.

        Raises:
            UnreachablePoseError: no start converges within the joint ranges.
        """
        return self._solve(p_base_sensor, R_base_sensor, [self._q_cmd, *self._ik_starts], label)

    def _solve(
        self,
        p_base_sensor: ArrayLike,
        R_base_sensor: ArrayLike,
        starts: Sequence[NDArray[np.float64]],
        label: str,
    ) -> NDArray[np.float64]:
        """:func:`~ftcomp.sim.ik.solve_pose` from ``starts`` (each (N,) [rad]), in the base
        frame; raises :class:`UnreachablePoseError` naming ``label`` if none converges."""
        p = np.asarray(p_base_sensor, dtype=float)
        R = np.asarray(R_base_sensor, dtype=float)
        finite = bool(np.isfinite(p).all() and np.isfinite(R).all())
        if p.shape != (3,) or R.shape != (3, 3) or not finite:
            raise ParameterError(f"{label or 'pose'}: need p (3,) and R (3, 3), finite")
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise ParameterError(f"{label or 'pose'}: R_base_sensor is not a rotation matrix")
        Rwb = self._R_world_base
        mujoco.mj_copyData(self._scratch, self._model, self._data)
        q = solve_pose(
            self._model,
            self._scratch,
            self._site,
            self._qpos_adr,
            self._dof_adr,
            Rwb @ p,
            Rwb @ R,
            starts,
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
