"""Held-out accuracy of each bias model on a real recording and on the simulated realistic drift.

Run by hand (not a test)::

    .venv/bin/python bench/bench_accuracy.py --real DIR [--splits 30]
    .venv/bin/python bench/bench_accuracy.py --sim [--seeds 20]
    .venv/bin/python bench/bench_accuracy.py --recording SAMPLES.csv [--splits 30] [--twin-seed S]
    .venv/bin/python bench/bench_accuracy.py --sim-recordings 20 [--splits 30]

``--real DIR``: a directory with ``recorded_messages_pose_100.txt`` (x, y, z, qx, qy, qz, qw:
the sensor frame in the robot base frame) and ``recorded_messages_wrench_100.txt`` (fx..tz in
the *base* frame, as recorded there: turned into the sensor frame here) of the public recording
github.com/leledeyuan00/Gravity-Compensation-F-T-sensor (folder ``datas/``, an ATI Axia80 on an
arm, 100 static poses in recording order, one reading each; docs/calibration.md). The files
carry no times: pose k is given ``t = k`` seconds (the recording order is the clock).

For each model (``none``, ``quadratic``, ``stochastic``, ``stochastic+map``: with the general
linear sensor map, ``--sensor-map linear``; ``default``: the model ``ftcomp calibrate`` chooses
with no model flag, :func:`~ftcomp.calibration.identify_extended.identify`; ``--models`` a
comma-separated subset, the same splits), calibrate on a random subset of poses
and predict the others at their times through :func:`ftcomp.calibration.identify_extended.
calibrate_extended` and :class:`~ftcomp.compensation.compensator.GravityCompensator` (what
``ftcomp calibrate`` and ``ftcomp compensate`` run), RMS over the held-out poses, median over
random splits: 9 and 50 training poses anywhere in the session, and "after": 9 of the first 71
poses predicting the last 29.

``--sim``: the same on recordings with the simulated sensor's realistic drift
(:meth:`~ftcomp.sim.sensor.SensorSpec.realistic_drift`, from t = 0: the sensor just switched
on), 30 poses, 600 readings each, a pose every 2 s (as a robot-driven ``ftcomp record`` on the
twin; from switching on, and 30 min later) and every 29.5 s (the Axia80 lab's hand-timed
session), in units of one pose mean's noise; ``truth`` is the true tool, tilt and bias
trajectory (the floor, measured: about 1), ``drift told`` a constant-bias fit of the readings
with the true drift subtracted (the tool model's own share). Two kinds of split: ``spanning``,
the poses to calibrate include the session's first and last, so every held-out pose lies in
the calibration's time window (what a calibration of the whole session is used for), and
``random``, any poses, so some held-out poses lie before or after the calibration's window,
where its bias is held by design. Then a calibration used 10 min after its session, with and
without :class:`~ftcomp.compensation.bias_tracking.BiasTracker`.

``--recording SAMPLES.csv``: a recording with many readings a pose (``ftcomp record`` on
``ftcomp twin --realistic-drift 1``), spanning and random splits of 9 poses to calibrate and
the rest held out, in units of its floor: one pose mean's noise from the scatter within the
poses. The poses are taken in the order they were recorded. ``--twin-seed S``: the recording is
from ``ftcomp twin --realistic-drift 1 --seed S --tilt-deg=-0.204,-0.129``; compare its pose
means with the twin's own truth (the tool, the tilt and the sensor's drift, rebuilt in process)
and give the pure simulator's figure with the same drift, orientations and times.

``--sim-recordings SEEDS``: ``--recording``'s figure (the median over one recording's splits)
on SEEDS simulated recordings at the twin's pace, to set one twin recording's figure beside.

``--twin-recordings N [--first-seed S] [--folder DIR] [--design-tilt-deg D]``: make N twin
recordings the way docs/calibration.md does by hand (``ftcomp twin --realistic-drift 1 --seed
S`` in its own process on two loopback addresses, ``ftcomp record`` through ``ur-rtde`` and
``pynetft`` of 30 poses designed on the twin's UR5e within D deg of tilt, 60 by default; about
80 s each; a recording or design already in DIR is reused), then give each one's
figure, the figure of an estimator told the twin's true drift (what the noise of that recording
leaves), and over the recordings the median with a bootstrap 90 % interval and the share within
1.2x. One recording's figure moves by +-0.1 with its noise alone: the goal is judged on the
median over many.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ftcomp.calibration.identify import calibrate, pose_means
from ftcomp.calibration.identify_extended import calibrate_extended, identify
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.samples import Samples

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from calibration.sim_drift_data import subset

MODELS = ("none", "quadratic", "stochastic", "stochastic+map", "default")
#: The tilt the twin recordings of docs/calibration.md were made with (the paper's) [deg].
TWIN_TILT_DEG = (-0.204, -0.129)
#: Their pace: 30 designed poses, 600 readings each, ``--move-s 1.5``, 2.4 s a pose (measured).
TWIN_POSE_PERIOD_S = 2.4


def read_real(folder: Path) -> Samples:
    """The 100-pose recording as samples in the sensor frame, ``t`` = pose index [s]."""
    pose = np.loadtxt(folder / "recorded_messages_pose_100.txt", delimiter=",")
    wrench_base = np.loadtxt(folder / "recorded_messages_wrench_100.txt", delimiter=",")
    R = Rotation.from_quat(pose[:, 3:7]).as_matrix()  # [x, y, z, w]
    Rt = np.transpose(R, (0, 2, 1))
    force = np.einsum("nij,nj->ni", Rt, wrench_base[:, :3])
    torque = np.einsum("nij,nj->ni", Rt, wrench_base[:, 3:])
    n = len(pose)
    return Samples(
        np.hstack([force, torque]),
        R,
        "quaternion",
        pose=np.array([f"p{k}" for k in range(n)]),
        t=np.arange(n, dtype=float),
        source=str(folder),
    )


def held_out_rms(samples: Samples, train: np.ndarray, test: np.ndarray, model: str):
    """Force [N] and torque [N*m] RMS predicting ``test`` poses from ``train`` poses."""
    P = len(np.unique(samples.pose))
    fit_on, held = (
        subset(samples, np.isin(np.arange(P), train)),
        subset(samples, np.isin(np.arange(P), test)),
    )
    drift, _, mapped = model.partition("+")
    if model == "default":  # what ``ftcomp calibrate SAMPLES.csv`` fits: the model chosen
        result = identify(fit_on, leave_one_out=False)[0]
    elif model == "none":
        result = calibrate(fit_on, leave_one_out=False)
    else:
        result = calibrate_extended(
            fit_on, bias_drift=drift, sensor_map=mapped == "map", leave_one_out=False
        )  # type: ignore[arg-type]
    ids, R, wrench, _, _ = pose_means(held)
    t = np.array([held.t[held.pose == i].mean() for i in ids])
    e = GravityCompensator(result).compensate(wrench, R, t_s=t)
    return float(np.sqrt(np.mean(e[:, :3] ** 2))), float(np.sqrt(np.mean(e[:, 3:] ** 2)))


def real_table(samples: Samples, splits: int, models: tuple[str, ...] = MODELS) -> None:
    rng = np.random.default_rng(0)
    P = len(np.unique(samples.pose))
    cases = {
        "9 poses": lambda: np.split(rng.permutation(P), [9]),
        "50 poses": lambda: np.split(rng.permutation(P), [50]),
        "after (9 of first 71)": lambda: (rng.permutation(71)[:9], np.arange(71, P)),
    }
    print(f"| model | {' | '.join(cases)} |")
    print("|---|" + "---|" * len(cases))
    draws = {name: [make() for _ in range(splits)] for name, make in cases.items()}
    for model in models:
        cells = []
        for name in cases:
            errors = np.array([held_out_rms(samples, tr, te, model) for tr, te in draws[name]])
            f, m = np.median(errors, axis=0)
            cells.append(f"{f:.3f} N / {m:.4f} N·m")
        print(f"| {model} | {' | '.join(cells)} |")
        sys.stdout.flush()


def truth_rms(samples: Samples, test: np.ndarray, model, drift) -> float:
    """Force RMS [N] over the ``test`` poses' means for the *true* tool, tilt and bias
    trajectory: what is left is each pose mean's noise alone (the floor, measured)."""
    P = len(np.unique(samples.pose))
    held = subset(samples, np.isin(np.arange(P), test))
    assert held.t is not None and held.pose is not None
    error = held.wrench_sensor - model.predict(held.R_base_sensor) - drift(held.t)
    ids = np.unique(held.pose)
    means = np.array([error[held.pose == i].mean(axis=0) for i in ids])
    return float(np.sqrt(np.mean(means[:, :3] ** 2)))


