"""A calibration a person can look at: one self-contained HTML page (``calibrate --report``).

:func:`calibration_report` renders a :class:`~ftcomp.calibration_record.Calibration` (and the
samples it came from) as one page through :mod:`ftcomp.views.html`, its figures embedded as PNG
data (matplotlib, extra ``report``), so the one file is the whole report:

- the parameters, each with its standard error (and the bias drift and the mount when fitted);
- the gravity directions of the poses on the sphere in the sensor frame (two equal-area discs,
  the upper and the lower hemisphere), with the designed poses if given, and the largest region
  no pose covers;
- the regressor's condition number and what would improve it: the pose toward the middle of
  that region, and the condition number with it added;
- per-pose residuals of force and torque, and the leave-one-pose-out prediction errors;
- the bias drift over time when it was fitted.
"""

from __future__ import annotations

import base64
import io
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration.identify import pose_groups
from ftcomp.calibration.methods import force_regressor
from ftcomp.calibration.temperature import sample_temperatures
from ftcomp.calibration_record import Calibration, TemperatureBiasDrift
from ftcomp.errors import ParameterError
from ftcomp.io.atomic import atomic_write_text
from ftcomp.samples import WRENCH_COLUMNS, Samples
from ftcomp.views.figures import new_figure
from ftcomp.views.html import Figure, Mark, Section, Table, render_report

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure as MplFigure

__all__ = ["CoverageGap", "calibration_report", "coverage_gap", "write_calibration_report"]

#: Directions tried for the largest uncovered region (a Fibonacci sphere: about 2 deg apart).
GAP_GRID = 10_000


@dataclass(frozen=True)
class CoverageGap:
    """The largest region of the sphere of gravity directions (sensor frame) no pose covers.

    Attributes:
        direction_sensor: its middle, a unit vector in the sensor frame, (3,).
        angle_rad: from there to the nearest pose's gravity direction [rad].
        condition_number: the force regressor's condition number now.
        condition_with_pose: with a pose added whose gravity points to ``direction_sensor``
            (the nearest pose turned there the shortest way).
    """

    direction_sensor: NDArray[np.float64]
    angle_rad: float
    condition_number: float
    condition_with_pose: float


def gravity_directions_sensor(calibration: Calibration) -> NDArray[np.float64]:
    """Unit gravity direction of each pose in the sensor frame, (P, 3)."""
    g = calibration.model.gravity_base_N
    g_unit = g / np.linalg.norm(g)
    return np.asarray(np.einsum("pji,j->pi", calibration.R_base_sensor, g_unit))


