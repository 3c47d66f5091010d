"""Static calibration data from the simulated cell: drive to each pose, wait until still, record.

Poses are sensor orientations ``R_base_sensor`` (the paper's Table 1, or a file using the
sample-CSV orientation columns), all at one sensor position in front of the robot.
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Final

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.errors import FtcompError, InputFileError, ParameterError
from ftcomp.frames import ENCODING_COLUMNS, OrientationEncoding, rotation_from_encoding
from ftcomp.model import GravityModel
from ftcomp.sim.cell import SimCell

__all__ = [
    "COLLECTION_POSITION_BASE_M",
    "PoseList",
    "StaticCollection",
    "collect_static_samples",
    "paper_poses",
    "read_pose_file",
]

#: Where the sensor origin is held for static collection, base frame [m].
COLLECTION_POSITION_BASE_M: Final = (0.45, 0.0, 0.42)
#: Optional position columns of a pose file: the sensor origin, base frame [m].
_POSITION_COLUMNS: Final = ("x_m", "y_m", "z_m")


@dataclass(frozen=True)
class PoseList:
    """Sensor orientations to visit.

    Attributes:
        ids: a label per pose (the ``pose`` column, or 1, 2, ...), shape (M,).
        rotations: ``R_base_sensor`` per pose (M rotations).
        source: where they came from, for messages.
        positions_base_m: sensor origin per pose, base frame [m], shape (M, 3); None: all at
            the collection position.
    """

    ids: tuple[str, ...]
    rotations: Rotation = field(repr=False)
    source: str = "<poses>"
    positions_base_m: NDArray[np.float64] | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if len(self.ids) == 0 or len(self.ids) != len(self.rotations):
            raise ParameterError(
                f"{self.source}: need as many pose ids as rotations (>= 1), "
                f"got {len(self.ids)} ids and {len(self.rotations)} rotations"
            )
        if self.positions_base_m is not None:
            pos = np.array(self.positions_base_m, dtype=float)
            if pos.shape != (len(self.ids), 3) or not np.isfinite(pos).all():
                raise ParameterError(f"{self.source}: positions must be finite, shape (M, 3)")
            pos.setflags(write=False)
            object.__setattr__(self, "positions_base_m", pos)

    def __len__(self) -> int:
        return len(self.ids)


@dataclass(frozen=True)
class StaticCollection:
    """Readings at static poses with the truth behind them.

    Attributes:
        wrench_sensor: readings [N, N*m], sensor frame, shape (N, 6).
        rotations: the sensor's measured ``R_base_sensor`` at each reading (N rotations).
        pose: index of the pose (position in the :class:`PoseList`, from 1), shape (N,).
        pose_ids: the pose labels, shape (N,).
        t: sensor time stamps [s], shape (N,).
        truth: what calibration should find (weight, centre of gravity, bias, tilt).
    """

    wrench_sensor: NDArray[np.float64] = field(repr=False)
    rotations: Rotation = field(repr=False)
    pose: NDArray[np.int64] = field(repr=False)
    pose_ids: tuple[str, ...] = field(repr=False)
    t: NDArray[np.float64] = field(repr=False)
    truth: GravityModel

    def __post_init__(self) -> None:
        n = len(self.wrench_sensor)
        for name in ("wrench_sensor", "pose", "t"):
            arr = np.array(getattr(self, name))
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        if self.wrench_sensor.shape != (n, 6) or len(self.pose) != n or len(self.t) != n:
            raise ParameterError("StaticCollection arrays must share their first dimension")


def paper_poses() -> PoseList:
    """The nine poses of the paper's Table 1 (angles ``R = Rz(alpha) Ry(beta) Rx(gamma)``)."""
    text = resources.files("ftcomp.data").joinpath("huang2020_table1_2.csv").read_text("utf-8")
    rows = list(csv.DictReader(text.splitlines()))
    columns = ENCODING_COLUMNS["paper_euler"]
    angles = np.array([[float(row[c]) for c in columns] for row in rows])
    return PoseList(
        tuple(row["pose"] for row in rows),
        rotation_from_encoding("paper_euler", angles),
        "paper Table 1",
    )


