"""What hangs below the F/T sensor: its sensing end, the paper's gripper, and graspable loads.

All positions are in the *sensor frame* (z along the tool axis, away from the flange) [m]; the
weights are what a scale would give times standard gravity [N]. The defaults are the paper's
(section 2.2.1): sensing end 0.835 N; sensing end plus gripper 3.153 N with the centre of gravity
at ``[0.0001, -0.0003, 0.0470]`` m; the loads of Table 4 and a 500 g mass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ftcomp import paper
from ftcomp.arrays import freeze_field, frozen_array
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import ParameterError

__all__ = [
    "LoadSpec",
    "ToolSpec",
    "paper_tool",
    "table4_loads",
]


def _positive(name: str, value: float) -> None:
    if not math.isfinite(value) or value <= 0.0:
        raise ParameterError(f"{name} must be finite and > 0, got {value}")


@dataclass(frozen=True)
class ToolSpec:
    """The sensor's sensing end and the gripper fixed to it.

    Attributes:
        sensing_end_weight_N: weight of the sensor's sensing end [N] (paper: 0.835 N).
        sensing_end_cog_m: its centre of gravity, sensor frame [m].
        total_weight_N: sensing end plus gripper [N] (paper: 3.153 N); used with a gripper.
        total_cog_m: centre of gravity of sensing end plus gripper, sensor frame [m].
        grasp_point_m: where a grasped load's centre of gravity sits, sensor frame [m].
        finger_length_m: length of the gripper's fingers along sensor z [m] (visual only).
    """

    sensing_end_weight_N: float = paper.SENSING_END_WEIGHT_N
    sensing_end_cog_m: NDArray[np.float64] = field(
        default_factory=lambda: np.array([0.0, 0.0, 0.008])
    )
    total_weight_N: float = paper.TOOL_WEIGHT_N
    total_cog_m: NDArray[np.float64] = field(
        default_factory=lambda: np.array(paper.CENTER_OF_GRAVITY_M)
    )
    grasp_point_m: NDArray[np.float64] = field(default_factory=lambda: np.array([0.0, 0.0, 0.125]))
    finger_length_m: float = 0.07

    def __post_init__(self) -> None:
        _positive("ToolSpec.sensing_end_weight_N", self.sensing_end_weight_N)
        _positive("ToolSpec.finger_length_m", self.finger_length_m)
        if not math.isfinite(self.total_weight_N) or (
            self.total_weight_N <= self.sensing_end_weight_N
        ):
            raise ParameterError(
                f"ToolSpec.total_weight_N must exceed the sensing end's "
                f"{self.sensing_end_weight_N} N, got {self.total_weight_N}"
            )
        for name in ("sensing_end_cog_m", "total_cog_m", "grasp_point_m"):
            freeze_field(self, name, (3,), finite=True)

    @property
    def gripper_weight_N(self) -> float:
        """The gripper alone [N]."""
        return self.total_weight_N - self.sensing_end_weight_N

    @property
    def gripper_cog_m(self) -> NDArray[np.float64]:
        """The gripper's own centre of gravity, sensor frame [m]: what makes the total's."""
        return (
            self.total_weight_N * self.total_cog_m
            - self.sensing_end_weight_N * self.sensing_end_cog_m
        ) / self.gripper_weight_N


@dataclass(frozen=True)
class LoadSpec:
    """A graspable box.

    Attributes:
        mass_kg: its mass [kg].
        half_size_m: half extents of the box along its x, y, z [m]; z is the tool axis when
            grasped, so the box's bottom face is ``half_size_m[2]`` beyond the grasp point.
        name: a label for reports.
    """

    mass_kg: float
    half_size_m: NDArray[np.float64] = field(default_factory=lambda: np.array([0.03, 0.03, 0.03]))
    name: str = "load"

    def __post_init__(self) -> None:
        _positive("LoadSpec.mass_kg", self.mass_kg)
        size = frozen_array(self.half_size_m, (3,), name="LoadSpec.half_size_m", finite=True)
        if np.any(size <= 0.0):
            raise ParameterError(f"LoadSpec.half_size_m must be > 0, got {size.tolist()}")
        object.__setattr__(self, "half_size_m", size)

    @classmethod
    def from_weight(cls, weight_N: float, name: str = "load") -> LoadSpec:
        """A load of the given weight [N] at standard gravity."""
        _positive("weight_N", weight_N)
        return cls(weight_N / STANDARD_GRAVITY_MPS2, name=name)

    @property
    def weight_N(self) -> float:
        """Its weight at standard gravity [N]."""
        return self.mass_kg * STANDARD_GRAVITY_MPS2


def paper_tool() -> ToolSpec:
    """The paper's gripper on the paper's sensor (section 2.2.1)."""
    return ToolSpec()


def table4_loads() -> tuple[LoadSpec, ...]:
    """The six loads of the paper's Table 4, by their true weights."""
    return tuple(
        LoadSpec.from_weight(w, name=f"table4_load{i}")
        for i, w in enumerate(paper.TABLE4_LOAD_WEIGHTS_N, start=1)
    )