def _fibonacci_sphere(n: int) -> NDArray[np.float64]:
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = math.pi * (3.0 - math.sqrt(5.0)) * k
    r = np.sqrt(1.0 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def _rotation_between(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """The shortest rotation taking unit vector ``a`` to unit vector ``b``, (3, 3)."""
    axis = np.cross(a, b)
    s, c = float(np.linalg.norm(axis)), float(np.dot(a, b))
    if s < 1e-12:
        if c > 0.0:
            return np.eye(3)
        other = np.eye(3)[int(np.argmin(np.abs(a)))]  # 180 deg about any axis normal to a
        n = np.cross(a, other)
        n /= np.linalg.norm(n)
        return 2.0 * np.outer(n, n) - np.eye(3)
    k = axis / s
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


def coverage_gap(calibration: Calibration) -> CoverageGap:
    """The largest region of gravity directions no pose covers, and what a pose there adds."""
    d = gravity_directions_sensor(calibration)
    grid = _fibonacci_sphere(GAP_GRID)
    nearest = np.arccos(np.clip(grid @ d.T, -1.0, 1.0)).min(axis=1)
    best = int(np.argmax(nearest))
    target = grid[best]
    k = int(np.argmax(d @ target))  # the pose nearest to it
    Q = _rotation_between(d[k], target)
    R = calibration.R_base_sensor
    R_new = R[k] @ Q.T  # its gravity direction R_new.T g = Q d_k = target
    cond_now = float(np.linalg.cond(force_regressor(R)))
    cond_new = float(np.linalg.cond(force_regressor(np.concatenate([R, R_new[None]]))))
    return CoverageGap(target, float(nearest[best]), cond_now, cond_new)


# ------------------------------------------------------------------------------------ figures
def _png(fig: MplFigure) -> str:
    """The figure as a ``data:`` URI (the page carries it)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def _disc_xy(d: NDArray[np.float64], upper: bool) -> NDArray[np.float64]:
    """Lambert equal-area projection of unit vectors onto the unit disc of one hemisphere."""
    z = d[:, 2] if upper else -d[:, 2]
    r = np.sqrt(np.clip(1.0 - z, 0.0, 2.0))  # 0 at the pole, 1 at the equator
    h = np.hypot(d[:, 0], d[:, 1])
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(h > 1e-12, r / h, 0.0)
    return np.column_stack([d[:, 0] * scale, d[:, 1] * scale])


def _disc(ax: Axes, upper: bool) -> None:
    t = np.linspace(0.0, 2.0 * math.pi, 181)
    for polar_deg in (30.0, 60.0, 90.0):
        r = math.sqrt(1.0 - math.cos(math.radians(polar_deg)))
        ax.plot(r * np.cos(t), r * np.sin(t), color="#bbb", lw=0.8 if polar_deg < 90 else 1.4)
    ax.plot([-1, 1], [0, 0], color="#ddd", lw=0.6)
    ax.plot([0, 0], [-1, 1], color="#ddd", lw=0.6)
    ax.text(1.04, 0.0, "+x", va="center", fontsize=8)
    ax.text(0.0, 1.04, "+y", ha="center", fontsize=8)
    ax.set_xlim(-1.15, 1.15)
    ax.set_ylim(-1.15, 1.15)
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title(f"gravity toward sensor {'+' if upper else '−'}z (hemisphere)", fontsize=9)


def sphere_figure(
    calibration: Calibration,
    gap: CoverageGap,
    title: str,
    designed_R_base_sensor: NDArray[np.float64] | None = None,
) -> MplFigure:
    """The poses' gravity directions (sensor frame) on two equal-area discs."""
    d = gravity_directions_sensor(calibration)
    fig = new_figure(8.0, 4.3)
    axes = fig.subplots(1, 2)
    designed = None
    if designed_R_base_sensor is not None:
        g = calibration.model.gravity_base_N
        designed = np.einsum("pji,j->pi", designed_R_base_sensor, g / np.linalg.norm(g))
    for ax, upper in zip(axes, (True, False), strict=True):
        _disc(ax, upper)
        side = d[:, 2] >= 0.0 if upper else d[:, 2] < 0.0
        xy = _disc_xy(d[side], upper)
        ax.scatter(xy[:, 0], xy[:, 1], s=28, color="#1f5fa8", zorder=3, label="recorded pose")
        for (x, y), pose in zip(xy, np.asarray(calibration.pose_ids)[side], strict=True):
            ax.annotate(str(pose), (x, y), xytext=(3, 3), textcoords="offset points", fontsize=7)
        if designed is not None:
            dside = designed[:, 2] >= 0.0 if upper else designed[:, 2] < 0.0
            dxy = _disc_xy(designed[dside], upper)
            style = {"s": 70, "facecolors": "none", "edgecolors": "#e08a00", "lw": 1.2}
            ax.scatter(dxy[:, 0], dxy[:, 1], zorder=2, label="designed pose", **style)
        if (gap.direction_sensor[2] >= 0.0) == upper:
            gxy = _disc_xy(gap.direction_sensor[None], upper)[0]
            label = f"largest gap ({math.degrees(gap.angle_rad):.0f}° from any pose)"
            ax.scatter(
                [gxy[0]], [gxy[1]], marker="*", s=160, color="#a4161a", zorder=4, label=label
            )
    handles, labels = {}, []
    for ax in axes:
        for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
            if label not in handles:
                handles[label] = h
                labels.append(label)
    fig.legend([handles[k] for k in labels], labels, loc="outside lower center", ncols=3)
    fig.suptitle(title, fontsize=10)
    return fig


def residual_figure(calibration: Calibration, title: str) -> MplFigure:
    """Per-pose residuals (force, torque), with the leave-one-pose-out errors' norms."""
    fig = new_figure(8.0, 5.2)
    axes = fig.subplots(2, 1, sharex=True)
    pose_ids = [str(p) for p in calibration.pose_ids]
    x = np.arange(len(pose_ids))
    colors = ("#1f5fa8", "#e08a00", "#17702a")
    for row, (ax, unit) in enumerate(zip(axes, ("N", "N·m"), strict=True)):
        res = calibration.residuals[:, 3 * row : 3 * row + 3]
        for k in range(3):
            label = WRENCH_COLUMNS[3 * row + k]
            ax.bar(x + (k - 1) * 0.22, res[:, k], 0.22, color=colors[k], label=f"{label} residual")
        loo = np.linalg.norm(calibration.loo_error[:, 3 * row : 3 * row + 3], axis=1)
        if np.any(np.isfinite(loo)):
            ax.plot(x, loo, "k_", ms=14, mew=2, label="|leave-one-out error|")
        ax.axhline(0.0, color="#888", lw=0.6)
        ax.set_ylabel(f"{'force' if row == 0 else 'torque'} [{unit}]")
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)
    axes[1].set_xticks(x, pose_ids, fontsize=8, rotation=90 if len(x) > 20 else 0)
    axes[1].set_xlabel("pose")
    fig.suptitle(title, fontsize=10)
    return fig


def drift_figure(calibration: Calibration, samples: Samples | None, title: str) -> MplFigure:
    """The fitted bias drift over time; per pose, the drift at its mean time plus its
    residual (where the data put the bias)."""
    drift = calibration.bias_drift
    if drift is None:
        raise ParameterError("the calibration has no bias drift to plot")
    heat = isinstance(drift, TemperatureBiasDrift)
    if isinstance(drift, TemperatureBiasDrift):  # the bias against the sensor's temperature
        t = np.linspace(drift.T_min_C, drift.T_max_C, 200)
        pose_t = _pose_temperatures(calibration, samples)
    else:
        t = np.linspace(drift.t_min_s, drift.t_max_s, 200)
        pose_t = _pose_times(calibration, samples)
    offset = drift.offset(t)
    fig = new_figure(8.0, 5.0)
    axes = fig.subplots(2, 1, sharex=True)
    colors = ("#1f5fa8", "#e08a00", "#17702a")
    for row, ax in enumerate(axes):
        for k in range(3):
            j = 3 * row + k
            ax.plot(t, offset[:, j], color=colors[k], label=f"{WRENCH_COLUMNS[j]} fitted")
            if pose_t is not None:
                points = drift.offset(pose_t)[:, j] + calibration.residuals[:, j]
                ax.plot(pose_t, points, "o", color=colors[k], ms=4)
        ref = "T_ref" if heat else "t_ref"
        ax.set_ylabel(f"bias − bias({ref}) [{'N' if row == 0 else 'N·m'}]")
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)
    axes[1].set_xlabel("sensor temperature [°C]" if heat else "t [s]")
    fig.suptitle(title, fontsize=10)
    return fig