#: (time between poses [s], session start after the sensor is switched on [s]): ``ftcomp
#: record`` robot-driven on the twin (measured, 1.8-2.0 s a pose), right after switching on and
#: 30 min later (the warm-up mostly over); the Axia80 lab's hand-timed session
#: (GP2025-07-22-22-06-02.txt: a pose every 29.5 s).
CASES = {
    "record (2 s a pose), just switched on": (2.0, 0.0),
    "record (2 s a pose), 30 min after switching on": (2.0, 1800.0),
    "lab (29.5 s a pose), just switched on": (29.5, 0.0),
}


def sim_table(seeds: int) -> None:
    from calibration.drift_data import NOISE_6
    from calibration.sim_drift_data import PER_POSE, session, spanning_split, used_later

    floor = NOISE_6[0] / np.sqrt(PER_POSE)
    print(
        f"held-out force error / one pose mean's noise ({floor:.4f} N), 30 poses, "
        f"median (min-max) over {seeds} seeds; 'spanning': the poses to calibrate include the "
        "session's first and last (every held-out pose inside its time window), 'random': any"
    )
    for label, (period, t0) in CASES.items():
        out: dict[tuple[int, str, str], list[float]] = {}
        for seed in range(seeds):
            model, samples, drift = session(seed, 30, period, t0)
            told = replace(samples, wrench_sensor=samples.wrench_sensor - drift(samples.t))
            rng, span_rng = np.random.default_rng(seed + 100), np.random.default_rng(seed + 200)
            for n in (9, 20):
                order = rng.permutation(30)
                splits = {
                    "spanning": spanning_split(span_rng, 30, n),
                    "random": np.split(order, [n]),
                }
                for kind, (train, test) in splits.items():
                    cell = (n, kind)
                    out.setdefault((*cell, "truth"), []).append(
                        truth_rms(samples, test, model, drift) / floor
                    )
                    f, _ = held_out_rms(told, train, test, "none")
                    out.setdefault((*cell, "drift told"), []).append(f / floor)
                    for name in MODELS:
                        f, _ = held_out_rms(samples, train, test, name)
                        out.setdefault((*cell, name), []).append(f / floor)
        print(f"  {label}:")
        for (n, kind, name), v in out.items():
            print(
                f"    {n:2d} poses {kind:8s} {name:15s} {np.median(v):5.2f} "
                f"({min(v):.2f}-{max(v):.2f})"
            )
        sys.stdout.flush()
    print("a stochastic calibration of 12 poses used 10 min after its session, still and free")
    print(
        "for the last 30 s: bias force error / the same floor, untracked, tracked, and "
        "re-biased from the first 0.5 s then tracked"
    )

    def cell(values: list[float], digits: int) -> str:
        return f"{np.median(values):.{digits}f} ({min(values):.{digits}f}-{max(values):.{digits}f})"

    for label, t0 in (("just switched on", 0.0), ("30 min after switching on", 1800.0)):
        uses = [used_later(seed, t0) for seed in range(seeds)]
        untracked = [u.untracked_N / floor for u in uses]
        tracked = [u.tracked_N / floor for u in uses]
        rebiased = [u.rebiased_tracked_N / floor for u in uses]
        updated = [u.updates / u.readings for u in uses]
        print(
            f"  {label}: untracked {cell(untracked, 1)}, tracked {cell(tracked, 2)} (readings "
            f"that updated {np.median(updated):.0%}), re-biased and tracked {cell(rebiased, 2)}"
        )


