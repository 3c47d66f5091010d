"""What a recording session keeps of one pose, and when its readings count as settled.

Both ways of recording calibration readings on a live cell, robot-driven
(:mod:`ftcomp.session.robot_driven`) and hand-guided (:mod:`ftcomp.session.hand_guided`), hand
each finished pose on as a :class:`PoseRecord` at once, announced as a :class:`PoseEvent`; a
pose's readings count as settled when the means of their window's two halves differ by less
than a :class:`WrenchTolerance`. :func:`samples_from_records` joins the records into one
:class:`~ftcomp.samples.Samples` (what the sample CSV holds).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ftcomp.arrays import freeze_field
from ftcomp.config_fields import check_fields, param
from ftcomp.errors import ParameterError
from ftcomp.samples import Samples, frozen_channels

__all__ = [
    "PoseEvent",
    "PoseRecord",
    "WrenchTolerance",
    "is_settled",
    "nearest_pose",
    "samples_from_records",
    "wrench_drift",
]


@dataclass(frozen=True)
class PoseRecord:
    """The readings recorded at one pose.

    Attributes:
        pose_id: the pose's label.
        R_base_sensor: the sensor's measured orientation there, (3, 3).
        p_base_sensor: the sensor origin there [m], base frame, (3,).
        wrench_sensor: the readings [N, N*m], sensor frame, (n, 6).
        t_ns: their stamps [ns] on the session's clock, (n,).
        extras: the sensor's extra channels of each reading, by name (``temperature_C``...),
            (n,) each (:attr:`~ftcomp.samples.Samples.extras`; empty without them).
    """

    pose_id: str
    R_base_sensor: NDArray[np.float64] = field(repr=False)
    p_base_sensor: NDArray[np.float64] = field(repr=False)
    wrench_sensor: NDArray[np.float64] = field(repr=False)
    t_ns: NDArray[np.int64] = field(repr=False)
    extras: Mapping[str, NDArray[np.float64]] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        n = len(self.wrench_sensor)
        if n < 1:
            raise ParameterError(f"pose {self.pose_id}: no readings")
        freeze_field(self, "R_base_sensor", (3, 3))
        freeze_field(self, "p_base_sensor", (3,))
        freeze_field(self, "wrench_sensor", (n, 6))
        freeze_field(self, "t_ns", (n,), dtype=np.int64)
        extras = frozen_channels(self.extras, n, f"pose {self.pose_id}")
        object.__setattr__(self, "extras", extras)

    @property
    def mean(self) -> NDArray[np.float64]:
        """Mean reading [N, N*m], (6,)."""
        return np.asarray(self.wrench_sensor.mean(axis=0))

    @property
    def scatter(self) -> NDArray[np.float64]:
        """Standard deviation of one reading per channel [N, N*m], (6,) (0 for one reading)."""
        if len(self.wrench_sensor) < 2:
            return np.zeros(6)
        return np.asarray(self.wrench_sensor.std(axis=0, ddof=1))


@dataclass(frozen=True)
class PoseEvent:
    """What a recording session noticed.

    Attributes:
        kind: ``"recorded"`` (a new pose) or ``"too_close"`` (hand-guided: a still period
            ignored, too close in orientation to a recorded pose).
        number: the new pose's number (1, 2, ...), or the number of the recorded pose it was
            too close to.
        angle_rad: the rotation to the nearest recorded pose before this one [rad] (inf for the
            first).
        record: the new pose's readings (None when ignored).
    """

    kind: Literal["recorded", "too_close"]
    number: int
    angle_rad: float
    record: PoseRecord | None

    def __post_init__(self) -> None:
        if (self.kind == "recorded") != (self.record is not None):
            raise ParameterError(f"a {self.kind!r} event must carry a record exactly when recorded")


@dataclass(frozen=True)
class WrenchTolerance:
    """How much the mean reading may move within a still window and still count as settled.

    Attributes:
        force_N: largest change of the force channels' mean between the window's halves [N].
        torque_Nm: same for the torques [N*m].
    """

    force_N: float = param(
        0.1, gt=0.0, unit="N", help="largest change of the force's mean within a still window"
    )
    torque_Nm: float = param(
        0.01, gt=0.0, unit="N*m", help="largest change of the torque's mean within a still window"
    )

    def __post_init__(self) -> None:
        check_fields(self)


def wrench_drift(wrench: ArrayLike) -> NDArray[np.float64]:
    """``|mean(second half) - mean(first half)|`` per channel [N, N*m], (6,): how much the
    readings drift over a window (zeros for fewer than two readings)."""
    w = np.asarray(wrench, dtype=float).reshape(-1, 6)
    if len(w) < 2:
        return np.zeros(6)
    half = len(w) // 2
    return np.asarray(np.abs(w[half:].mean(axis=0) - w[:half].mean(axis=0)))


def is_settled(wrench: ArrayLike, tolerance: WrenchTolerance) -> bool:
    """Whether readings [N, N*m], (n, 6), drift less than ``tolerance`` over their window."""
    drift = wrench_drift(wrench)
    return bool(np.all(drift[:3] <= tolerance.force_N) and np.all(drift[3:] <= tolerance.torque_Nm))


def nearest_pose(records: Sequence[PoseRecord], R_base_sensor: ArrayLike) -> tuple[int, float]:
    """(number, angle [rad]) of the record nearest in orientation to ``R_base_sensor`` (3, 3);
    numbers count from 1; ``(0, inf)`` when there is none."""
    R = np.asarray(R_base_sensor, dtype=float)
    best = (0, math.inf)
    for k, record in enumerate(records, start=1):
        angle = float(Rotation.from_matrix(record.R_base_sensor.T @ R).magnitude())
        if angle < best[1]:
            best = (k, angle)
    return best


def samples_from_records(records: Sequence[PoseRecord], source: str) -> Samples:
    """All records as one :class:`~ftcomp.samples.Samples` (``pose`` ids, ``t`` in seconds,
    the extra channels the records share)."""
    if not records:
        raise ParameterError(f"{source}: no poses recorded")
    n = [len(r.wrench_sensor) for r in records]
    names = [name for name in records[0].extras if all(name in r.extras for r in records)]
    return Samples(
        wrench_sensor=np.concatenate([r.wrench_sensor for r in records]),
        R_base_sensor=np.concatenate(
            [np.broadcast_to(r.R_base_sensor, (k, 3, 3)) for r, k in zip(records, n, strict=True)]
        ),
        encoding="quaternion",
        pose=np.repeat([r.pose_id for r in records], n),
        t=np.concatenate([r.t_ns for r in records]).astype(np.float64) * 1e-9,
        source=source,
        extras={name: np.concatenate([r.extras[name] for r in records]) for name in names},
    )
