"""Bias drift and re-bias on a simulated recording, judged on held-out poses.

The simulated cell is opened by URI with a drifting sensor (``sim://?drift_N_per_min=...``) and
recorded through the same path as ``ftcomp record`` (:func:`~ftcomp.calibration.collect_live.
record_poses`, through the hardware protocols). The plan:

1. **Calibration recording**: ``poses`` D-optimal orientations (:mod:`ftcomp.calibration.design`,
   reachable by the cell), each visited ``passes`` times, every pass in a fresh random order, so
   each orientation is seen early and late. Every visit is its own pose id (``c03@2``: pose 3,
   pass 2), so the drift fit sees each visit at its own time.
2. **Held-out error** (:func:`held_out_by_pose`): leave one *orientation* out (all its visits),
   fit ``none`` / ``linear`` / ``quadratic`` bias drift to the other visits
   (:func:`~ftcomp.calibration.drift.calibrate_extended`), compensate the held-out readings
   at their times and average them per visit; the error is the RMS of those visit means over
   visits and force (torque) axes.
3. **Noise floor** (:func:`noise_floor`): the same RMS for a perfect model, the noise of a visit
   mean, from the readings' scatter within each visit (``pose_means``' variance of the mean;
   quantisation included). A held-out prediction also carries the fit's own error, so even the
   right model sits a little above the floor: ``floor * sqrt(1 + leverage)``.
4. **Re-bias** after ``wait_s`` more seconds of drift: a fresh full calibration (the same
   recording again, ``linear``), then :func:`~ftcomp.calibration.drift.rebias` of the first
   calibration from ``still_s`` seconds at one pose, then ``check_poses`` new orientations
   (random reachable ones, none of the calibration's) recorded once each right after. Each
   calibration's *collection time* is simulated seconds from the phase's start
   (``robot.now_ns()``) to its last reading's ``t``: moves, settling, recording.

Scoring the re-bias: a calibration's bias is the bias when it was made; the sensor goes on
drifting while the check poses are recorded, the same for every calibration. So the check error
that compares calibrations removes the drift since each calibration's bias was measured (the
fresh fit's: its last reading; a re-bias's: the mean time of its still readings), from the
simulated sensor's drift rate (the simulator's truth; a random walk, if set, stays in). The raw
errors (no truth used: the fresh calibration applying its drift model from ``t``, the re-biased
one constant) are reported beside them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.calibration.design import candidate_orientations, design_poses, nominal_theta
from ftcomp.calibration.identify import pose_means
from ftcomp.calibration.identify_extended import calibrate_extended
from ftcomp.calibration.rebias import rebias
from ftcomp.calibration_record import Calibration, DriftModel
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.errors import FtcompError, ParameterError
from ftcomp.hardware.registry import open_robot, open_sensor
from ftcomp.samples import PoseList, Samples
from ftcomp.session.pose_record import PoseRecord, samples_from_records
from ftcomp.session.robot_driven import record_poses
from ftcomp.sim.cell import COLLECTION_POSITION_BASE_M, SimCell

__all__ = [
    "DriftFits",
    "DriftSetup",
    "HeldOutError",
    "RebiasComparison",
    "held_out_by_pose",
    "noise_floor",
    "run_drift_experiment",
    "visit_errors",
]

_MODELS: tuple[DriftModel, ...] = ("none", "linear", "quadratic")


@dataclass(frozen=True)
class DriftSetup:
    """The simulated cell and the recording plan.

    Attributes:
        seed: sensor-noise seed (URI ``seed``) and the visit orders' generator.
        poses: calibration orientations (D-optimal, reachable).
        passes: visits of every orientation (each pass in a fresh random order), >= 2.
        readings_per_pose: readings averaged at each visit.
        move_duration_s: duration of each move [s].
        drift_N_per_min: force-bias drift rate [N/min], sensor frame.
        drift_Nm_per_min: torque-bias drift rate [N*m/min].
        drift_walk_N: force-bias random walk, its std after one minute [N] (URI ``drift_walk_N``).
        wait_s: further drift between the calibration and the re-bias [s].
        still_s: the re-bias recording at one pose [s].
        check_poses: new orientations recorded once each after the re-bias.
    """

    seed: int = 0
    poses: int = 12
    passes: int = 2
    readings_per_pose: int = 500
    move_duration_s: float = 1.0
    drift_N_per_min: tuple[float, float, float] = (0.4, -0.3, 0.35)
    drift_Nm_per_min: tuple[float, float, float] = (0.006, -0.004, 0.005)
    drift_walk_N: float = 0.0
    wait_s: float = 30.0
    still_s: float = 2.0
    check_poses: int = 12

    def __post_init__(self) -> None:
        if self.passes < 2 or self.poses < 4 or self.check_poses < 1:
            raise ParameterError("DriftSetup needs passes >= 2, poses >= 4, check_poses >= 1")
        if self.readings_per_pose < 2:
            raise ParameterError("DriftSetup.readings_per_pose must be >= 2")
        if not (self.move_duration_s > 0 and self.still_s > 0 and self.wait_s >= 0):
            raise ParameterError("DriftSetup: durations must be > 0 (wait_s >= 0)")

    @property
    def robot_uri(self) -> str:
        """The ``sim://`` robot URI (the paper's tilt and gripper, this sensor drift)."""

        force = ",".join(repr(float(v)) for v in self.drift_N_per_min)
        torque = ",".join(repr(float(v)) for v in self.drift_Nm_per_min)
        return (
            f"sim://?seed={self.seed}&drift_N_per_min={force}&drift_Nm_per_min={torque}"
            f"&drift_walk_N={float(self.drift_walk_N)!r}"
        )