def in_recording_order(samples: Samples) -> Samples:
    """The poses renamed ``p0, p1, ...`` in the order they were recorded (by their first
    reading's time): the splits take the session's first and last pose by number, and a
    design's names (``d1, d10, d20, ...`` in the order ``record`` visits them) are not in time
    order."""
    assert samples.pose is not None and samples.t is not None
    names, first = np.unique(samples.pose, return_index=True)
    order = names[np.argsort(samples.t[first])]
    rank = {name: f"p{k}" for k, name in enumerate(order.tolist())}
    return replace(samples, pose=np.array([rank[name] for name in samples.pose.tolist()]))


def scatter_floor(samples: Samples) -> float:
    """One pose mean's force noise [N] from the scatter within the poses (RMS over poses and
    axes)."""
    return float(np.sqrt(np.mean(pose_means(samples)[4][:, :3])))


def recording_table(path: Path, splits: int, twin_seed: int | None = None) -> None:
    """Held-out force error of a recording with many readings a pose (e.g. ``ftcomp record``
    on ``ftcomp twin --realistic-drift 1``), 9 poses to calibrate, in units of its floor: one
    pose mean's noise from the scatter within the poses."""
    from calibration.sim_drift_data import spanning_split
    from ftcomp.io.samples_csv import read_samples

    samples = in_recording_order(read_samples(path))
    floor = scatter_floor(samples)
    rng = np.random.default_rng(0)
    P = len(np.unique(samples.pose))  # type: ignore[arg-type]
    draws = {
        "spanning": [spanning_split(rng, P, 9) for _ in range(splits)],
        "random": [np.split(rng.permutation(P), [9]) for _ in range(splits)],
    }
    print(f"{path}: {P} poses, floor {floor:.4f} N; 9 poses to calibrate, {splits} splits")
    for kind, pairs in draws.items():
        for name in ("none", "linear", "stochastic"):
            v = [held_out_rms(samples, train, test, name)[0] / floor for train, test in pairs]
            print(
                f"  {kind:8s} {name:10s} {np.median(v):5.2f} (10-90 %: "
                f"{np.percentile(v, 10):.2f}-{np.percentile(v, 90):.2f})"
            )
    if twin_seed is not None:
        twin_truth_table(samples, twin_seed, TWIN_TILT_DEG)


