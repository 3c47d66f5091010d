"""The F/T sensor model: what a real six-axis sensor makes of the wrench MuJoCo computes.

MuJoCo's ``force``/``torque`` sensors at ``ft_site`` report the wrench the parent (the sensor's
fixed housing) exerts on the child subtree (sensing end, gripper, what they carry), in the site
frame. A real sensor reports the opposite: the load the tool puts on it. So the *ideal* reading is
the negated MuJoCo sensor data; on top of it :class:`SensorSpec` adds, in this order, bias
``F0, M0``, Gaussian noise, quantisation to the resolution, and saturation at the range (a reading
beyond the overload limit also sets a latched ``overloaded`` flag). Readings come at the output rate
(1.2 kHz), stamped with the sensor's tick time; the physics state between ticks is held.

Optional realism, off by default: a per-axis gain error (the reading is ``(1 + gain) * ideal``;
the paper's sensor is specified at +-1.5 %) and a slow bias drift, functions of the sensor's tick
time: a constant rate, a random walk, a smooth wander (a Matérn 3/2 process with a time constant
of minutes, what a strain-gauge sensor's zero does as its temperature wanders) and a
temperature-like warm-up trend ``trend * (1 - exp(-t / tau))``. :meth:`SensorSpec.realistic_drift`
turns on the wander and the trend at the sizes and time constants a real ATI Axia80 showed (its
docstring gives the source); the wander is drawn on a
grid of knots from its own seeded generator, so the same seed gives the same drift however the
sensor is read.
"""

from __future__ import annotations

import collections
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp import paper
from ftcomp.arrays import freeze_field, frozen_array
from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import NothingToClose, WrenchSample

__all__ = ["SensorSpec", "SimWrenchSensor", "WanderKnots"]

_NOISE_BLOCK: Final = 4096
#: Readings a stream keeps for read_new (10 s at the paper's 1.2 kHz).
_PENDING_MAX: Final = 12_000
_NS_PER_S: Final = 1_000_000_000


