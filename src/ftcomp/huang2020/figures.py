"""The paper's figures and the "beyond the paper" ones, drawn on :mod:`ftcomp.views.figures`.

One function per figure; each takes the numbers it draws and its title (the report shows the
same words as the caption).
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ftcomp.views.figures import WRENCH_AXIS_LABELS, moving_mean, new_figure, save_figure

__all__ = [
    "plot_continuous_pose",
    "plot_fast_move",
    "plot_online_load",
    "plot_table3",
    "plot_table4",
]


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
    fig = new_figure(12, 6.8)
    axes = fig.subplots(2, 3, sharex=True)
    for k, ax in enumerate(axes.ravel()):
        ax.plot(t, measured[:, k], lw=0.8, label="measured")
        ax.plot(t, -compensation[:, k], lw=1.2, label="− compensation value")
        ax.plot(t, error[:, k], lw=0.8, label="error (measured − compensation value)")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_title(WRENCH_AXIS_LABELS[k])
        ax.grid(alpha=0.3)
        if k >= 3:
            ax.set_xlabel("t [s]")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=9)
    fig.suptitle(title)
    save_figure(fig, path)


def plot_table3(
    ours: NDArray[np.float64],
    published: NDArray[np.float64],
    path: str | os.PathLike[str],
    *,
    labels: Sequence[str],
    title: str,
) -> None:
    """Table 3 as grouped bars: relative compensation error per pose and axis, per source."""
    fig = new_figure(12, 6.8)
    axes = fig.subplots(2, 3, sharex=True)
    poses = np.arange(1, ours.shape[0] + 1)
    width = 0.4
    for k, ax in enumerate(axes.ravel()):
        ax.bar(poses - width / 2, published[:, k], width, label=labels[0])
        ax.bar(poses + width / 2, ours[:, k], width, label=labels[1])
        ax.set_title(WRENCH_AXIS_LABELS[k].split()[0])
        ax.set_ylabel("relative error [%]")
        ax.set_xticks(poses)
        ax.grid(alpha=0.3, axis="y")
        if k >= 3:
            ax.set_xlabel("pose")
    handles, names = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncol=2, fontsize=9)
    fig.suptitle(title)
    save_figure(fig, path)


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
    fig = new_figure(11, 4.6)
    ax1, ax2 = fig.subplots(1, 2)
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
    save_figure(fig, path)


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
    fig = new_figure(10, 8)
    axes = fig.subplots(3, 1, sharex=True)
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
    save_figure(fig, path)


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
    fig = new_figure(10, 7)
    axes = fig.subplots(3, 1, sharex=True)
    for k, ax in enumerate(axes):
        for force, label, color in (
            (static_force_N, "static only", "C3"),
            (inertial_force_N, "static + inertial", "C0"),
        ):
            ax.plot(t, force[:, k], lw=0.3, color=color, alpha=0.35)
            ax.plot(t, moving_mean(force[:, k]), lw=1.2, color=color, label=label)
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_ylabel(WRENCH_AXIS_LABELS[k])
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=2, fontsize=9)
    fig.suptitle(title)
    save_figure(fig, path)