def spanning_median(
    samples: Samples, splits: int, model: str = "stochastic", floor: float | None = None
) -> float:
    """The median over ``splits`` spanning splits (9 poses to calibrate) of ``model``'s
    held-out force error, in units of the scatter floor (default: ``samples``' own):
    ``--recording``'s figure."""
    from calibration.sim_drift_data import spanning_split

    rng = np.random.default_rng(0)
    P = len(np.unique(samples.pose))  # type: ignore[arg-type]
    floor = scatter_floor(samples) if floor is None else floor
    pairs = [spanning_split(rng, P, 9) for _ in range(splits)]
    return float(np.median([held_out_rms(samples, tr, te, model)[0] / floor for tr, te in pairs]))


def figure_and_told(samples: Samples, drift, splits: int) -> tuple[float, float]:
    """The stochastic model's spanning figure, and *told*'s: a constant-bias fit of the same
    readings with the true ``drift(t)`` subtracted, both in units of ``samples``' floor."""
    floor = scatter_floor(samples)
    assert samples.t is not None
    known = replace(samples, wrench_sensor=samples.wrench_sensor - drift(samples.t))
    return spanning_median(samples, splits, floor=floor), spanning_median(
        known, splits, "none", floor
    )


def record_on_twin(seed: int, poses: Path, out: Path) -> None:
    """One recording as docs/calibration.md makes it: ``ftcomp twin --realistic-drift 1 --seed
    SEED`` in its own process on two loopback addresses of its own, ``ftcomp record`` of
    ``poses`` through ``ur-rtde`` and ``pynetft``, 600 readings a pose."""
    import subprocess

    from standins.twin_process import running_twin

    tilt = ",".join(str(v) for v in TWIN_TILT_DEG)
    args = ("--realistic-drift", "1", "--seed", str(seed), f"--tilt-deg={tilt}")
    with running_twin(f"bench-accuracy-{seed}", *args, seconds=600.0) as twin:
        subprocess.run(
            [
                sys.executable,
                "-m",
                "ftcomp",
                "record",
                "--robot",
                f"{twin.robot_uri}?max_speed_mm_s=250&max_accel_mm_s2=1500",
                "--sensor",
                twin.sensor_uri,
                "--poses",
                str(poses),
                "--samples-per-pose",
                "600",
                "--move-s",
                "1.5",
                "-o",
                str(out),
            ],
            check=True,
            stdout=subprocess.DEVNULL,
        )