@dataclass(frozen=True)
class HeldOutError:
    """RMS of per-visit mean errors over visits and axes: force [N], torque [N*m]."""

    force_N: float
    torque_Nm: float

    def over(self, floor: HeldOutError) -> tuple[float, float]:
        """This error in units of ``floor`` (force, torque)."""
        return self.force_N / floor.force_N, self.torque_Nm / floor.torque_Nm


def _rms(errors: NDArray[np.float64]) -> HeldOutError:
    return HeldOutError(
        float(np.sqrt(np.mean(errors[:, :3] ** 2))), float(np.sqrt(np.mean(errors[:, 3:] ** 2)))
    )


def noise_floor(samples: Samples) -> HeldOutError:
    """The RMS noise of a visit's mean reading (variance of the mean from the scatter within
    each visit, pooled over visits and axes): what a perfect model's held-out error would be."""
    _, _, _, _, var_mean = pose_means(samples)
    return _rms(np.sqrt(var_mean))


def visit_errors(
    calibration: Calibration,
    samples: Samples,
    *,
    apply_drift: bool,
    true_drift_since: tuple[NDArray[np.float64], float] | None = None,
) -> NDArray[np.float64]:
    """Per-visit mean of the compensated readings (reading - model), shape (V, 6).

    Args:
        calibration: the calibration to judge.
        samples: readings without contact, a ``pose`` id per visit, with ``t``.
        apply_drift: apply the calibration's drift model from each row's ``t``.
        true_drift_since: ``(rate_6 [N/s, N*m/s], t0 [s])``: remove the sensor's true drift
            since ``t0`` from the readings first (scoring with the simulator's truth).
    """
    _need_visits(samples)
    assert samples.t is not None and samples.pose is not None
    w = samples.wrench_sensor
    if true_drift_since is not None:
        rate, t0 = true_drift_since
        w = w - np.outer(samples.t - t0, rate)
    comp = GravityCompensator(calibration)
    contact = comp.compensate(w, samples.R_base_sensor, t_s=samples.t if apply_drift else None)
    _, inverse = np.unique(samples.pose, return_inverse=True)
    count = np.bincount(inverse).astype(float)
    sums = np.column_stack([np.bincount(inverse, contact[:, j]) for j in range(6)])
    return np.asarray(sums / count[:, None])


def _need_visits(samples: Samples) -> None:
    if samples.t is None or samples.pose is None:
        raise ParameterError(f"{samples.source}: need a pose id per visit and each reading's t")


def _subset(samples: Samples, keep: NDArray[np.bool_]) -> Samples:
    assert samples.pose is not None and samples.t is not None
    return Samples(
        samples.wrench_sensor[keep],
        samples.R_base_sensor[keep],
        samples.encoding,
        pose=samples.pose[keep],
        t=samples.t[keep],
        source=samples.source,
    )


