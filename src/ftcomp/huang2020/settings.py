"""What the demo runs: its settings, shared by the demo and each of its sections."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ftcomp.errors import ParameterError

__all__ = ["Advance", "DemoSettings"]

#: Called once per finished step of the demo with a label of what was done (a progress bar).
Advance = Callable[[str], None]


@dataclass(frozen=True)
class DemoSettings:
    """What the demo runs.

    Attributes:
        samples_per_pose: readings per calibration pose (the paper: 500).
        weighing_samples_per_pose: readings per pose when weighing the Table-4 loads.
        continuous_duration_s: duration of the continuous orientation change [s].
        k13_values_mm_per_N: the K1 sweep on the sponge, K2 fixed at the sponge's default.
        k23_values_mm_per_s_N: the K2 sweep on the sponge, K1 fixed at the paper's 0.1 mm/N.
        seed: seeds every sensor's noise.
        beyond_no_grasp_s: motion without grasping in the "beyond the paper" section [s].
    """

    samples_per_pose: int
    weighing_samples_per_pose: int
    continuous_duration_s: float
    k13_values_mm_per_N: tuple[float, ...]
    k23_values_mm_per_s_N: tuple[float, ...]
    seed: int
    beyond_no_grasp_s: float = 60.0

    def __post_init__(self) -> None:
        if self.samples_per_pose < 1 or self.weighing_samples_per_pose < 1:
            raise ParameterError(
                "samples_per_pose and weighing_samples_per_pose must be >= 1, got "
                f"{self.samples_per_pose} and {self.weighing_samples_per_pose}"
            )
        if not self.continuous_duration_s > 0 or not self.beyond_no_grasp_s > 0:
            raise ParameterError(
                "continuous_duration_s and beyond_no_grasp_s must be > 0, got "
                f"{self.continuous_duration_s} and {self.beyond_no_grasp_s}"
            )
        if not self.k13_values_mm_per_N or not self.k23_values_mm_per_s_N:
            raise ParameterError("k13_values_mm_per_N and k23_values_mm_per_s_N need a value")
        if self.seed < 0:
            raise ParameterError(f"seed must be >= 0, got {self.seed}", field="seed")

    @classmethod
    def full(cls, seed: int) -> DemoSettings:
        """The paper's settings: 500 readings per pose, three-value gain sweeps."""
        return cls(500, 200, 4.0, (0.05, 0.1, 0.2), (0.5, 1.0, 2.0), seed)

    @classmethod
    def quick(cls, seed: int) -> DemoSettings:
        """A shorter run with the same sections (for tests)."""
        return cls(60, 30, 1.5, (0.05, 0.2), (1.0, 2.0), seed, beyond_no_grasp_s=9.0)

    @property
    def steps(self) -> int:
        """Progress steps: 2 calibrations, 2 continuous-pose steps, 6 loads, placement runs."""
        placement = 5 + len(self.k13_values_mm_per_N) + len(self.k23_values_mm_per_s_N)
        return 2 + 2 + 6 + placement + 3  # + 3: beyond the paper
