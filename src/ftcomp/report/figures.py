"""The demo's figures (matplotlib, Agg backend, PNG): one function per figure of the paper."""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from ftcomp.experiments.placement import PlacementResult

__all__ = ["plot_continuous_pose", "plot_placement", "plot_table3", "plot_table4"]

_AXES = ("fx [N]", "fy [N]", "fz [N]", "tx [N·m]", "ty [N·m]", "tz [N·m]")


def _save(fig: plt.Figure, path: str | os.PathLike[str]) -> None:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
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
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.5), sharex=True)
    for k, ax in enumerate(axes.ravel()):
        ax.plot(t, measured[:, k], lw=0.8, label="measured")
        ax.plot(t, -compensation[:, k], lw=1.2, label="− compensation value")
        ax.plot(t, error[:, k], lw=0.8, label="error (measured − compensation)")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_title(_AXES[k])
        ax.grid(alpha=0.3)
        if k >= 3:
            ax.set_xlabel("t [s]")
    axes[0, 0].legend(fontsize=8, loc="best")
    fig.suptitle(title)
    _save(fig, path)


def plot_table3(
    ours: NDArray[np.float64],
    published: NDArray[np.float64],
    path: str | os.PathLike[str],
    *,
    labels: Sequence[str],
) -> None:
    """Table 3 as grouped bars: relative compensation error per pose and axis, per source."""
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.5), sharex=True)
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
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(
        "Table 3: relative compensation error per pose (100·|measured − comp.|/|measured|)"
    )
    _save(fig, path)


def plot_table4(
    true_N: NDArray[np.float64],
    computed_N: NDArray[np.float64],
    published_true_N: NDArray[np.float64],
    published_computed_N: NDArray[np.float64],
    path: str | os.PathLike[str],
) -> None:
    """Table 4: computed against true load weight, simulation and paper, with relative errors."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax1.plot(published_true_N, published_computed_N, "o", label="paper (real sensor)")
    ax1.plot(true_N, computed_N, "s", mfc="none", label="ftcomp (simulated cell)")
    lim = [0.0, float(max(true_N.max(), published_computed_N.max())) * 1.08]
    ax1.plot(lim, lim, "k--", lw=0.8, label="computed = true")
    ax1.set_xlabel("true weight [N]")
    ax1.set_ylabel("computed weight (Eq. 23) [N]")
    ax1.grid(alpha=0.3)
    ax1.legend(fontsize=8)
    idx = np.arange(1, len(true_N) + 1)
    ax2.bar(
        idx - 0.2,
        100 * np.abs(published_computed_N - published_true_N) / published_true_N,
        0.4,
        label="paper",
    )
    ax2.bar(idx + 0.2, 100 * np.abs(computed_N - true_N) / true_N, 0.4, label="ftcomp")
    ax2.set_xlabel("load")
    ax2.set_ylabel("relative error δc [%]")
    ax2.set_xticks(idx)
    ax2.grid(alpha=0.3, axis="y")
    ax2.legend(fontsize=8)
    fig.suptitle("Table 4: weighing grasped loads through gravity compensation")
    _save(fig, path)


def plot_placement(
    results: Sequence[PlacementResult],
    path: str | os.PathLike[str],
    *,
    labels: Sequence[str] | None = None,
    title: str = "",
) -> None:
    """Force, displacement and velocity over time (the paper's Fig. 6/7), one line per run."""
    fig, axes = plt.subplots(3, 1, figsize=(7, 7.5), sharex=True)
    for i, result in enumerate(results):
        s = result.timeseries
        label = labels[i] if labels is not None else None
        line = axes[0].plot(s["t_s"], s["force_filtered_N"], label=label)[0]
        if len(results) == 1:
            axes[0].plot(
                s["t_s"],
                s["force_compensated_N"],
                lw=0.4,
                alpha=0.4,
                color=line.get_color(),
                label="compensated (raw samples)",
            )
            axes[0].plot(
                s["t_s"],
                s["force_true_contact_N"] - result.metrics["load_weight_N"],
                "--",
                lw=1,
                label="true press (contact - weight)",
            )
        axes[1].plot(s["t_s"], s["displacement_mm"], color=line.get_color())
        axes[2].plot(s["t_s"], s["velocity_mm_s"], color=line.get_color())
    band = results[0].config.band_N if results else 0.05
    axes[0].axhspan(-band, band, color="green", alpha=0.15, label=f"±{band:g} N band")
    axes[0].set_ylabel("force along gravity [N]")
    axes[1].set_ylabel("displacement [mm]")
    axes[2].set_ylabel("velocity [mm/s]")
    axes[2].set_xlabel("time [s]")
    axes[0].legend(fontsize=7)
    for ax in axes:
        ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
