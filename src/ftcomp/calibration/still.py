"""Still segments in a continuous recording: where the sensor held a pose and the wrench settled.

Calibration needs readings at static poses, but a recording in motion (a ROS bag, a ``stream
--robot`` log, any user's log with a time column) holds everything: moves, stops, ringing after a
stop. :func:`find_still_segments` finds the still segments; :func:`still_samples` keeps their
readings as calibration samples, one pose id per segment (``ftcomp calibrate --still-segments``,
``ftcomp import-bag``). A *still segment* is found in two steps:

1. **Orientation.** A maximal run of readings whose orientation stays within ``angle_deg`` of
   the run's first reading, lasting at least ``min_duration_s``, with no gap in the readings
   (longer than ``window_s`` or five typical intervals).
2. **Wrench.** Readings at the start of the run are dropped while the wrench still settles: the
   run starts at the first reading from which the moving mean over ``window_s`` stays within
   ``force_N`` / ``torque_Nm`` of the mean over the run's second half. What is left must still
   last ``min_duration_s``; a run that never settles is reported, not used.

The orientation tolerance is small by default (0.03 deg) because ``ftcomp calibrate`` takes a
pose id as *one* orientation (readings of one pose may differ by at most 1e-3 in the Frobenius
norm of ``R``, about 0.04 deg).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.calibration.temperature import sample_temperatures
from ftcomp.errors import IdentificationError, ParameterError
from ftcomp.hardware.protocols import TEMPERATURE_CHANNEL
from ftcomp.samples import Samples

__all__ = [
    "Segment",
    "StillConfig",
    "StillSamples",
    "find_still_segments",
    "segment_rows",
    "still_samples",
]

_NS = 1_000_000_000


@dataclass(frozen=True)
class StillConfig:
    """Thresholds of still-segment detection (see the module docstring).

    Attributes:
        angle_deg: largest orientation change within a segment [deg].
        min_duration_s: shortest segment kept [s].
        window_s: moving window of the wrench-settled test [s].
        force_N: beyond the noise, the RMS deviation of each force axis from the segment's
            mean over a window [N].
        torque_Nm: ... of each torque axis [N*m].
    """

    angle_deg: float = 0.03
    min_duration_s: float = 0.5
    window_s: float = 0.1
    force_N: float = 0.1
    torque_Nm: float = 0.005

    def __post_init__(self) -> None:
        for name in ("angle_deg", "min_duration_s", "window_s", "force_N", "torque_Nm"):
            value = getattr(self, name)
            if not math.isfinite(value) or value <= 0.0:
                raise ParameterError(f"still-segment {name} must be finite and > 0, got {value}")

    def why_none(self, unsettled: int) -> str:
        """The end of a "no still segment" message: how many held orientations never settled,
        and the thresholds."""
        extra = f" ({unsettled} held orientations where the wrench never settled)"
        return (extra if unsettled else "") + f"; thresholds: {self.describe()}"

    def describe(self) -> str:
        """The thresholds in one line, for reports."""
        return (
            f"orientation within {self.angle_deg:g} deg for >= {self.min_duration_s:g} s; "
            f"wrench settled: over {self.window_s:g} s within noise + {self.force_N:g} N, "
            f"{self.torque_Nm:g} N*m"
        )


@dataclass(frozen=True)
class Segment:
    """One still segment.

    Attributes:
        start: index of its first reading; ``stop``: one past its last.
        t_start_ns: stamp of its first reading [ns]; ``duration_s``: its length [s].
        settled_from: index where the orientation run began (readings from there to ``start``
            were dropped while the wrench settled).
        R_base_sensor: the mean orientation, shape (3, 3).
        wrench_mean: [N, N*m], shape (6,); ``wrench_std``: the scatter of one reading, (6,).
    """

    start: int
    stop: int
    t_start_ns: int
    duration_s: float
    settled_from: int
    R_base_sensor: NDArray[np.float64] = field(repr=False)
    wrench_mean: NDArray[np.float64] = field(repr=False)
    wrench_std: NDArray[np.float64] = field(repr=False)

    @property
    def readings(self) -> int:
        """How many readings the segment holds."""
        return self.stop - self.start


def _orientation_runs(
    q: NDArray[np.float64], t_ns: NDArray[np.int64], config: StillConfig
) -> list[tuple[int, int]]:
    """Maximal runs within ``angle_deg`` of their first reading, long enough."""
    n = len(q)
    cos_half = math.cos(math.radians(config.angle_deg) / 2.0)
    min_ns = round(config.min_duration_s * _NS)
    # A gap in the readings ends a run: longer than the settle window, or five typical intervals.
    dt = np.diff(t_ns)
    max_gap = max(config.window_s * _NS, 5.0 * float(np.median(dt))) if n > 1 else 0.0
    gaps = np.flatnonzero(dt > max_gap)  # a gap between readings k and k + 1
    runs: list[tuple[int, int]] = []
    i = 0
    while i < n:
        g = int(np.searchsorted(gaps, i))
        limit = int(gaps[g]) + 1 if g < len(gaps) else n
        # |q_i . q_k| >= cos(angle / 2) <=> angle(R_i, R_k) <= angle_deg; search in growing blocks.
        end, block = i + 1, 64
        while end < limit:
            stop = min(limit, end + block)
            far = np.flatnonzero(np.abs(q[end:stop] @ q[i]) < cos_half)
            if far.size:
                end += int(far[0])
                break
            end, block = stop, block * 2
        if t_ns[end - 1] - t_ns[i] >= min_ns:
            runs.append((i, end))
            i = end
        else:
            i += 1
    return runs


def _settled_span(
    wrench: NDArray[np.float64], t_ns: NDArray[np.int64], config: StillConfig
) -> tuple[int, int]:
    """``(start, stop)``: the longest stretch where the wrench stays near the run's final mean.

    Over a moving window, the mean square deviation from the mean of the run's second half
    must stay within the sensor noise (a chi-square bound of five standard deviations) plus
    the tolerance squared: drift, ringing and a load still swinging all raise it.
    """
    n = len(wrench)
    duration = (t_ns[-1] - t_ns[0]) / _NS
    per_s = (n - 1) / duration if duration > 0 else 1.0
    width = max(2, min(n, round(config.window_s * per_s)))
    tail = wrench[n // 2 :].mean(axis=0)
    # The noise of one reading, from differences of neighbours (blind to slow drift and
    # ringing well below the sample rate): 1.4826 MAD / sqrt(2).
    d = np.diff(wrench, axis=0)
    noise_var = (1.4826 * np.median(np.abs(d - np.median(d, axis=0)), axis=0)) ** 2 / 2.0
    csum = np.vstack([np.zeros(6), np.cumsum((wrench - tail) ** 2, axis=0)])
    mean_square = (csum[width:] - csum[:-width]) / width  # over readings [k, k + width)
    tol = np.repeat([config.force_N, config.torque_Nm], 3)
    limit = noise_var * (1.0 + 5.0 * math.sqrt(2.0 / width)) + tol**2
    good = np.concatenate([[False], np.all(mean_square <= limit, axis=1), [False]])
    edges = np.flatnonzero(np.diff(good.astype(np.int8)))
    if edges.size == 0:
        return 0, 0
    # The longest stretch of good windows (k0 ... k1 - 1) covers readings k0 ... k1 + width - 2.
    starts, stops = edges[0::2], edges[1::2]
    longest = int(np.argmax(stops - starts))
    return int(starts[longest]), int(stops[longest]) + width - 1


def find_still_segments(
    t_ns: NDArray[np.int64],
    rotations: Rotation,
    wrench: NDArray[np.float64],
    config: StillConfig,
) -> tuple[list[Segment], int]:
    """Still segments of a recording (see the module docstring).

    Args:
        t_ns: stamps [ns], shape (N,), increasing.
        rotations: ``R_base_sensor`` of each reading (N rotations).
        wrench: readings [N, N*m], sensor frame, shape (N, 6).
        config: the thresholds.

    Returns:
        ``(segments, unsettled)``: the segments in time order, and how many orientation runs
        were dropped because the wrench did not settle within them.
    """
    q = rotations.as_quat()
    segments: list[Segment] = []
    unsettled = 0
    min_ns = round(config.min_duration_s * _NS)
    for a, b in _orientation_runs(q, t_ns, config):
        first, last = _settled_span(wrench[a:b], t_ns[a:b], config)
        start, b = a + first, a + last
        if b - start < 2 or t_ns[b - 1] - t_ns[start] < min_ns:
            unsettled += 1
            continue
        w = wrench[start:b]
        segments.append(
            Segment(
                start=start,
                stop=b,
                t_start_ns=int(t_ns[start]),
                duration_s=float((t_ns[b - 1] - t_ns[start]) / _NS),
                settled_from=a,
                R_base_sensor=rotations[start:b].mean().as_matrix(),
                wrench_mean=w.mean(axis=0),
                wrench_std=w.std(axis=0, ddof=1) if len(w) > 1 else np.zeros(6),
            )
        )
    return segments, unsettled


def segment_rows(segments: list[Segment]) -> tuple[NDArray[np.intp], NDArray[np.str_]]:
    """The recording's rows in the segments, and each row's pose id (``"k + 1"`` for
    ``segments[k]``)."""
    rows = np.concatenate([np.arange(s.start, s.stop) for s in segments])
    ids = np.concatenate([np.full(s.readings, str(k + 1)) for k, s in enumerate(segments)])
    return rows, ids


@dataclass(frozen=True)
class StillSamples:
    """What :func:`still_samples` kept.

    Attributes:
        samples: the readings of the still segments, pose ids ``"1"``, ``"2"``, ... by segment,
            their time stamps kept (``t`` [s]).
        segments: the segments, in time order (pose id ``k + 1`` for ``segments[k]``; indices
            into the recording).
        t0_ns: the recording's first stamp [ns] (``Segment.t_start_ns`` counts on its clock).
        readings_total: readings in the recording.
        unsettled: held orientations dropped because the wrench never settled.
        config: the thresholds used.
    """

    samples: Samples
    segments: tuple[Segment, ...]
    t0_ns: int
    readings_total: int
    unsettled: int
    config: StillConfig


def still_samples(samples: Samples, config: StillConfig) -> StillSamples:
    """The readings of a recording in motion that lie in still segments, one pose per segment.

    Args:
        samples: a recording with a time column (``t`` [s], non-decreasing) and no pose ids.
        config: the thresholds.

    Raises:
        IdentificationError: no ``t`` column, a pose column already, time that goes back, or
            no still segment (naming the thresholds).
    """
    source = samples.source
    if samples.t is None:
        raise IdentificationError(
            f"{source}: still segments need each reading's time: the file has no 't' column"
        )
    if samples.pose is not None:
        raise IdentificationError(
            f"{source}: has a 'pose' column already; still segments would replace it (drop "
            "the column to have the poses found from the motion)"
        )
    t_ns = np.round(np.asarray(samples.t, dtype=float) * _NS).astype(np.int64)
    back = np.flatnonzero(np.diff(t_ns) < 0)
    if back.size:
        raise IdentificationError(
            f"{source}: row {int(back[0]) + 2}: t goes back in time; still segments need the "
            "readings in time order"
        )
    rotations = Rotation.from_matrix(samples.R_base_sensor)
    segments, unsettled = find_still_segments(t_ns, rotations, samples.wrench_sensor, config)
    if not segments:
        raise IdentificationError(
            f"{source}: no still segment in {len(t_ns)} readings{config.why_none(unsettled)}"
        )
    rows, ids = segment_rows(segments)
    temperature = sample_temperatures(samples)  # kept for a bias that follows it
    kept = Samples(
        wrench_sensor=samples.wrench_sensor[rows],
        R_base_sensor=samples.R_base_sensor[rows],
        encoding=samples.encoding,
        pose=ids,
        t=np.asarray(samples.t, dtype=float)[rows],
        source=source,
        warnings=samples.warnings,
        extras={} if temperature is None else {TEMPERATURE_CHANNEL: temperature[rows]},
    )
    return StillSamples(kept, tuple(segments), int(t_ns[0]), len(t_ns), unsettled, config)
