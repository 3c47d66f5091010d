"""The demo's figures (matplotlib, Agg backend, PNG): one function per figure of the paper.

Every figure takes its title from the caller, who shows the same words as the caption in the
report, and keeps its legend outside the axes so no legend hides data.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D
from numpy.typing import NDArray
from scipy.ndimage import uniform_filter1d

if TYPE_CHECKING:
    from ftcomp.session.placement import PlacementResult

__all__ = [
    "TRUE_FORCE_LABEL",
    "plot_continuous_pose",
    "plot_fast_move",
    "plot_online_load",
    "plot_placement",
    "plot_table3",
    "plot_table4",
]

_AXES = ("fx [N]", "fy [N]", "fz [N]", "tx [N·m]", "ty [N·m]", "tz [N·m]")

#: Readings per moving mean of the sensed force when several runs share a plot (10 ms at 1 kHz).
_MEAN_READINGS = 10

#: What the dashed line of a placement plot shows, on the same axis and sign as the sensed force.
TRUE_FORCE_LABEL = "true: load weight − surface force"


def _save(fig: Any, path: str | os.PathLike[str], dpi: int = 110) -> None:
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def plot_continuous_pose(
    t: NDArray[np.float64],
    measured: NDArray[np.float64],
    compensation: NDArray[np.float64],
    error: NDArray[np.float64],
    path: str | os.PathLike[str],
    *,
    title: str,
) -> None:
    """Fig. 5: measured value, compensation value (drawn negated, as the paper) and error."""
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.8), sharex=True, layout="constrained")
    for k, ax in enumerate(axes.ravel()):
        ax.plot(t, measured[:, k], lw=0.8, label="measured")
        ax.plot(t, -compensation[:, k], lw=1.2, label="− compensation value")
        ax.plot(t, error[:, k], lw=0.8, label="error (measured − compensation value)")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_title(_AXES[k])
        ax.grid(alpha=0.3)
        if k >= 3:
            ax.set_xlabel("t [s]")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=9)
    fig.suptitle(title)
    _save(fig, path)


def plot_table3(
    ours: NDArray[np.float64],
    published: NDArray[np.float64],
    path: str | os.PathLike[str],
    *,
    labels: Sequence[str],
    title: str,
) -> None:
    """Table 3 as grouped bars: relative compensation error per pose and axis, per source."""
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.8), sharex=True, layout="constrained")
    poses = np.arange(1, ours.shape[0] + 1)
    width = 0.4
    for k, ax in enumerate(axes.ravel()):
        ax.bar(poses - width / 2, published[:, k], width, label=labels[0])
        ax.bar(poses + width / 2, ours[:, k], width, label=labels[1])
        ax.set_title(_AXES[k].split()[0])
        ax.set_ylabel("relative error [%]")
        ax.set_xticks(poses)
        ax.grid(alpha=0.3, axis="y")
        if k >= 3:
            ax.set_xlabel("pose")
    handles, names = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncol=2, fontsize=9)
    fig.suptitle(title)
    _save(fig, path)


def plot_table4(
    true_N: NDArray[np.float64],
    computed_N: NDArray[np.float64],
    published_true_N: NDArray[np.float64],
    published_computed_N: NDArray[np.float64],
    path: str | os.PathLike[str],
    *,
    title: str,
) -> None:
    """Table 4: computed against true load weight, simulation and paper, with relative errors."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.6), layout="constrained")
    ax1.plot(published_true_N, published_computed_N, "o", label="paper (real sensor)")
    ax1.plot(true_N, computed_N, "s", mfc="none", label="ftcomp (simulated cell)")
    lim = [0.0, float(max(true_N.max(), published_computed_N.max())) * 1.08]
    ax1.plot(lim, lim, "k--", lw=0.8, label="computed = true")
    ax1.set_xlabel("true weight [N]")
    ax1.set_ylabel("computed weight (Eq. 23) [N]")
    ax1.grid(alpha=0.3)
    idx = np.arange(1, len(true_N) + 1)
    ax2.bar(
        idx - 0.2,
        100 * np.abs(published_computed_N - published_true_N) / published_true_N,
        0.4,
        color="C0",
    )
    ax2.bar(idx + 0.2, 100 * np.abs(computed_N - true_N) / true_N, 0.4, color="C1")
    ax2.set_xlabel("load")
    ax2.set_ylabel("relative error δc [%]")
    ax2.set_xticks(idx)
    ax2.grid(alpha=0.3, axis="y")
    handles, names = ax1.get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncol=3, fontsize=9)
    fig.suptitle(title)
    _save(fig, path)