def held_out_by_pose(
    samples: Samples, orientation: NDArray[np.str_], model: DriftModel
) -> HeldOutError:
    """Leave one orientation out (all its visits), fit ``model`` to the rest, predict its visits
    at their times; the RMS over all visits of all orientations.

    Args:
        samples: the recording (a pose id per visit, ``t``).
        orientation: each row's orientation label (several visits share one), shape (N,).
        model: the bias drift model fitted.
    """
    _need_visits(samples)
    errors = []
    for label in np.unique(orientation):
        out = orientation == label
        fit = calibrate_extended(_subset(samples, ~out), bias_drift=model, leave_one_out=False)
        errors.append(visit_errors(fit, _subset(samples, out), apply_drift=True))
    return _rms(np.concatenate(errors))


@dataclass(frozen=True)
class DriftFits:
    """The calibration recording and its held-out errors.

    Attributes:
        samples: the recording (pose id ``cNN@k`` per visit).
        duration_s: its collection time [s] (moves, settling, recording).
        bias_change_N: the true force-bias change over it per axis [N] (rate part).
        floor: the noise floor (:func:`noise_floor`).
        held_out: leave-one-orientation-out error per drift model.
        calibration: the ``linear`` fit to the whole recording (re-biased later).
    """

    samples: Samples = field(repr=False)
    duration_s: float
    bias_change_N: tuple[float, float, float]
    floor: HeldOutError
    held_out: dict[DriftModel, HeldOutError]
    calibration: Calibration = field(repr=False)


@dataclass(frozen=True)
class RebiasComparison:
    """A fresh calibration against a re-bias of the old one, on check poses recorded after.

    Errors ``fresh``, ``rebiased``, ``stale`` (the old calibration, constant bias, judged now)
    remove the true drift since each was finished; ``fresh_raw`` (its drift model applied from
    ``t``) and ``rebiased_raw`` (constant) use no truth.
    """

    fresh_time_s: float
    rebias_time_s: float
    floor: HeldOutError
    fresh: HeldOutError
    rebiased: HeldOutError
    stale: HeldOutError
    fresh_raw: HeldOutError
    rebiased_raw: HeldOutError

    @property
    def time_ratio(self) -> float:
        """Re-bias collection time over the fresh calibration's."""
        return self.rebias_time_s / self.fresh_time_s


class _Session:
    """The cell, its sensor and the recorder, with the phase timing."""

    def __init__(self, setup: DriftSetup) -> None:
        robot = open_robot(setup.robot_uri)
        if not isinstance(robot, SimCell):
            raise ParameterError(f"{setup.robot_uri}: not the simulated cell")
        self.cell = robot
        self.sensor = open_sensor("sim://", robot)
        self.setup = setup
        self.position = np.array(COLLECTION_POSITION_BASE_M)
        self.rate_6 = robot.sensor.spec.bias_drift_rate_per_s.copy()

    def reachable(self, R: NDArray[np.float64]) -> bool:
        try:
            self.cell.solve_ik(self.position, R)
        except FtcompError:
            return False
        return True

    def record(
        self, ids: list[str], R: NDArray[np.float64], n: int, what: str
    ) -> tuple[Samples, float]:
        """Visit ``R`` in order; the samples and the collection time [s]."""
        records: list[PoseRecord] = []
        start_ns = self.cell.now_ns()
        poses = PoseList(tuple(ids), Rotation.from_matrix(R), what)
        record_poses(
            self.cell,
            self.sensor,
            poses,
            n,
            records.append,
            position_base_m=self.position,
            move_duration_s=self.setup.move_duration_s,
        )
        samples = samples_from_records(records, what)
        assert samples.t is not None
        return samples, float(samples.t[-1] - start_ns * 1e-9)

    def interleaved(
        self, R: NDArray[np.float64], rng: np.random.Generator
    ) -> tuple[list[str], NDArray[np.float64], NDArray[np.str_]]:
        """Every orientation ``passes`` times, each pass in a fresh random order."""
        order = np.concatenate([rng.permutation(len(R)) for _ in range(self.setup.passes)])
        visit = np.zeros(len(R), dtype=int)
        ids = []
        for i in order:
            visit[i] += 1
            ids.append(f"c{i + 1:02d}@{visit[i]}")
        return ids, R[order], np.array([f"c{i + 1:02d}" for i in order])