def twin_recordings_table(
    count: int, first_seed: int, folder: Path, splits: int, max_tilt_deg: float
) -> None:
    """``count`` twin recordings (made in ``folder``, or reused from it) of 30 poses designed
    within ``max_tilt_deg`` of straight down, each one's figure beside an estimator told the
    twin's true drift, and the median over the recordings with a bootstrap interval."""
    import subprocess

    from standins.twin_process import running_twin

    folder.mkdir(parents=True, exist_ok=True)
    poses = folder / "poses.csv"
    if not poses.exists():  # designed on the twin's own UR5e: its IK within its joint limits
        with running_twin("bench-accuracy-design", seconds=120.0) as twin:
            design = f"--count 30 --position-mm 450 0 420 --max-tilt-deg {max_tilt_deg:g}"
            subprocess.run(
                [
                    *(sys.executable, "-m", "ftcomp", "poses", "design", *design.split()),
                    *("--robot", twin.robot_uri, "-o", str(poses)),
                ],
                check=True,
                stdout=subprocess.DEVNULL,
            )
    from ftcomp.io.samples_csv import read_samples

    figures, told = [], []
    print(
        f"twin recordings (30 poses of {poses}, 600 readings each), stochastic, 9 spanning "
        f"poses, median over {splits} splits each; 'told': a constant-bias fit of the readings "
        "with the twin's true drift subtracted (what the recording's noise alone leaves)"
    )
    for seed in range(first_seed, first_seed + count):
        path = folder / f"twin-seed{seed}.csv"
        if not path.exists():
            record_on_twin(seed, poses, path)
        samples = in_recording_order(read_samples(path))
        truth = TwinTruth(samples, seed, TWIN_TILT_DEG)
        figure, known = figure_and_told(samples, truth.drift, splits)
        figures.append(figure)
        told.append(known)
        print(f"  seed {seed:3d}: {figures[-1]:.2f}   told {told[-1]:.2f}")
        sys.stdout.flush()
    v, w = np.array(figures), np.array(told)
    rng = np.random.default_rng(0)
    boot = np.median(rng.choice(v, (10_000, len(v))), axis=1)
    low, high = np.percentile(boot, [5, 95])
    print(
        f"over {len(v)} recordings: median {np.median(v):.2f} (bootstrap 90 %: {low:.2f}-"
        f"{high:.2f}), {np.mean(v <= 1.2):.0%} within 1.2x; told: median {np.median(w):.2f}; "
        f"the estimator's own share, figure / told: median {np.median(v / w):.3f}"
    )
    simulated_at_design(truth.model, truth.R, count, splits)