def plot_placement(
    results: Sequence[PlacementResult],
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
    """
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 8.2), sharex=True, layout="constrained")
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
            mean = uniform_filter1d(s["force_compensated_N"], _MEAN_READINGS, mode="nearest")
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
    _save(fig, path, dpi=100)


def plot_online_load(
    t: NDArray[np.float64],
    mass_kg: NDArray[np.float64],
    mass_std_kg: NDArray[np.float64],
    cog_m: NDArray[np.float64],
    contact_force_N: NDArray[np.float64],
    events: Sequence[tuple[str, float]],
    true_mass_kg: float,
    true_cog_m: NDArray[np.float64],
    path: str | os.PathLike[str],
    *,
    title: str,
) -> None:
    """Beyond the paper: an online load estimate (mass +- sigma, centre of gravity) over time,
    and the compensated force, with the detected grasp and release marked."""
    fig, axes = plt.subplots(3, 1, figsize=(10, 8), sharex=True, layout="constrained")
    ax = axes[0]
    ax.plot(t, mass_kg * 1e3, lw=1.0, label="estimate")
    ax.fill_between(
        t,
        (mass_kg - 3 * mass_std_kg) * 1e3,
        (mass_kg + 3 * mass_std_kg) * 1e3,
        alpha=0.3,
        label="± 3σ",
    )
    ax.axhline(true_mass_kg * 1e3, color="k", ls="--", lw=0.8, label="truth")
    ax.set_ylim(-0.2 * true_mass_kg * 1e3, 1.4 * true_mass_kg * 1e3)
    ax.set_ylabel("load mass [g]")
    ax = axes[1]
    for k, name in enumerate("xyz"):
        ax.plot(t, cog_m[:, k] * 1e3, lw=1.0, label=f"c{name}")
        ax.axhline(true_cog_m[k] * 1e3, color=f"C{k}", ls="--", lw=0.6)
    ax.set_ylim(-40.0, 1.3 * max(1e3 * float(np.abs(true_cog_m).max()), 10.0))
    ax.set_ylabel("centre of gravity [mm]")
    ax = axes[2]
    for k, name in enumerate("xyz"):
        ax.plot(t, contact_force_N[:, k], lw=0.6, label=f"f{name}")
    ax.set_ylabel("compensated force [N]")
    ax.set_xlabel("t [s]")
    for ax in axes:
        for kind, te in events:
            ax.axvline(te, color="r" if kind == "release" else "g", lw=0.8, alpha=0.7)
        ax.grid(alpha=0.3)
        ax.legend(loc="center left", bbox_to_anchor=(1.0, 0.5), fontsize=8)
    fig.suptitle(title)
    _save(fig, path)


def plot_fast_move(
    t: NDArray[np.float64],
    static_force_N: NDArray[np.float64],
    inertial_force_N: NDArray[np.float64],
    path: str | os.PathLike[str],
    *,
    title: str,
) -> None:
    """Beyond the paper: the contact-free compensated force of a fast move, static-only and
    with inertial compensation (thin: every reading; thick: 10 ms moving mean)."""
    fig, axes = plt.subplots(3, 1, figsize=(10, 7), sharex=True, layout="constrained")
    for k, ax in enumerate(axes):
        for force, label, color in (
            (static_force_N, "static only", "C3"),
            (inertial_force_N, "static + inertial", "C0"),
        ):
            ax.plot(t, force[:, k], lw=0.3, color=color, alpha=0.35)
            mean = uniform_filter1d(force[:, k], _MEAN_READINGS, mode="nearest")
            ax.plot(t, mean, lw=1.2, color=color, label=label)
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_ylabel(_AXES[k])
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=2, fontsize=9)
    fig.suptitle(title)
    _save(fig, path)
