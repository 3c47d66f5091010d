"""Surfaces a held object can be set down on: a sponge pad and a book, on a table.

The sponge is a rigid plate on a vertical slide joint with a linear spring and damper, so its
stiffness and damping are physical values [N/m], [N*s/m] (MuJoCo's negative ``solref`` is not in
N/m); two horizontal slides with the pad's shear stiffness let it shear as a foam pad does (a
load that sticks to it and moves sideways is not held rigidly). The plate's own weight is
cancelled (``gravcomp``), so at rest the contact force the sponge pushes on the object is
exactly ``stiffness_N_per_m * compression_m`` (its *spring law*). The book
is a fixed box with a stiff contact (MuJoCo time constant 8 ms: the stiffest that does not chatter
against the stiff position-servoed arm at the 1 ms step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final, Literal

from ftcomp.errors import ParameterError

__all__ = ["SURFACE_KINDS", "BookSpec", "SpongeSpec", "SurfaceKind", "TableSpec"]

SurfaceKind = Literal["none", "sponge", "book"]
#: Valid values of :data:`SurfaceKind`.
SURFACE_KINDS: Final[tuple[SurfaceKind, ...]] = ("none", "sponge", "book")


def _check_positive(owner: str, **values: float) -> None:
    for name, value in values.items():
        if not math.isfinite(value) or value <= 0.0:
            raise ParameterError(f"{owner}.{name} must be finite and > 0, got {value}")


@dataclass(frozen=True)
class TableSpec:
    """The table the surfaces lie on, in the *world* frame (z up, level).

    Attributes:
        center_xy_m: centre of the placement spot, world x and y [m].
        top_height_m: height of the table top above the floor [m].
        half_size_xy_m: half extents of the table top [m].
    """

    center_xy_m: tuple[float, float] = (0.45, 0.0)
    top_height_m: float = 0.15
    half_size_xy_m: tuple[float, float] = (0.25, 0.30)

    def __post_init__(self) -> None:
        _check_positive(
            "TableSpec",
            top_height_m=self.top_height_m,
            half_x=self.half_size_xy_m[0],
            half_y=self.half_size_xy_m[1],
        )
        if not all(math.isfinite(v) for v in self.center_xy_m):
            raise ParameterError(f"TableSpec.center_xy_m must be finite, got {self.center_xy_m}")


@dataclass(frozen=True)
class SpongeSpec:
    """A sponge pad: a plate on a spring-damper.

    Attributes:
        stiffness_N_per_m: spring constant of the pad [N/m].
        damping_N_s_per_m: damping of the pad [N*s/m].
        thickness_m: pad thickness [m]; the plate bottoms out at 90 % of it.
        half_size_xy_m: half extents of the pad [m].
        plate_mass_kg: mass of the moving plate [kg] (its weight is compensated).
        shear_stiffness_N_per_m: the pad's stiffness across its top, x and y [N/m] (a foam's
            shear modulus is about 0.4 of its Young's modulus: 0.4 of the compression
            stiffness for the same pad); ``math.inf``: rigid across (a plate on a vertical
            slide only, the cell before the shear).
    """

    stiffness_N_per_m: float = 1500.0
    damping_N_s_per_m: float = 15.0
    thickness_m: float = 0.03
    half_size_xy_m: tuple[float, float] = (0.08, 0.08)
    plate_mass_kg: float = 0.02
    shear_stiffness_N_per_m: float = 600.0

    def __post_init__(self) -> None:
        _check_positive(
            "SpongeSpec",
            stiffness_N_per_m=self.stiffness_N_per_m,
            thickness_m=self.thickness_m,
            plate_mass_kg=self.plate_mass_kg,
            half_x=self.half_size_xy_m[0],
            half_y=self.half_size_xy_m[1],
        )
        if math.isnan(self.shear_stiffness_N_per_m) or self.shear_stiffness_N_per_m <= 0.0:
            raise ParameterError(
                "SpongeSpec.shear_stiffness_N_per_m must be > 0 (inf: rigid across), "
                f"got {self.shear_stiffness_N_per_m}"
            )
        if not math.isfinite(self.damping_N_s_per_m) or self.damping_N_s_per_m < 0.0:
            raise ParameterError(
                f"SpongeSpec.damping_N_s_per_m must be finite and >= 0, "
                f"got {self.damping_N_s_per_m}"
            )


@dataclass(frozen=True)
class BookSpec:
    """A book: a stiff box.

    Attributes:
        thickness_m: its thickness [m].
        half_size_xy_m: half extents [m].
    """

    thickness_m: float = 0.025
    half_size_xy_m: tuple[float, float] = (0.10, 0.13)

    def __post_init__(self) -> None:
        _check_positive(
            "BookSpec",
            thickness_m=self.thickness_m,
            half_x=self.half_size_xy_m[0],
            half_y=self.half_size_xy_m[1],
        )