@dataclass(frozen=True)
class SensorSpec:
    """A six-axis F/T sensor's specification; defaults are the paper's sensor.

    Attributes:
        force_range_N: measuring range of each force axis, +- [N] (readings saturate there).
        torque_range_Nm: measuring range of each torque axis, +- [N*m].
        overload_force_percent: overload limit in percent of the force range.
        overload_torque_percent: overload limit in percent of the torque range.
        resolution_fraction_of_range: quantisation step as a fraction of the range (1/2000);
            0 turns quantisation off.
        force_noise_std_N: standard deviation of the Gaussian force noise [N] per sample.
        torque_noise_std_Nm: standard deviation of the Gaussian torque noise [N*m] per sample.
        force_bias_N: zero offset F0 [N], sensor frame.
        torque_bias_Nm: zero offset M0 [N*m], sensor frame.
        output_rate_Hz: output rate [Hz].
        gain_error_fraction: per-axis gain error, the reading is ``(1 + g) * ideal``, shape (6,)
            (0.015 is +1.5 %); default zeros.
        bias_drift_rate_per_s: bias drift rate ``[N/s]*3 + [N*m/s]*3``, shape (6,); default zeros.
        bias_walk_per_sqrt_s: random-walk intensity of the bias, ``[N/sqrt(s)]*3 +
            [N*m/sqrt(s)]*3``, shape (6,): after ``t`` seconds the walk's standard deviation is
            this times ``sqrt(t)``; default zeros. Its own generator (seeded from the sensor's
            seed), so turning it on leaves the noise sequence unchanged.
        bias_wander_std: standard deviation of the smooth wander per axis ``[N]*3 + [N*m]*3``,
            (6,); default zeros (off).
        bias_wander_time_constant_s: its Matérn 3/2 time constant [s] (default 300 s).
        bias_trend: the warm-up trend's final amplitude per axis, (6,); default zeros (off).
        bias_trend_time_constant_s: its time constant [s] (default 1800 s).

    The paper gives no noise figure; the default noise is one resolution count (0.125 N,
    0.003 N*m), which also dithers the quantiser so that means of many readings are unbiased.
    """

    force_range_N: float = 250.0
    torque_range_Nm: float = 6.0
    overload_force_percent: float = 400.0
    overload_torque_percent: float = 200.0
    resolution_fraction_of_range: float = 1.0 / 2000.0
    force_noise_std_N: float = 0.125
    torque_noise_std_Nm: float = 0.003
    force_bias_N: NDArray[np.float64] = field(default_factory=lambda: np.array(paper.FORCE_BIAS_N))
    torque_bias_Nm: NDArray[np.float64] = field(
        default_factory=lambda: np.array(paper.TORQUE_BIAS_Nm)
    )
    output_rate_Hz: float = 1200.0
    gain_error_fraction: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    bias_drift_rate_per_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    bias_walk_per_sqrt_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    bias_wander_std: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    bias_wander_time_constant_s: float = 300.0
    bias_trend: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    bias_trend_time_constant_s: float = 1800.0

    def __post_init__(self) -> None:
        positive = (
            "force_range_N",
            "torque_range_Nm",
            "output_rate_Hz",
            "bias_wander_time_constant_s",
            "bias_trend_time_constant_s",
        )
        percent = ("overload_force_percent", "overload_torque_percent")
        nonnegative = ("resolution_fraction_of_range", "force_noise_std_N", "torque_noise_std_Nm")
        for name in positive:
            value = getattr(self, name)
            if not math.isfinite(value) or value <= 0.0:
                raise ParameterError(f"SensorSpec.{name} must be finite and > 0, got {value}")
        for name in percent:
            value = getattr(self, name)
            if not math.isfinite(value) or value < 100.0:
                raise ParameterError(f"SensorSpec.{name} must be >= 100 %, got {value}")
        for name in nonnegative:
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0.0:
                raise ParameterError(f"SensorSpec.{name} must be finite and >= 0, got {value}")
        if self.resolution_fraction_of_range >= 1.0:
            raise ParameterError("SensorSpec.resolution_fraction_of_range must be below 1")
        for name in ("force_bias_N", "torque_bias_Nm"):
            freeze_field(self, name, (3,), finite=True)
        for name in (
            "gain_error_fraction",
            "bias_drift_rate_per_s",
            "bias_walk_per_sqrt_s",
            "bias_wander_std",
            "bias_trend",
        ):
            freeze_field(self, name, (6,), finite=True)
        if np.any(self.bias_wander_std < 0.0):
            raise ParameterError("SensorSpec.bias_wander_std must be >= 0 per axis")
        if np.any(np.abs(self.gain_error_fraction) >= 0.5):
            raise ParameterError("SensorSpec.gain_error_fraction must be within +-0.5 per axis")
        if np.any(self.bias_walk_per_sqrt_s < 0.0):
            raise ParameterError("SensorSpec.bias_walk_per_sqrt_s must be >= 0 per axis")

    @property
    def drifts(self) -> bool:
        """Whether the bias drifts (a rate, a random walk, a wander or a trend is set)."""
        return bool(
            np.any(self.bias_drift_rate_per_s)
            or np.any(self.bias_walk_per_sqrt_s)
            or np.any(self.bias_wander_std)
            or np.any(self.bias_trend)
        )

    def realistic_drift(self, scale: float = 1.0) -> SensorSpec:
        """The same sensor with the bias drift of a real one, times ``scale``: a smooth wander
        of 0.03-0.05 N and 0.001-0.002 N*m per axis (Matérn 3/2, time constant 10 min) and a
        warm-up trend that settles by 2.3 N in z, 0.02-0.13 N across, 0.001-0.005 N*m (time
        constant 15 min, from the sensor's t = 0 as if just switched on).

        Source: the public recording of an ATI Axia80 on an arm
        (github.com/leledeyuan00/Gravity-Compensation-F-T-sensor, ``datas/``, commit 139efe1;
        docs/calibration.md). ``--bias-drift stochastic`` on its 100 poses (REML) finds a
        wander of 0.053, 0.027 N and 0.0009-0.0022 N*m with a time constant of 22.6 poses, and
        a bias that fell over the session by 2.27 N in z (most of it in the first half), 0.13
        and 0.02 N across and 0.001-0.005 N*m. The file has no times: the same lab's recording
        ``GP2025-07-22-22-06-02.txt`` (same sensor, with times) takes a pose every 29.5 s,
        which makes 22.6 poses about 11 min and the fall about 25 min. ATI's manuals name drift
        but publish no figure for it.
        """
        return replace(
            self,
            bias_wander_std=scale * np.array([0.05, 0.03, 0.05, 0.001, 0.002, 0.0013]),
            bias_wander_time_constant_s=600.0,
            bias_trend=scale * np.array([-0.13, -0.02, -2.3, -0.001, -0.001, -0.005]),
            bias_trend_time_constant_s=900.0,
        )

    def ideal(self) -> SensorSpec:
        """The same sensor without noise and quantisation (bias, range and rate kept)."""
        return replace(
            self, force_noise_std_N=0.0, torque_noise_std_Nm=0.0, resolution_fraction_of_range=0.0
        )

    def unbiased(self) -> SensorSpec:
        """The same sensor with zero bias."""
        return replace(self, force_bias_N=np.zeros(3), torque_bias_Nm=np.zeros(3))

    # The per-axis vectors are computed once (a spec is frozen): the sensor model reads them
    # on every conversion, and rebuilding them there was most of the twin's step.
    @cached_property
    def range_6(self) -> NDArray[np.float64]:
        """Measuring range per axis ``[F, F, F, M, M, M]``, shape (6,)."""
        return frozen_array(np.repeat([self.force_range_N, self.torque_range_Nm], 3))

    @cached_property
    def step_6(self) -> NDArray[np.float64]:
        """Quantisation step per axis, shape (6,) (zeros: no quantisation)."""
        return frozen_array(self.range_6 * self.resolution_fraction_of_range)

    @cached_property
    def noise_std_6(self) -> NDArray[np.float64]:
        """Noise standard deviation per axis, shape (6,)."""
        return frozen_array(np.repeat([self.force_noise_std_N, self.torque_noise_std_Nm], 3))

    @cached_property
    def overload_6(self) -> NDArray[np.float64]:
        """Overload limit per axis, shape (6,)."""
        percent = np.repeat([self.overload_force_percent, self.overload_torque_percent], 3)
        return frozen_array(self.range_6 * percent / 100.0)

    @cached_property
    def bias_6(self) -> NDArray[np.float64]:
        """``[F0, M0]``, shape (6,)."""
        return frozen_array(np.concatenate([self.force_bias_N, self.torque_bias_Nm]))

    def apply(
        self, ideal_wrench: ArrayLike, standard_normal: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Turn ideal wrenches into readings.

        Args:
            ideal_wrench: the load on the sensor [N, N*m], sensor frame, shape (6,) or (N, 6).
            standard_normal: standard normal draws of the same shape (scaled here by the noise).

        Returns:
            ``(readings, overloaded)``: readings of the same shape; overloaded per row (any axis
            beyond its overload limit).
        """
        ideal = np.asarray(ideal_wrench, dtype=float)
        loaded = ideal * (1.0 + self.gain_error_fraction) + self.bias_6
        overloaded = np.any(np.abs(loaded) > self.overload_6, axis=-1)
        reading = loaded + np.asarray(standard_normal, dtype=float) * self.noise_std_6
        step = self.step_6
        if self.resolution_fraction_of_range > 0.0:
            reading = np.round(reading / step) * step
        rng = self.range_6
        return np.clip(reading, -rng, rng), np.asarray(overloaded)


class WanderKnots:
    """A Matérn 3/2 process per axis, drawn exactly on a grid of knots and read between them
    by linear interpolation (the process is smooth: at a knot spacing of 1/100 of its time
    constant the interpolation error is below 1e-4 of its size).

    Args:
        std: its stationary standard deviation per axis, (6,).
        time_constant_s: its length scale [s].
        seed: seeds its own generator; knots are drawn in order as time advances, so the
            values depend on the seed alone.
    """

    def __init__(self, std: NDArray[np.float64], time_constant_s: float, seed: object) -> None:
        self.step_s = min(1.0, time_constant_s / 100.0)
        lam = math.sqrt(3.0) / time_constant_s
        d = self.step_s
        e = math.exp(-lam * d)
        self._phi = e * np.array([[1.0 + lam * d, d], [-lam * lam * d, 1.0 - lam * d]])
        p_inf = np.diag([1.0, lam * lam])
        self._q_chol = np.linalg.cholesky(p_inf - self._phi @ p_inf @ self._phi.T + 1e-15 * p_inf)
        self._std = np.asarray(std, dtype=float)
        self._rng = np.random.default_rng(seed)  # type: ignore[arg-type]
        self._state = np.linalg.cholesky(p_inf) @ self._rng.standard_normal((2, 6))  # unit std
        self._values: list[NDArray[np.float64]] = [self._state[0] * self._std]

    def _extend(self, knots: int) -> None:
        while len(self._values) < knots:
            self._state = self._phi @ self._state + self._q_chol @ self._rng.standard_normal((2, 6))
            self._values.append(self._state[0] * self._std)

    def at(self, t_s: NDArray[np.float64]) -> NDArray[np.float64]:
        """The wander at times ``t_s`` [s] (>= 0), (N, 6)."""
        x = np.maximum(np.asarray(t_s, dtype=float), 0.0) / self.step_s
        k = np.floor(x).astype(int)
        self._extend(int(k.max()) + 2)
        values = np.asarray(self._values[int(k.min()) : int(k.max()) + 2])
        i = k - int(k.min())
        frac = (x - k)[:, None]
        return values[i] * (1.0 - frac) + values[i + 1] * frac


class SimWrenchSensor(NothingToClose):
    """The simulated sensor: implements :class:`ftcomp.hardware.protocols.WrenchSensor`.

    Args:
        spec: the sensor's specification.
        ideal_wrench: returns the current ideal load on the sensor [N, N*m], shape (6,).
        clock: returns the current simulation time [s].
        seed: seeds the noise (``np.random.default_rng``); one noise draw per new output tick,
            so the same sequence of calls gives the same readings.
    """

    def __init__(
        self,
        spec: SensorSpec,
        ideal_wrench: Callable[[], NDArray[np.float64]],
        clock: Callable[[], float],
        *,
        seed: int | None,
    ) -> None:
        self._spec = spec
        self._ideal = ideal_wrench
        self._clock = clock
        self._rng = np.random.default_rng(seed)
        self._block = np.empty((0, 6))
        self._next = 0
        self._last_tick = -1
        self._last: WrenchSample | None = None
        # After the first read_new: every tick is kept until read_new hands it out (the newest
        # _PENDING_MAX, as a driver's bounded buffer: a loop that stops calling read_new
        # does not grow it without end).
        self._streaming = False
        self._pending: collections.deque[WrenchSample] = collections.deque(maxlen=_PENDING_MAX)
        self._overloaded = False
        # Hot-path copies (read() runs every control cycle).
        self._bias = spec.bias_6
        self._std = spec.noise_std_6
        self._range = spec.range_6
        self._range_ft = (spec.force_range_N, spec.torque_range_Nm)
        # (step, 1 / step) per axis as floats, or None without quantisation.
        step = spec.step_6
        self._quantum: tuple[list[float], list[float]] | None = (
            (step.tolist(), (1.0 / step).tolist())
            if spec.resolution_fraction_of_range > 0.0
            else None
        )
        self._offsets: list[list[float]] = []
        self._overload = spec.overload_6
        self._ns_per_tick = _NS_PER_S / spec.output_rate_Hz
        # Optional realism (None / False: the fast path above is unchanged).
        gain = spec.gain_error_fraction
        self._gain = 1.0 + gain if np.any(gain) else None
        self._drifting = spec.drifts
        self._walk_rng = np.random.default_rng(None if seed is None else [seed, 0x0D21F7])
        self._walk = np.zeros(6)
        self._walk_tick = 0
        self._wander = (
            WanderKnots(
                spec.bias_wander_std,
                spec.bias_wander_time_constant_s,
                None if seed is None else [seed, 0x3A7D],
            )
            if np.any(spec.bias_wander_std)
            else None
        )

    @property
    def sample_rate_hz(self) -> float:
        """Its output rate [Hz] (:class:`~ftcomp.hardware.protocols.ReportsRate`)."""
        return self._spec.output_rate_Hz

    @property
    def spec(self) -> SensorSpec:
        """The sensor's specification."""
        return self._spec

    @property
    def overloaded(self) -> bool:
        """True once any reading has exceeded the overload limit (latched)."""
        return self._overloaded

    def tick(self, t_s: float) -> int:
        """Index of the newest output tick at time ``t_s`` [s]."""
        return math.floor(t_s * self._spec.output_rate_Hz + 1e-6)

    def _refill(self) -> None:
        """The next block of standard normal draws, and the same as biased noise on floats."""
        self._block = self._rng.standard_normal((_NOISE_BLOCK, 6))
        self._offsets = (self._block * self._std + self._bias).tolist()
        self._next = 0

    def _draw(self, n: int) -> NDArray[np.float64]:
        """The next ``n`` rows of standard normal noise, shape (n, 6)."""
        out = np.empty((n, 6))
        filled = 0
        while filled < n:
            if self._next >= len(self._block):
                self._refill()
            take = min(n - filled, len(self._block) - self._next)
            out[filled : filled + take] = self._block[self._next : self._next + take]
            self._next += take
            filled += take
        return out

    def drift(self, first_tick: int, n: int) -> NDArray[np.float64]:
        """The bias drift at ticks ``first_tick .. first_tick + n - 1``, shape (n, 6).

        Rate times tick time, the warm-up trend, the smooth wander (a function of the tick
        time alone) and the random walk, advanced tick by tick (a gap since the last call is one
        step of the same distribution); ticks must not go back.
        """
        spec = self._spec
        dt = 1.0 / spec.output_rate_Hz
        ticks = first_tick + np.arange(n)
        t: NDArray[np.float64] = np.asarray(ticks * dt, dtype=np.float64)
        out: NDArray[np.float64] = np.outer(t, spec.bias_drift_rate_per_s)
        if np.any(spec.bias_trend):
            out += np.outer(-np.expm1(-t / spec.bias_trend_time_constant_s), spec.bias_trend)
        if self._wander is not None:
            out += self._wander.at(t)
        if not np.any(spec.bias_walk_per_sqrt_s) or n == 0:
            return out
        scale = spec.bias_walk_per_sqrt_s * math.sqrt(dt)
        gap = first_tick - self._walk_tick
        if gap > 1:  # ticks skipped: one step of their summed variance
            self._walk += self._walk_rng.standard_normal(6) * scale * math.sqrt(gap - 1)
        steps = self._walk_rng.standard_normal((n, 6)) * scale
        if gap < 1:  # the first tick was drawn before (read, then read_new of the same tick)
            steps[0] = 0.0
        walk = self._walk + np.cumsum(steps, axis=0)
        self._walk = walk[-1].copy()
        self._walk_tick = first_tick + n - 1
        return out + walk

    def convert(self, ideal_wrench: ArrayLike) -> NDArray[np.float64]:
        """Readings for ideal wrenches at consecutive new ticks, shape (N, 6) (draws noise;
        the bias drift, when on, is added by :meth:`read` and :meth:`read_new`)."""
        ideal = np.atleast_2d(np.asarray(ideal_wrench, dtype=float))
        readings, overloaded = self._spec.apply(ideal, self._draw(len(ideal)))
        self._overloaded = self._overloaded or bool(np.any(overloaded))
        return readings

    def _stamp_ns(self, k: int) -> int:
        """The time stamp of output tick ``k`` [ns] on the simulation clock."""
        return round(k * self._ns_per_tick)

    def read(self) -> WrenchSample:
        """The newest reading, stamped with its output tick [ns] (non-blocking).

        Written on Python floats (six values: a numpy call costs more than the arithmetic):
        the noise block is drawn 4096 rows at a time, already scaled and biased.
        """
        k = self.tick(self._clock())
        if k == self._last_tick and self._last is not None:
            return self._last
        if self._streaming and 0 <= self._last_tick < k - 1:  # ticks between two reads
            self._pending.extend(self._generate(self._last_tick + 1, k - 1))
        if self._next >= len(self._block):
            self._refill()
        ideal = self._ideal()
        if self._gain is not None:
            ideal = ideal * self._gain
        if self._drifting:
            ideal = ideal + self.drift(k, 1)[0]
        x0, x1, x2, x3, x4, x5 = ideal.tolist()
        o0, o1, o2, o3, o4, o5 = self._offsets[self._next]
        self._next += 1
        x = [x0 + o0, x1 + o1, x2 + o2, x3 + o3, x4 + o4, x5 + o5]
        force, torque = self._range_ft
        if (
            max(abs(x[0]), abs(x[1]), abs(x[2])) > force
            or max(abs(x[3]), abs(x[4]), abs(x[5])) > torque
        ):  # saturated (rare): numpy's clip, and the overload latch
            arr = np.array(x)
            if not self._overloaded and np.any(np.abs(arr) > self._overload):
                self._overloaded = True
            x = np.clip(arr, -self._range, self._range).tolist()
        if self._quantum is not None:
            (s0, s1, s2, s3, s4, s5), (i0, i1, i2, i3, i4, i5) = self._quantum
            x0, x1, x2, x3, x4, x5 = x
            # round() halves to even, as numpy's rint; round(v) * s == rint(v) * s exactly.
            x = [
                round(x0 * i0) * s0,
                round(x1 * i1) * s1,
                round(x2 * i2) * s2,
                round(x3 * i3) * s3,
                round(x4 * i4) * s4,
                round(x5 * i5) * s5,
            ]
        self._last_tick = k
        self._last = WrenchSample.owning(self._stamp_ns(k), np.array(x))
        if self._streaming:
            self._pending.append(self._last)
        return self._last

    def read_new(self) -> list[WrenchSample]:
        """Every output tick since the previous call, oldest first (also the ticks that
        :meth:`read` has seen meanwhile: the same samples). The first call returns the newest
        reading alone and starts the stream.

        The physics advances one control cycle at a time, so every tick since the last read
        sees the newest physics state (a real sensor sampling a signal held for one cycle).
        """
        if not self._streaming:
            newest = self.read()
            self._streaming = True
            self._pending.clear()
            return [newest]
        self.read()  # every tick up to now into the pending buffer
        out = list(self._pending)
        self._pending.clear()
        return out

    def _generate(self, first: int, last: int) -> list[WrenchSample]:
        """Readings for ticks ``first .. last`` in order (noise and drift tick by tick)."""
        n = last - first + 1
        ideal = np.broadcast_to(self._ideal(), (n, 6))
        if self._drifting:  # added as the bias is: after the gain, before noise
            ideal = ideal + self.drift(first, n) / (1.0 + self._spec.gain_error_fraction)
        readings = self.convert(ideal)
        return [WrenchSample(self._stamp_ns(first + i), readings[i]) for i in range(n)]