def _pose_times(calibration: Calibration, samples: Samples | None) -> NDArray[np.float64] | None:
    """Each pose's mean reading time [s] (None without the samples' times and poses)."""
    if samples is None or samples.t is None or samples.pose is None:
        return None
    pose = np.asarray(samples.pose).astype(str)
    out = []
    for pid in calibration.pose_ids:
        mask = pose == str(pid)
        if not np.any(mask):
            return None
        out.append(float(np.mean(samples.t[mask])))
    return np.array(out)


def _pose_temperatures(
    calibration: Calibration, samples: Samples | None
) -> NDArray[np.float64] | None:
    """Each pose's mean sensor temperature [degC] (None without the samples' temperatures or
    when their poses are not the calibration's)."""
    temperature = sample_temperatures(samples) if samples is not None else None
    if samples is None or temperature is None:
        return None
    group, first = pose_groups(samples)
    if len(first) != len(calibration.pose_ids):
        return None
    return np.bincount(group, temperature) / np.bincount(group)


# ------------------------------------------------------------------------------------ tables
def _pm(value: float, se: float, digits: int) -> str:
    return f"{value:.{digits}f} ± {se:.{digits}f}"


def parameter_table(calibration: Calibration) -> Table:
    """Every identified parameter with its standard error."""
    m, se = calibration.model, calibration.std_errors
    rows: list[list[str]] = [
        ["tool weight G", "N", _pm(m.weight_N, se.weight_N, 4)],
        ["tool mass", "kg", _pm(m.mass_kg, se.weight_N / m.weight_N * m.mass_kg, 5)],
    ]
    for k, axis in enumerate("xyz"):
        rows.append(
            [
                f"centre of gravity {axis}",
                "mm",
                _pm(m.center_of_gravity_m[k] * 1e3, se.center_of_gravity_m[k] * 1e3, 3),
            ]
        )
    for k, axis in enumerate("xyz"):
        rows.append([f"force bias F0 {axis}", "N", _pm(m.force_bias_N[k], se.force_bias_N[k], 4)])
    for k, axis in enumerate("xyz"):
        rows.append(
            [f"torque bias M0 {axis}", "N·m", _pm(m.torque_bias_Nm[k], se.torque_bias_Nm[k], 5)]
        )
    rows.append(
        ["base tilt U", "deg", _pm(math.degrees(m.tilt_U_rad), math.degrees(se.tilt_U_rad), 4)]
    )
    rows.append(
        ["base tilt V", "deg", _pm(math.degrees(m.tilt_V_rad), math.degrees(se.tilt_V_rad), 4)]
    )
    drift = calibration.bias_drift
    if isinstance(drift, TemperatureBiasDrift):
        for j, name in enumerate(WRENCH_COLUMNS):
            unit = ("N" if j < 3 else "N·m") + "/°C"
            c, s = drift.slopes[j], drift.std_errors[j]
            rows.append([f"temperature slope {name}", unit, f"{c:.3e} ± {s:.1e}"])
    elif drift is not None:
        for order in range(drift.order):
            unit_t = "s" if order == 0 else "s²"
            for j, name in enumerate(WRENCH_COLUMNS):
                unit = ("N" if j < 3 else "N·m") + "/" + unit_t
                c, s = drift.coefficients[order, j], drift.std_errors[order, j]
                rows.append([f"drift c{order + 1} {name}", unit, f"{c:.3e} ± {s:.1e}"])
    mount = calibration.mount
    if mount is not None:
        names = ("yaw",) if mount.axes == "yaw" else ("rx", "ry", "rz")
        for name, a, s in zip(names, mount.angles_rad, mount.std_errors_rad, strict=True):
            what = "rotation vector " if mount.axes == "full" else ""
            rows.append([f"mount {what}{name}", "deg", _pm(math.degrees(a), math.degrees(s), 3)])
    note = "± one standard error"
    if isinstance(drift, TemperatureBiasDrift):
        note += f"; F0, M0 are the bias at T_ref = {drift.T_ref_C:.4g} °C"
    elif drift is not None:
        note += f"; F0, M0 are the bias at t_ref = {drift.t_ref_s:.6g} s"
    return Table("Identified parameters", ["parameter", "unit", "value"], rows, note=note)


