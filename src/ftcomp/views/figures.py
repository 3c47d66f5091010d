"""Plots as PNG files, drawn with matplotlib's object API (no pyplot, no global backend).

matplotlib is the extra ``report``; it is imported when a figure is first asked for, so
``import ftcomp.views`` works without it. Every figure takes its title from the caller, who
shows the same words as the caption in a report, and keeps its legend outside the axes so no
legend hides data.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from ftcomp.extras import require_extra

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "MEAN_READINGS",
    "TRUE_FORCE_LABEL",
    "WRENCH_AXIS_LABELS",
    "PlacementRunLike",
    "PlacementSettingsLike",
    "moving_mean",
    "new_figure",
    "plot_placement",
    "save_figure",
]

#: Axis labels of the six wrench components, in the order fx, fy, fz, tx, ty, tz.
WRENCH_AXIS_LABELS = ("fx [N]", "fy [N]", "fz [N]", "tx [N·m]", "ty [N·m]", "tz [N·m]")

#: Readings per moving mean of a noisy force drawn beside others (10 ms at 1 kHz).
MEAN_READINGS = 10

#: What the dashed line of a placement plot shows, on the same axis and sign as the sensed force.
TRUE_FORCE_LABEL = "true: load weight − surface force"


def new_figure(width_in: float, height_in: float) -> Figure:
    """A figure with constrained layout, not registered anywhere (no pyplot state).

    Raises:
        MissingExtraError: matplotlib is not installed (extra ``report``).
    """
    require_extra("report", "drawing a figure")
    from matplotlib.figure import Figure

    return Figure(figsize=(width_in, height_in), layout="constrained")


def save_figure(fig: Figure, path: str | os.PathLike[str], dpi: int = 110) -> None:
    """Write ``fig`` as a PNG (matplotlib's Agg renderer, chosen by the file's suffix)."""
    fig.savefig(path, dpi=dpi)


def moving_mean(values: NDArray[np.float64], readings: int = MEAN_READINGS) -> NDArray[np.float64]:
    """The centred moving mean of ``values`` over ``readings`` readings (edges held)."""
    from scipy.ndimage import uniform_filter1d

    return np.asarray(uniform_filter1d(values, readings, mode="nearest"), dtype=np.float64)


class PlacementSettingsLike(Protocol):
    """What :func:`plot_placement` reads of a placement run's settings."""

    @property
    def compensation(self) -> bool:
        """Whether the controller saw the compensated force (else the raw one)."""

    @property
    def decision_cutoff_hz(self) -> float:
        """Cut-off of the filter the placement decision reads [Hz]."""

    @property
    def band_N(self) -> float:
        """Half-width of the band the force settles in to count as placed [N]."""


class PlacementRunLike(Protocol):
    """What :func:`plot_placement` reads of a placement run (a placement result has it)."""

    @property
    def timeseries(self) -> Mapping[str, NDArray[np.float64]]:
        """Columns ``t_s``, ``force_compensated_N``, ``force_filtered_N``,
        ``force_true_contact_N``, ``displacement_mm``, ``velocity_mm_s``."""

    @property
    def config(self) -> PlacementSettingsLike:
        """The run's settings."""

    @property
    def metrics(self) -> Mapping[str, Any]:
        """The run's metrics; the plot reads ``load_weight_N`` [N]."""


def plot_placement(
    results: Sequence[PlacementRunLike],
    path: str | os.PathLike[str],
    *,
    labels: Sequence[str] | None = None,
    title: str = "",
) -> None:
    """Force, displacement and velocity over time (the paper's Fig. 6/7), one colour per run.

    The force panel has, per run, the sensed force along gravity (one run alone: every reading
    and the filtered force the placement decides on; several runs: each a 10-reading moving
    mean) and, dashed in the same colour, the
    true force on the same axis and sign: load weight − surface force (+ while the load hangs,
    0 when the surface carries exactly its weight, − when pressed into the surface).

    Raises:
        MissingExtraError: matplotlib is not installed (extra ``report``).
    """
    fig = new_figure(7.5, 8.2)
    from matplotlib.lines import Line2D

    axes = fig.subplots(3, 1, sharex=True)
    handles: list[Any] = []
    for i, result in enumerate(results):
        s, config = result.timeseries, result.config
        sensed = "compensated" if config.compensation else "raw (no compensation)"
        name = labels[i] if labels is not None else ""
        color = f"C{i}"
        if len(results) == 1:
            (each,) = axes[0].plot(
                s["t_s"], s["force_compensated_N"], lw=0.4, alpha=0.45, color=color
            )
            each.set_label(f"sensed, {sensed}, each reading")
            handles.append(each)
        if len(results) == 1:
            (line,) = axes[0].plot(s["t_s"], s["force_filtered_N"], lw=1.8, color=color)
            line.set_label(
                f"sensed, {sensed}, filtered ({config.decision_cutoff_hz:g} Hz: the placement "
                "decision)"
            )
        else:  # several runs: readings averaged over 10 ms (no lag worth showing)
            mean = moving_mean(s["force_compensated_N"])
            (line,) = axes[0].plot(s["t_s"], mean, lw=1.5, color=color)
            line.set_label(f"{name}: sensed, {sensed}")
        (true,) = axes[0].plot(
            s["t_s"],
            result.metrics["load_weight_N"] - s["force_true_contact_N"],
            "--",
            lw=1.2,
            color=color,
        )
        true.set_label(f"{name}: {TRUE_FORCE_LABEL}" if name else TRUE_FORCE_LABEL)
        handles += [line, true]
        axes[1].plot(s["t_s"], s["displacement_mm"], color=color)
        axes[2].plot(s["t_s"], s["velocity_mm_s"], color=color)
    band = results[0].config.band_N if results else 0.05
    axes[0].axhspan(-band, band, color="green", alpha=0.2)
    handles.append(
        Line2D([], [], color="green", alpha=0.4, lw=6, label=f"±{band:g} N: the placement band")
    )
    axes[0].axhline(0.0, color="k", lw=0.5)
    axes[0].set_ylabel("force along gravity [N]")
    axes[1].set_ylabel("descent [mm]")
    axes[2].set_ylabel("velocity, down [mm/s]")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.legend(handles=handles, loc="outside lower center", ncol=2, fontsize=7.5)
    if title:
        fig.suptitle(title)
    save_figure(fig, path, dpi=100)