def simulated_at_design(model, R: np.ndarray, seeds: int, splits: int) -> None:
    """The same figures on the pure simulator: this tool, these orientations, the realistic
    drift from the sensor's switch-on, a pose every :data:`TWIN_POSE_PERIOD_S`, one recording
    per seed (what the twin's figures are to be set beside)."""
    from calibration.drift_data import readings
    from calibration.sim_drift_data import PER_POSE, RealisticDrift

    figures, told = [], []
    for seed in range(seeds):
        drift = RealisticDrift(seed)
        samples = readings(
            np.random.default_rng(seed),
            model,
            R,
            PER_POSE,
            t0_s=4.0,
            pose_period_s=TWIN_POSE_PERIOD_S,
            rate_hz=1200.0,
            drift=drift,
        )
        figure, known = figure_and_told(samples, drift, splits)
        figures.append(figure)
        told.append(known)
    print(
        f"the simulator with this tool and these orientations, {seeds} recordings: median "
        f"{np.median(figures):.2f}, {np.mean(np.array(figures) <= 1.2):.0%} within 1.2x; "
        f"told: median {np.median(told):.2f}"
    )


def sim_recordings_table(seeds: int, splits: int) -> None:
    """``--recording``'s figure (one recording, the median over its splits) on simulated
    recordings at the twin's pace, one per seed: how far one recording's figure spreads."""
    from calibration.sim_drift_data import session

    v = [spanning_median(session(seed, 30, TWIN_POSE_PERIOD_S)[1], splits) for seed in range(seeds)]
    print(
        f"simulated recordings at {TWIN_POSE_PERIOD_S} s a pose from switch-on, 30 poses, "
        f"stochastic, 9 spanning poses, median over {splits} splits each: median over {seeds} "
        f"seeds {np.median(v):.2f} ({min(v):.2f}-{max(v):.2f}); "
        f"{np.mean(np.array(v) <= 1.2):.0%} of recordings within 1.2x"
    )


class TwinTruth:
    """A twin recording's truth, rebuilt in process from the twin's seed: the tool and the tilt
    (``model``), and the sensor's drift, a function of the seed and the sensor's clock alone,
    on the recording's clock (the offset between the two clocks fitted to the pose means)."""

    def __init__(self, samples: Samples, seed: int, tilt_deg: tuple[float, float]) -> None:
        from scipy.optimize import minimize_scalar

        from ftcomp.sim.cell_config import CellConfig
        from ftcomp.twin.serve import TwinConfig

        cell_config = CellConfig(realistic_drift=1.0, seed=seed, tilt_deg=tilt_deg)
        config = TwinConfig("127.0.0.1", "127.0.0.2", 1.0, cell=cell_config)
        cell = config.open_cell()  # the cell alone: nothing is bound
        self.model, self._sensor = cell.true_gravity_model(), cell.sensor
        self.rate_hz = self._sensor.spec.output_rate_Hz
        ids, R, wrench, _, var = pose_means(samples)
        t = np.array([samples.t[samples.pose == i].mean() for i in ids])  # type: ignore[index]
        order = np.argsort(t)
        self.R, self.se, self.t = R[order], np.sqrt(var[order]), t[order]
        left = wrench[order] - self.model.predict(self.R)

        def misfit(offset: float) -> float:
            return float(
                np.sum(((left - self.sensor_drift(self.t - offset))[:, :3] / self.se[:, :3]) ** 2)
            )

        self.offset_s = float(
            minimize_scalar(misfit, bounds=(self.t[0] - 600.0, self.t[0]), method="bounded").x
        )
        #: Each pose mean's error against the truth in its standard errors, (P, 6).
        self.z = (left - self.drift(self.t)) / self.se

    def sensor_drift(self, t_sensor_s: np.ndarray) -> np.ndarray:
        """The drift [N, N*m] at times on the sensor's clock (from its switch-on), (n, 6)."""
        ticks = np.rint(np.maximum(np.asarray(t_sensor_s, dtype=float), 0.0) * self.rate_hz)
        ticks = ticks.astype(int)
        first = int(ticks.min())
        return self._sensor.drift(first, int(ticks.max()) - first + 1)[ticks - first]

    def drift(self, t_s: np.ndarray) -> np.ndarray:
        """The drift at times on the recording's clock, (n, 6)."""
        return self.sensor_drift(np.asarray(t_s, dtype=float) - self.offset_s)