def pose_table(calibration: Calibration, directions: NDArray[np.float64]) -> Table:
    """Per pose: readings, gravity direction, residuals and leave-one-out errors."""
    rows = []
    loo = calibration.loo_error
    for k, pose in enumerate(calibration.pose_ids):
        res_f = float(np.linalg.norm(calibration.residuals[k, :3]))
        res_m = float(np.linalg.norm(calibration.residuals[k, 3:]))
        loo_f = float(np.linalg.norm(loo[k, :3]))
        loo_m = float(np.linalg.norm(loo[k, 3:]))
        d = directions[k]
        rows.append(
            [
                str(pose),
                f"{int(calibration.readings_per_pose[k])}",
                f"{d[0]:+.2f} {d[1]:+.2f} {d[2]:+.2f}",
                f"{res_f:.4f}",
                f"{res_m:.5f}",
                f"{loo_f:.4f}" if math.isfinite(loo_f) else "–",
                f"{loo_m:.5f}" if math.isfinite(loo_m) else "–",
                f"{np.nanmax(calibration.relative_error_percent[k]):.2f}",
            ]
        )
    return Table(
        "Per pose",
        [
            *("pose", "readings", "gravity dir."),
            *("|F res| N", "|M res| N·m", "|F loo| N", "|M loo| N·m", "max rel. %"),
        ],
        rows,
        groups=[("", 3), ("residual", 2), ("leave-one-out", 2), ("Table 3", 1)],
        note="gravity direction: unit vector in the sensor frame; residual: mean reading minus "
        "the model; leave-one-out: the pose predicted by the model fitted without it",
        text_columns=3,
    )


