"""The records calibration works on: readings with orientations, and poses to visit.

:class:`Samples` holds F/T readings, each with the sensor's orientation ``R_base_sensor`` at
that moment (from a sample CSV, a recording or a bag). :class:`PoseList` holds the orientations
(and optionally positions) a robot should visit to collect them. Neither knows about files:
:mod:`ftcomp.io.samples_csv` and :mod:`ftcomp.io.poses_csv` read and write them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ftcomp.arrays import freeze_field
from ftcomp.config_fields import FieldSpec
from ftcomp.errors import ParameterError
from ftcomp.frames import OrientationEncoding

if TYPE_CHECKING:  # scipy.spatial takes most of a second to import: a type here only
    from scipy.spatial.transform import Rotation

__all__ = ["SENSOR_RANGE", "WRENCH_COLUMNS", "PoseList", "Samples", "frozen_channels"]

#: The six wrench columns, in order: forces [N] then torques [N*m], sensor frame.
WRENCH_COLUMNS: tuple[str, ...] = ("fx", "fy", "fz", "tx", "ty", "tz")
#: The rule of a sensor's measuring range ``(force_N, torque_Nm)``, per axis: a reading at or
#: beyond it is saturated (a file's, a live loop's).
SENSOR_RANGE = FieldSpec(
    help="the sensor's measuring range per axis", unit="N, N*m", gt=0.0, length=2
)


def frozen_channels(
    channels: Mapping[str, object], n: int, source: str
) -> dict[str, NDArray[np.float64]]:
    """A copy of extra channels (name -> values), each a read-only float array of shape (n,)
    (:attr:`Samples.extras`); a name clashing with a wrench column or a wrong length is a
    ParameterError naming ``source``."""
    out: dict[str, NDArray[np.float64]] = {}
    for name, values in channels.items():
        if name in WRENCH_COLUMNS or not name:
            raise ParameterError(f"{source}: an extra channel may not be called {name!r}")
        array = np.array(values, dtype=float)
        if array.shape != (n,):
            raise ParameterError(
                f"{source}: extra channel {name!r} has shape {array.shape}, expected ({n},)"
            )
        array.setflags(write=False)
        out[name] = array
    return out


@dataclass(frozen=True)
class Samples:
    """F/T readings, each with the sensor's orientation.

    Attributes:
        wrench_sensor: [N, N*m], sensor frame, shape (N, 6).
        R_base_sensor: sensor orientation in the base frame, shape (N, 3, 3).
        encoding: the orientation encoding the readings came in (and are written back in).
        pose: pose id of each row as text, shape (N,), or None when the rows carry no pose id.
        t: time stamps [s], shape (N,), or None.
        header: the source file's column names, in order (empty when not from a file).
        rows: every data row's cells as read, for writing them back out unchanged (a file
            read by :func:`ftcomp.read_samples` gives a view that reads them on access).
        source: where the samples came from (a file path, "simulated cell"...), for messages.
        warnings: things that look wrong but were accepted (e.g. angles that look like radians).
        extras: the sensor's extra channels of each reading, by name with its unit
            (``temperature_C``, ``accel_x_m_s2``..., :class:`~ftcomp.hardware.protocols.
            ReportsExtraChannels`), each shape (N,); filled by a recording (written as the
            sample CSV's last columns), empty when read from a file (whose extra columns are
            in ``header`` and ``rows``).
    """

    wrench_sensor: NDArray[np.float64] = field(repr=False)
    R_base_sensor: NDArray[np.float64] = field(repr=False)
    encoding: OrientationEncoding
    pose: NDArray[np.str_] | None = field(default=None, repr=False)
    t: NDArray[np.float64] | None = field(default=None, repr=False)
    header: tuple[str, ...] = ()
    rows: Sequence[tuple[str, ...]] = field(default=(), repr=False)
    source: str = "<memory>"
    warnings: tuple[str, ...] = ()
    extras: Mapping[str, NDArray[np.float64]] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        n = len(self.wrench_sensor)
        freeze_field(self, "wrench_sensor", (n, 6))
        freeze_field(self, "R_base_sensor", (n, 3, 3))
        object.__setattr__(self, "extras", frozen_channels(self.extras, n, self.source))
        if self.pose is not None:
            freeze_field(self, "pose", (n,), dtype=str)
        if self.t is not None:
            freeze_field(self, "t", (n,))

    def __len__(self) -> int:
        return len(self.wrench_sensor)


@dataclass(frozen=True)
class PoseList:
    """Sensor orientations to visit (and optionally where).

    Attributes:
        ids: a label per pose (a file's ``pose`` column, or 1, 2, ...), shape (M,).
        rotations: ``R_base_sensor`` per pose (M rotations).
        source: where they came from, for messages.
        positions_base_m: sensor origin per pose, base frame [m], shape (M, 3); None: the
            recorder's default position for every pose.
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
            freeze_field(self, "positions_base_m", (len(self.ids), 3), finite=True)

    def __len__(self) -> int:
        return len(self.ids)