def twin_truth_table(samples: Samples, seed: int, tilt_deg: tuple[float, float]) -> None:
    """A twin recording against the twin's own truth (:class:`TwinTruth`); then the 9-pose
    figure of the pure simulator with that drift, those orientations and those times, for four
    draws of the noise (how far the noise alone moves one recording's figure)."""
    from calibration.drift_data import readings
    from calibration.sim_drift_data import PER_POSE

    truth = TwinTruth(samples, seed, tilt_deg)
    model, R, t, z, offset = truth.model, truth.R, truth.t, truth.z, truth.offset_s
    drift, rate = truth.sensor_drift, truth.rate_hz
    print(
        f"  against the twin's truth (seed {seed}; the recording starts {t[0] - offset:.1f} s "
        f"after the sensor's switch-on): pose means' z RMS, force "
        f"{np.sqrt(np.mean(z[:, :3] ** 2, axis=0)).round(2)}, torque "
        f"{np.sqrt(np.mean(z[:, 3:] ** 2, axis=0)).round(2)} (1 if the twin were its model)"
    )
    period = float(np.mean(np.diff(t)))
    figures = [
        spanning_median(
            readings(
                np.random.default_rng([seed, draw]),
                model,
                R,
                PER_POSE,
                t0_s=t[0] - offset,
                pose_period_s=period,
                rate_hz=rate,
                drift=drift,
            ),
            30,
        )
        for draw in range(4)
    ]
    print(
        f"  the simulator with this drift, these orientations and {period:.2f} s a pose, four "
        f"noise draws: spanning stochastic {', '.join(f'{v:.2f}' for v in figures)}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--real", type=Path, help="folder with the 100-pose recording")
    parser.add_argument("--splits", type=int, default=30)
    parser.add_argument(
        "--models", default=",".join(MODELS), help="--real's rows, comma-separated (default: all)"
    )
    parser.add_argument("--sim", action="store_true")
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--recording", type=Path, help="a samples CSV with many readings a pose")
    parser.add_argument(
        "--sim-recordings",
        type=int,
        metavar="SEEDS",
        help="--recording's figure on SEEDS simulated recordings at the twin's pace",
    )
    parser.add_argument(
        "--twin-seed",
        type=int,
        help="the recording is from `ftcomp twin --realistic-drift 1 --seed S "
        "--tilt-deg=-0.204,-0.129`: compare it with the twin's truth",
    )
    parser.add_argument(
        "--twin-recordings",
        type=int,
        metavar="N",
        help="make N twin recordings (about 80 s each) and give the figure over them",
    )
    parser.add_argument("--first-seed", type=int, default=0, help="--twin-recordings' first seed")
    parser.add_argument(
        "--design-tilt-deg",
        type=float,
        default=60.0,
        help="--twin-recordings' design: its --max-tilt-deg (default 60)",
    )
    parser.add_argument(
        "--folder",
        type=Path,
        default=Path("twin-recordings"),
        help="--twin-recordings' folder (recordings in it are reused; default ./twin-recordings)",
    )
    args = parser.parse_args()
    if args.recording is not None:
        recording_table(args.recording, args.splits, args.twin_seed)
    if args.real is not None:
        real_table(read_real(args.real), args.splits, tuple(args.models.split(",")))
    if args.sim:
        sim_table(args.seeds)
    if args.sim_recordings:
        sim_recordings_table(args.sim_recordings, args.splits)
    if args.twin_recordings:
        twin_recordings_table(
            args.twin_recordings, args.first_seed, args.folder, args.splits, args.design_tilt_deg
        )


if __name__ == "__main__":
    main()