def _condition_mark(condition: float) -> Mark:
    kind: str = "good" if condition < 10.0 else ("note" if condition < 30.0 else "bad")
    return Mark(f"{condition:.2f}", kind)  # type: ignore[arg-type]


def calibration_report(
    calibration: Calibration,
    *,
    source: str,
    samples: Samples | None = None,
    designed_R_base_sensor: NDArray[np.float64] | None = None,
) -> str:
    """The page (HTML) for ``calibration``, identified from ``source``.

    Args:
        calibration: the identified calibration.
        source: where the readings came from (the page's title names it).
        samples: the readings (their times place the poses on the drift plot).
        designed_R_base_sensor: the poses that were designed (e.g. ``ftcomp poses design``),
            drawn beside the recorded ones, (N, 3, 3).

    Raises:
        MissingExtraError: matplotlib is not installed (extra ``report``).
    """
    directions = gravity_directions_sensor(calibration)
    gap = coverage_gap(calibration)
    rms_f, rms_m = calibration.residual_rms
    loo_f, loo_m = calibration.loo_rms
    n_poses = len(calibration.pose_ids)
    intro = [
        f"Readings: {source} ({n_poses} poses, {int(calibration.readings_per_pose.sum())} "
        f"readings); method {calibration.method}.",
        f"Residual RMS: force {rms_f:.4f} N, torque {rms_m:.5f} N·m; leave-one-pose-out RMS: "
        + (
            f"force {loo_f:.4f} N, torque {loo_m:.5f} N·m."
            if math.isfinite(loo_f)
            else f"needs at least 4 poses ({n_poses} given)."
        ),
    ]
    g = gap.direction_sensor
    middle = f"{g[0]:+.2f} {g[1]:+.2f} {g[2]:+.2f}"
    coverage = Table(
        "Condition and coverage",
        ["quantity", "value"],
        [
            ["force regressor condition number (Eq. 7)", _condition_mark(gap.condition_number)],
            ["largest uncovered region: its middle (sensor frame)", middle],
            ["… its distance from the nearest pose", f"{math.degrees(gap.angle_rad):.1f} deg"],
            ["condition number with a pose added there", _condition_mark(gap.condition_with_pose)],
        ],
        note="a condition number near 1 separates bias from gravity best; poses that point "
        "gravity in many directions of the sensor frame lower it",
    )
    advice = (
        f"To improve the calibration, add a pose that turns gravity toward "
        f"[{g[0]:+.2f}, {g[1]:+.2f}, {g[2]:+.2f}] in the sensor frame (the red star): no pose "
        f"comes closer than {math.degrees(gap.angle_rad):.0f} deg to it, and with it the "
        f"condition number would go from {gap.condition_number:.2f} to "
        f"{gap.condition_with_pose:.2f}."
    )
    sphere = sphere_figure(
        calibration, gap, "Gravity directions of the poses, sensor frame", designed_R_base_sensor
    )
    residuals = residual_figure(calibration, "Per-pose residuals and leave-one-pose-out errors")
    sections = [
        Section("Parameters", tables=[parameter_table(calibration)], anchor="parameters"),
        Section(
            "Poses on the sphere",
            paragraphs=[advice],
            tables=[coverage],
            figures=[
                Figure(
                    _png(sphere),
                    "Gravity directions of the poses, sensor frame",
                    "Each dot is one pose's gravity direction seen from the sensor, on "
                    "equal-area discs (centre: gravity along the sensor's +z or −z axis, rim: "
                    "in its xy plane; circles every 30 deg). Evenly spread dots identify bias "
                    "and gravity best.",
                )
            ],
            anchor="sphere",
        ),
        Section(
            "Residuals",
            tables=[pose_table(calibration, directions)],
            figures=[
                Figure(
                    _png(residuals),
                    "Per-pose residuals and leave-one-pose-out errors",
                    "Bars: each pose's mean reading minus the model; black marks: the norm of "
                    "the error predicting that pose from a model fitted without it. A pose far "
                    "above the others is worth recording again.",
                )
            ],
            anchor="residuals",
        ),
    ]
    if isinstance(calibration.bias_drift, TemperatureBiasDrift):
        heat = calibration.bias_drift
        sections.append(
            Section(
                "Bias and temperature",
                paragraphs=[
                    "The bias was fitted as a linear function of the sensor's temperature over "
                    f"{heat.T_min_C:.4g} .. {heat.T_max_C:.4g} °C (held at the nearer end "
                    "outside it)."
                ],
                figures=[
                    Figure(
                        _png(drift_figure(calibration, samples, "Bias against temperature")),
                        "Bias against temperature",
                        "Lines: the fitted bias minus the bias at T_ref; dots: per pose, the "
                        "fitted bias at its mean temperature plus its residual.",
                    )
                ],
                anchor="drift",
            )
        )
    elif calibration.bias_drift is not None:
        drift = calibration.bias_drift
        sections.append(
            Section(
                "Bias drift",
                paragraphs=[
                    f"The bias was fitted as a {drift.name} function of time over "
                    f"{drift.t_min_s:.6g} .. {drift.t_max_s:.6g} s."
                ],
                figures=[
                    Figure(
                        _png(drift_figure(calibration, samples, "Bias drift over time")),
                        "Bias drift over time",
                        "Lines: the fitted bias minus the bias at t_ref; dots: per pose, the "
                        "fitted drift at its mean time plus its residual.",
                    )
                ],
                anchor="drift",
            )
        )
    if calibration.warnings:
        sections.append(Section("Warnings", paragraphs=list(calibration.warnings)))
    return render_report(f"Calibration of {os.path.basename(source)}", intro, sections)


def write_calibration_report(
    path: str | os.PathLike[str],
    calibration: Calibration,
    *,
    source: str,
    samples: Samples | None = None,
    designed_R_base_sensor: Sequence[NDArray[np.float64]] | NDArray[np.float64] | None = None,
) -> None:
    """Render :func:`calibration_report` and write it atomically to ``path``."""
    designed = None if designed_R_base_sensor is None else np.asarray(designed_R_base_sensor)
    page = calibration_report(
        calibration, source=source, samples=samples, designed_R_base_sensor=designed
    )
    atomic_write_text(path, page)
