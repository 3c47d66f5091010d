"""Calibration readings from a hand-guided arm: record each period the user holds it still.

The user jogs or free-drives the arm from pose to pose; :class:`ManualRecorder`, a step for
:func:`ftcomp.control.loop.run_loop` that commands nothing, watches the sensor frame's pose and
the readings every cycle:

- a *still period* starts when the pose last moved beyond ``position_tol_m`` / ``angle_tol_rad``
  from where the period started, and counts once it has lasted ``still_s`` with readings that do
  not drift (:class:`~ftcomp.session.pose_record.WrenchTolerance`, the means of the
  window's two halves); while the readings still drift, the window slides on;
- a still period at an orientation within ``min_separation_rad`` of a pose already recorded is
  ignored (it would add nothing to separate bias from gravity) and announced as such;
- otherwise its readings (the last ``samples_per_pose`` of the window, by default its last three
  quarters: the arm may still have been creeping into the pose when the window opened) become
  the next :class:`~ftcomp.session.pose_record.PoseRecord`, announced at once (a
  :class:`~ftcomp.session.pose_record.PoseEvent`);
- after ``n_poses`` records the step ends the loop.

Each still period is handled once: the arm must move beyond the tolerance before the next one.
"""

from __future__ import annotations

import collections
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.config_fields import check_fields, param
from ftcomp.errors import ParameterError
from ftcomp.session.pose_record import (
    PoseEvent,
    PoseRecord,
    WrenchTolerance,
    is_settled,
    nearest_pose,
)

if TYPE_CHECKING:
    from ftcomp.control.loop import Reading

__all__ = ["ManualRecorder", "StillCriteria"]


@dataclass(frozen=True)
class StillCriteria:
    """When the arm counts as held still, and when a pose is new.

    Attributes:
        still_s: how long pose and readings must stay still [s].
        position_tol_m: largest movement of the sensor origin within a still period [m].
        angle_tol_rad: largest rotation within a still period [rad].
        wrench: how little the readings may drift (see ``WrenchTolerance``).
        min_separation_rad: a pose closer than this to a recorded one is ignored [rad].
    """

    still_s: float = param(1.0, gt=0.0, unit="s", help="still for")
    position_tol_m: float = param(
        0.002, gt=0.0, unit="m", help="largest movement of the sensor origin while still"
    )
    angle_tol_rad: float = param(
        math.radians(0.5), gt=0.0, unit="rad", help="largest rotation while still"
    )
    wrench: WrenchTolerance = field(default_factory=WrenchTolerance)
    min_separation_rad: float = param(
        math.radians(5.0),
        ge=0.0,
        unit="rad",
        help="ignore a pose closer than this to a recorded one",
    )

    def __post_init__(self) -> None:
        check_fields(self)


class ManualRecorder:
    """A :func:`~ftcomp.control.loop.run_loop` step recording still periods (module docstring).

    It reads every reading its cycle took (``ControlCycle(every_reading=True)``: each cycle's
    :attr:`~ftcomp.control.loop.Reading.new`, raw wrench and stamp), and commands nothing.

    Args:
        n_poses: stop after this many poses, >= 1.
        criteria: what counts as still and as new.
        on_event: called with every :class:`~ftcomp.session.pose_record.PoseEvent` as it
            happens.
        samples_per_pose: readings kept per pose (the window's last ones); None: the last
            three quarters of the window.
        extra_channels: the names of the sensor's extra channels, whose values each reading
            carries (:class:`~ftcomp.hardware.protocols.ReportsExtraChannels`), kept in each
            :attr:`PoseRecord.extras <ftcomp.session.pose_record.PoseRecord.extras>`.
    """

    def __init__(
        self,
        n_poses: int,
        criteria: StillCriteria,
        on_event: Callable[[PoseEvent], None],
        *,
        samples_per_pose: int | None = None,
        extra_channels: tuple[str, ...] = (),
    ) -> None:
        if not (isinstance(n_poses, int) and n_poses >= 1):
            raise ParameterError(f"the number of poses must be an integer >= 1, got {n_poses}")
        if samples_per_pose is not None and samples_per_pose < 2:
            raise ParameterError(f"samples_per_pose must be >= 2, got {samples_per_pose}")
        self.n_poses = n_poses
        self.criteria = criteria
        self.on_event = on_event
        self.samples_per_pose = samples_per_pose
        self.extra_channels = extra_channels
        self.records: list[PoseRecord] = []
        self._zero = np.zeros(6)
        self._still_ns = round(criteria.still_s * 1e9)
        self._since_ns: int | None = None
        self._ref: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        self._window: collections.deque[tuple[int, NDArray[np.float64], tuple[float, ...]]] = (
            collections.deque()
        )
        self._handled = False

    def _moved(self, p: NDArray[np.float64], R: NDArray[np.float64]) -> bool:
        assert self._ref is not None
        p_ref, R_ref = self._ref
        if float(np.linalg.norm(p - p_ref)) > self.criteria.position_tol_m:
            return True
        return float(Rotation.from_matrix(R_ref.T @ R).magnitude()) > self.criteria.angle_tol_rad

    def __call__(self, reading: Reading) -> NDArray[np.float64] | None:
        """One cycle: take the new readings, follow the pose, record a still period."""
        if len(self.records) >= self.n_poses:
            return None
        now, p, R = reading.now_ns, reading.p_base_sensor, reading.R_base_sensor
        if self._ref is None or self._moved(p, R):
            self._ref, self._since_ns, self._handled = (p.copy(), R.copy()), now, False
            self._window.clear()  # readings from before the stillness are of no use
            return self._zero
        assert self._since_ns is not None
        for c in reading.new:
            if c.t_ns >= self._since_ns:
                self._window.append((c.t_ns, c.wrench_raw_sensor, c.extras))
        if self._handled or now - self._since_ns < self._still_ns or len(self._window) < 4:
            return self._zero
        wrench = np.array([w for _, w, _ in self._window])
        if not is_settled(wrench, self.criteria.wrench):
            # Still settling: slide the window to its second half and wait on.
            half = len(self._window) // 2
            for _ in range(half):
                self._window.popleft()
            self._since_ns = self._window[0][0]
            return self._zero
        self._handled = True
        number, angle = nearest_pose(self.records, R)
        if angle < self.criteria.min_separation_rad:
            self.on_event(PoseEvent("too_close", number, angle, None))
            return self._zero
        keep = self.samples_per_pose or (3 * len(self._window)) // 4
        stamps = np.array([t for t, _, _ in self._window], dtype=np.int64)[-keep:]
        names = self.extra_channels
        values = np.array([e for _, _, e in self._window], dtype=float)
        values = values.reshape(len(self._window), len(names))
        extras = dict(zip(names, values[-keep:].T, strict=True))
        record = PoseRecord(str(len(self.records) + 1), R, p, wrench[-keep:], stamps, extras)
        self.records.append(record)
        self.on_event(PoseEvent("recorded", len(self.records), angle, record))
        return None if len(self.records) >= self.n_poses else self._zero