def _orientations(
    session: _Session, setup: DriftSetup, rng: np.random.Generator
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """D-optimal calibration orientations and random reachable check orientations."""
    candidates = candidate_orientations(180.0, directions=100, spins=6)
    R_cal = design_poses(setup.poses, candidates, nominal_theta(), reachable=session.reachable)
    check: list[NDArray[np.float64]] = []
    for i in rng.permutation(len(candidates)):
        R = candidates[i]
        if len(check) == setup.check_poses:
            break
        if not np.any(np.all(np.isclose(R_cal, R), axis=(1, 2))) and session.reachable(R):
            check.append(R)
    return R_cal, np.array(check)


def _fits(session: _Session, R_cal: NDArray[np.float64], rng: np.random.Generator) -> DriftFits:
    """The calibration recording, its held-out errors and the ``linear`` fit to all of it."""
    n = session.setup.readings_per_pose
    ids, R, labels = session.interleaved(R_cal, rng)
    samples, duration = session.record(ids, R, n, "calibration recording")
    per_row = np.repeat(labels, n)
    change = session.rate_6[:3] * duration
    return DriftFits(
        samples,
        duration,
        (float(change[0]), float(change[1]), float(change[2])),
        noise_floor(samples),
        {m: held_out_by_pose(samples, per_row, m) for m in _MODELS},
        calibrate_extended(samples, bias_drift="linear", leave_one_out=False),
    )


def _compare(
    session: _Session,
    old: Calibration,
    R_cal: NDArray[np.float64],
    R_check: NDArray[np.float64],
    rng: np.random.Generator,
) -> RebiasComparison:
    """Wait, recalibrate afresh, re-bias ``old``, record the check poses and judge."""
    setup, cell, n = session.setup, session.cell, session.setup.readings_per_pose
    cell.step(round(setup.wait_s / cell.control_period_s))
    ids, R, _ = session.interleaved(R_cal, rng)
    fresh_samples, fresh_time = session.record(ids, R, n, "fresh calibration")
    fresh = calibrate_extended(fresh_samples, bias_drift="linear", leave_one_out=False)
    still_n = max(2, round(setup.still_s * cell.sensor.spec.output_rate_Hz))
    still, rebias_time = session.record(["still"], R_cal[:1], still_n, "re-bias still")
    rebiased = rebias(old, still)
    check, _ = session.record([f"h{i + 1}" for i in range(len(R_check))], R_check, n, "check")
    assert fresh_samples.t is not None and still.t is not None
    # The fresh fit's bias is at its last reading (t_ref); a re-bias averages its readings, so
    # its bias is the bias at their mean time.
    t_fresh, t_rebias = float(fresh_samples.t[-1]), float(still.t.mean())

    def judged(c: Calibration, t0: float) -> HeldOutError:
        return _rms(
            visit_errors(c, check, apply_drift=False, true_drift_since=(session.rate_6, t0))
        )

    return RebiasComparison(
        fresh_time_s=fresh_time,
        rebias_time_s=rebias_time,
        floor=noise_floor(check),
        fresh=judged(fresh, t_fresh),
        rebiased=judged(rebiased, t_rebias),
        stale=judged(old, t_rebias),
        fresh_raw=_rms(visit_errors(fresh, check, apply_drift=True)),
        rebiased_raw=_rms(visit_errors(rebiased, check, apply_drift=False)),
    )


def run_drift_experiment(setup: DriftSetup) -> tuple[DriftFits, RebiasComparison]:
    """Record, fit, hold out, wait, recalibrate and re-bias; see the module docstring.

    Raises:
        FtcompError: a pose the cell cannot reach, a sensor that goes silent (as a recording).
    """
    rng = np.random.default_rng(setup.seed)
    session = _Session(setup)
    with session.cell, session.sensor:
        R_cal, R_check = _orientations(session, setup, rng)
        fits = _fits(session, R_cal, rng)
        comparison = _compare(session, fits.calibration, R_cal, R_check, rng)
    return fits, comparison