def read_pose_file(path: str | os.PathLike[str]) -> PoseList:
    """Poses from a CSV with one orientation encoding's columns (as in the sample CSV).

    An optional ``pose`` column labels the poses; rows sharing a label are one pose (their
    mean orientation), so a sample CSV can be reused as a pose file. Optional columns
    ``x_m,y_m,z_m`` give the sensor origin in the base frame [m] (default: the collection
    position). Other columns are ignored.

    Raises:
        InputFileError: unreadable file, no or several encodings, a bad cell (file, row,
            column named).
    """
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(f"{source}: cannot read the pose file: {exc}") from exc
    reader = csv.reader(text.splitlines())
    header = [h.strip() for h in next(reader, [])]
    found: list[OrientationEncoding] = [
        enc for enc, cols in ENCODING_COLUMNS.items() if all(c in header for c in cols)
    ]
    if len(found) != 1:
        valid = "; ".join(",".join(cols) for cols in ENCODING_COLUMNS.values())
        what = "no" if not found else "more than one"
        raise InputFileError(
            f"{source}: {what} orientation encoding in the header {header}; "
            f"give exactly one of: {valid}"
        )
    encoding = found[0]
    idx = [header.index(c) for c in ENCODING_COLUMNS[encoding]]
    pose_col = header.index("pose") if "pose" in header else None
    has_position = all(c in header for c in _POSITION_COLUMNS)
    if has_position:
        idx += [header.index(c) for c in _POSITION_COLUMNS]
    width = len(ENCODING_COLUMNS[encoding])
    labels: list[str] = []
    values: list[list[float]] = []
    for row_no, row in enumerate(reader, start=1):
        if not row or all(not cell.strip() for cell in row):
            continue
        if len(row) < len(header):
            raise InputFileError(
                f"{source}: row {row_no} has {len(row)} cells, the header has {len(header)}"
            )
        try:
            values.append([float(row[i]) for i in idx])
        except ValueError:
            bad = next(i for i in idx if not _is_float(row[i]))
            raise InputFileError(
                f"{source}: row {row_no}, column {header[bad]!r}: {row[bad]!r} is not a number"
            ) from None
        labels.append(row[pose_col].strip() if pose_col is not None else str(len(labels) + 1))
    if not values:
        raise InputFileError(f"{source}: no pose rows after the header")
    table = np.array(values)
    try:
        rotations = rotation_from_encoding(encoding, table[:, :width])
    except FtcompError as exc:
        raise InputFileError(f"{source}: {exc}") from exc
    positions = table[:, width:] if has_position else None
    order = list(dict.fromkeys(labels))
    if len(order) == len(labels):
        return PoseList(tuple(labels), rotations, source, positions)
    label_arr = np.array(labels)
    groups = [np.flatnonzero(label_arr == lab) for lab in order]
    means = Rotation.concatenate([rotations[g].mean() for g in groups])
    mean_pos = None if positions is None else np.array([positions[g].mean(0) for g in groups])
    return PoseList(tuple(order), means, source, mean_pos)


def _is_float(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def collect_static_samples(
    cell: SimCell,
    poses: PoseList,
    samples_per_pose: int,
    *,
    position_base_m: tuple[float, float, float] = COLLECTION_POSITION_BASE_M,
    move_duration_s: float = 1.0,
    settle_max_s: float = 3.0,
) -> StaticCollection:
    """Drive to each pose, wait until the cell is still, record ``samples_per_pose`` readings.

    Poses without a position are held at ``position_base_m`` [m] (base frame).
    Readings are the sensor model applied to MuJoCo's force/torque sensor data while the
    physics keeps running at the held pose (1.2 kHz output, the latest 1 ms physics state).

    Raises:
        UnreachablePoseError: a pose cannot be reached (the error names it).
        SimulationError: the cell does not come to rest at a pose.
    """
    if samples_per_pose < 1:
        raise ParameterError(f"samples_per_pose must be >= 1, got {samples_per_pose}")
    p = np.asarray(position_base_m, dtype=float)
    if p.shape != (3,) or not np.isfinite(p).all():
        raise ParameterError(f"position_base_m must be 3 finite numbers [m], got {position_base_m}")
    wrenches, rots, pose_idx, times, weights, cogs = [], [], [], [], [], []
    for i, (label, rotation) in enumerate(zip(poses.ids, poses.rotations, strict=True)):
        name = f"pose {label} of {poses.source}"
        if poses.positions_base_m is not None:
            p = poses.positions_base_m[i]
        cell.move_pose(p, rotation.as_matrix(), move_duration_s, label=name)
        cell.settle(settle_max_s, label=f"the cell at {name}")
        t, w = cell.record_readings(samples_per_pose)
        _, R_base_sensor = cell.sensor_pose()
        truth = cell.true_gravity_model()
        weights.append(truth.weight_N)
        cogs.append(truth.center_of_gravity_m)
        wrenches.append(w)
        rots.append(np.broadcast_to(R_base_sensor, (samples_per_pose, 3, 3)))
        pose_idx.append(np.full(samples_per_pose, i + 1, dtype=np.int64))
        times.append(t)
    truth = cell.true_gravity_model()
    # The held load's weld flexes by micrometres from pose to pose: report the mean.
    truth = GravityModel(
        float(np.mean(weights)),
        np.mean(cogs, axis=0),
        truth.force_bias_N,
        truth.torque_bias_Nm,
        tilt_U_rad=truth.tilt_U_rad,
        tilt_V_rad=truth.tilt_V_rad,
    )
    pose_arr = np.concatenate(pose_idx)
    return StaticCollection(
        np.concatenate(wrenches),
        Rotation.from_matrix(np.concatenate(rots)),
        pose_arr,
        tuple(poses.ids[k - 1] for k in pose_arr),
        np.concatenate(times),
        truth,
    )
