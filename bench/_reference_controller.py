"""The control step before the lean one, verbatim: the reference of ``bench_control.py``.

A copy of ``src/ftcomp/control/controller.py`` as of commit d76635e (unchanged up to 46ecdfb) and
of the parts of ``filters.py``, ``safety.py`` and ``laws.py`` it uses: :class:`LowPassFilter`,
:class:`SafetyLimits` and its checks, :class:`CombinedLaw` with the :class:`AdmittanceLaw`
protocol and its helpers. Only the module docstrings, the imports and ``__all__`` differ; the
code is left as it was, one numpy operation after another. It exists so that the benchmark can
time the straightforward numpy step beside the lean one in the same run and check that both
agree; nothing in ``ftcomp`` or the tests imports it.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import Literal, NamedTuple, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from ftcomp.errors import ParameterError

__all__ = [
    "AdmittanceController",
    "AdmittanceLaw",
    "CombinedLaw",
    "ControllerState",
    "LawState",
    "LowPassFilter",
    "SafetyLimits",
    "StopReason",
    "WatchdogState",
    "selection_matrix",
]

# --- filters.py ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class LowPassFilter:
    """Butterworth low-pass over ``channels`` signals sampled every ``period_s``.

    Attributes:
        cutoff_hz: -3 dB frequency [Hz], 0 < cutoff_hz < Nyquist (0.5 / period_s).
        period_s: sample period [s] the filter is designed for (the control period).
        order: filter order, 1..8.
        channels: number of signals filtered together (6 for a wrench).
        sos: the second-order sections, shape (n_sections, 6), computed in ``__post_init__``.
    """

    cutoff_hz: float
    period_s: float
    order: int = 2
    channels: int = 6
    sos: NDArray[np.float64] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not (self.period_s > 0.0 and np.isfinite(self.period_s)):
            raise ParameterError(f"period_s must be > 0 s, got {self.period_s}")
        nyquist = 0.5 / self.period_s
        if not (0.0 < self.cutoff_hz < nyquist):
            raise ParameterError(
                f"cutoff_hz must be in (0, {nyquist:g}) Hz (Nyquist at period_s="
                f"{self.period_s:g} s), got {self.cutoff_hz}"
            )
        if not (isinstance(self.order, int) and 1 <= self.order <= 8):
            raise ParameterError(f"order must be an integer in 1..8, got {self.order!r}")
        if not (isinstance(self.channels, int) and self.channels >= 1):
            raise ParameterError(f"channels must be a positive integer, got {self.channels!r}")
        sos = np.asarray(
            signal.butter(
                self.order, self.cutoff_hz, btype="low", output="sos", fs=1 / self.period_s
            ),
            dtype=float,
        )
        sos.setflags(write=False)
        object.__setattr__(self, "sos", sos)

    def initial_state(self, x0: ArrayLike) -> NDArray[np.float64]:
        """The state of a filter that has seen ``x0`` forever (steady output ``x0``).

        Args:
            x0: shape (channels,).

        Returns:
            shape (n_sections, 2, channels), as ``sosfilt_zi(sos)[..., None] * x0``.
        """
        x = self._input(x0)
        zi = np.asarray(signal.sosfilt_zi(self.sos), dtype=float)
        return zi[:, :, None] * x[None, None, :]

    def step(
        self, state: NDArray[np.float64], x: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Filter one sample: ``(new_state, y)``, y shape (channels,). ``state`` is not modified.

        A non-finite input would poison the state for good: the caller (the controller's
        watchdog) must not feed one.
        """
        y = self._input(x)
        new = np.empty_like(state)
        for i, (b0, b1, b2, _a0, a1, a2) in enumerate(self.sos):
            z0, z1 = state[i, 0], state[i, 1]
            out = b0 * y + z0
            new[i, 0] = b1 * y - a1 * out + z1
            new[i, 1] = b2 * y - a2 * out
            y = out
        return new, y

    def _input(self, x: ArrayLike) -> NDArray[np.float64]:
        arr = np.asarray(x, dtype=float)
        if arr.shape != (self.channels,):
            raise ParameterError(
                f"filter input must have shape ({self.channels},), got {arr.shape}"
            )
        return arr


# --- safety.py ----------------------------------------------------------------------------------


class StopReason(str, enum.Enum):
    """Why the controller stopped the motion (a protective stop)."""

    NON_FINITE_SAMPLE = "non_finite_sample"
    REPEATED_SAMPLE = "repeated_sample"
    STALE_SAMPLE = "stale_sample"
    FORCE_LIMIT = "force_limit"
    TORQUE_LIMIT = "torque_limit"
    TRAVEL_LIMIT = "travel_limit"


def _frozen6(name: str, value: ArrayLike) -> NDArray[np.float64]:
    arr = np.array(value, dtype=float)
    if arr.shape == ():
        arr = np.full(6, float(arr))
    if arr.shape != (6,) or not np.all(arr > 0.0):
        raise ParameterError(
            f"{name} must be > 0 on all six axes, got {np.asarray(value).tolist()}"
        )
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class SafetyLimits:
    """The envelope. Vectors are per axis ``[x, y, z, rx, ry, rz]`` in the *base* frame.

    Attributes:
        max_twist: velocity limit [m/s, rad/s], shape (6,) or a scalar, > 0 (``inf`` allowed).
        max_twist_rate: acceleration limit [m/s^2, rad/s^2], shape (6,) or a scalar, > 0.
        max_travel: largest displacement from the start [m, rad], shape (6,) or a scalar, > 0.
        max_force_N: protective stop when the contact force's norm exceeds this [N].
        max_torque_Nm: protective stop when the contact torque's norm exceeds this [N*m].
        stale_after_s: a sample older than this (robot clock minus sample stamp) stops [s].
        max_repeated_samples: consecutive samples with an already seen time stamp tolerated
            (0: the first repeat stops; raise it when the sensor is slower than the loop).
    """

    max_twist: NDArray[np.float64]
    max_twist_rate: NDArray[np.float64]
    max_travel: NDArray[np.float64]
    max_force_N: float
    max_torque_Nm: float
    stale_after_s: float
    max_repeated_samples: int = 0

    def __post_init__(self) -> None:
        for name in ("max_twist", "max_twist_rate", "max_travel"):
            object.__setattr__(self, name, _frozen6(name, getattr(self, name)))
        for name in ("max_force_N", "max_torque_Nm", "stale_after_s"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value > 0.0 and not math.isnan(value)):
                raise ParameterError(f"{name} must be > 0, got {value!r}")
        if not (isinstance(self.max_repeated_samples, int) and self.max_repeated_samples >= 0):
            raise ParameterError(
                f"max_repeated_samples must be an integer >= 0, got {self.max_repeated_samples!r}"
            )


class WatchdogState(NamedTuple):
    """Last accepted sample stamp [s] (``-inf`` before the first) and the current repeat count."""

    last_t: float = -math.inf
    repeats: int = 0


def check_sample(
    limits: SafetyLimits,
    state: WatchdogState,
    t_sample: float,
    wrench: ArrayLike,
    now: float,
) -> tuple[WatchdogState, StopReason | None]:
    """Judge one sample: non-finite values or stamp, a repeated or older stamp, or a stale one.

    Args:
        limits: the envelope.
        state: watchdog state from the previous sample.
        t_sample: the sample's stamp [s].
        wrench: the sample's wrench, shape (6,) (any frame).
        now: the robot's clock [s].

    Returns:
        ``(new_state, reason)``; ``reason`` is None when the sample may be used.
    """
    if not (math.isfinite(t_sample) and np.all(np.isfinite(wrench))):
        return state, StopReason.NON_FINITE_SAMPLE
    if t_sample <= state.last_t:
        repeats = state.repeats + 1
        new = WatchdogState(state.last_t, repeats)
        if repeats > limits.max_repeated_samples:
            return new, StopReason.REPEATED_SAMPLE
        if now - state.last_t > limits.stale_after_s:
            return new, StopReason.STALE_SAMPLE
        return new, None
    if now - t_sample > limits.stale_after_s:
        return state, StopReason.STALE_SAMPLE
    return WatchdogState(t_sample, 0), None


def check_wrench(limits: SafetyLimits, wrench: ArrayLike) -> StopReason | None:
    """FORCE_LIMIT or TORQUE_LIMIT when the contact wrench's force or torque norm is too large."""
    w = np.asarray(wrench, dtype=float)
    if float(np.linalg.norm(w[:3])) > limits.max_force_N:
        return StopReason.FORCE_LIMIT
    if float(np.linalg.norm(w[3:])) > limits.max_torque_Nm:
        return StopReason.TORQUE_LIMIT
    return None


def limit_twist(
    limits: SafetyLimits,
    twist_cmd: ArrayLike,
    twist_prev: ArrayLike,
    dt: float,
) -> NDArray[np.float64]:
    """Clamp a twist per axis to the velocity limit, then its change to ``max_twist_rate * dt``.

    Args:
        limits: the envelope.
        twist_cmd: wanted twist [m/s, rad/s], base frame, shape (6,).
        twist_prev: twist commanded in the previous period, shape (6,).
        dt: period [s], > 0.

    Returns:
        The twist to command, shape (6,).
    """
    if not dt > 0.0:
        raise ParameterError(f"dt must be > 0 s, got {dt}")
    prev = np.asarray(twist_prev, dtype=float)
    v = np.clip(np.asarray(twist_cmd, dtype=float), -limits.max_twist, limits.max_twist)
    step = limits.max_twist_rate * dt
    return np.clip(v, prev - step, prev + step)


def check_travel(
    limits: SafetyLimits, travel: ArrayLike, twist: ArrayLike, dt: float
) -> tuple[NDArray[np.float64], StopReason | None]:
    """Integrate the commanded twist into the travel from the start; stop before leaving it.

    Args:
        limits: the envelope.
        travel: displacement commanded so far [m, rad], base frame, shape (6,).
        twist: twist about to be commanded, shape (6,).
        dt: period [s].

    Returns:
        ``(new_travel, reason)``: with TRAVEL_LIMIT the travel is left unchanged (the twist must
        not be sent).
    """
    current = np.asarray(travel, dtype=float)
    new = current + np.asarray(twist, dtype=float) * dt
    if np.any(np.abs(new) > limits.max_travel):
        return current, StopReason.TRAVEL_LIMIT
    return new, None


# --- laws.py ------------------------------------------------------------------------------------

_AXES = ("x", "y", "z", "rx", "ry", "rz")


class LawState(NamedTuple):
    """State shared by all laws (immutable; each step returns a new one).

    Attributes:
        offset: displacement commanded so far, ΔX [m, rad], control frame, shape (6,).
        twist: last twist command [m/s, rad/s], control frame, shape (6,).
        wrench_error: last wrench error input [N, N*m], control frame, shape (6,).
    """

    offset: NDArray[np.float64]
    twist: NDArray[np.float64]
    wrench_error: NDArray[np.float64]


class AdmittanceLaw(Protocol):
    """What the controller needs of a law."""

    @property
    def selection(self) -> NDArray[np.float64]:
        """The 6x6 diagonal selection matrix S."""
        ...

    def initial_state(self, wrench_error: ArrayLike | None = None) -> LawState:
        """State at rest with ``wrench_error`` [N, N*m] as the previous input (default zeros)."""
        ...

    def step(
        self, state: LawState, wrench_error: ArrayLike, dt: float
    ) -> tuple[LawState, NDArray[np.float64]]:
        """Advance one period ``dt`` [s]; return the new state and the twist command."""
        ...


def selection_matrix(axes: str | ArrayLike) -> NDArray[np.float64]:
    """The 6x6 diagonal selection matrix S of Eq. 27.

    Args:
        axes: either a string of axis names among ``x y z rx ry rz`` separated by commas or
            spaces (``"z"``, ``"x,y,z"``; ``""`` for none), or six 0/1 values.

    Returns:
        ``diag(s)`` with ``s[i] = 1`` where axis ``i`` yields to force, shape (6, 6).

    Raises:
        ParameterError: an unknown axis name, or values that are not six 0/1 numbers.
    """
    if isinstance(axes, str):
        names = [a for a in axes.replace(",", " ").split() if a]
        diag = np.zeros(6)
        for name in names:
            if name not in _AXES:
                raise ParameterError(f"unknown selection axis {name!r}; valid: {', '.join(_AXES)}")
            diag[_AXES.index(name)] = 1.0
        return np.diag(diag)
    values = np.asarray(axes, dtype=float)
    if values.shape != (6,) or not np.all((values == 0.0) | (values == 1.0)):
        raise ParameterError(f"selection must be six 0/1 values, got {values.tolist()}")
    return np.diag(values)


def _frozen_diag(name: str, value: ArrayLike, *, positive: bool = False) -> NDArray[np.float64]:
    """A gain given as a scalar, six values or a 6x6 diagonal matrix, as a read-only (6,) array."""
    arr = np.array(value, dtype=float)
    if arr.shape == (6, 6):
        if np.any(arr - np.diag(np.diag(arr))):
            raise ParameterError(f"{name} must be diagonal, got off-diagonal terms")
        arr = np.diag(arr).copy()
    elif arr.shape == ():
        arr = np.full(6, float(arr))
    if arr.shape != (6,):
        raise ParameterError(f"{name} must be a scalar, (6,) or diagonal (6, 6), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} must be finite, got {arr.tolist()}")
    if positive and np.any(arr <= 0.0):
        raise ParameterError(f"{name} must be > 0 on every axis, got {arr.tolist()}")
    if not positive and np.any(arr < 0.0):
        raise ParameterError(f"{name} must be >= 0 on every axis, got {arr.tolist()}")
    arr.setflags(write=False)
    return arr


def _frozen_selection(selection: ArrayLike | str) -> NDArray[np.float64]:
    """S from axis names, six 0/1 values or a diagonal 6x6 matrix, as a read-only (6, 6)."""
    if isinstance(selection, str):
        matrix = selection_matrix(selection)
    else:
        arr = np.asarray(selection, dtype=float)
        if arr.shape == (6, 6):
            if np.any(arr - np.diag(np.diag(arr))):
                raise ParameterError("selection must be a diagonal 6x6 matrix")
            arr = np.diag(arr)
        matrix = selection_matrix(arr)
    matrix.setflags(write=False)
    return matrix


def _check_dt(dt: float) -> None:
    if not dt > 0.0:
        raise ParameterError(f"dt must be > 0 s, got {dt}")


def _vector6(value: ArrayLike | None) -> NDArray[np.float64]:
    if value is None:
        return np.zeros(6)
    arr = np.array(value, dtype=float)
    if arr.shape != (6,):
        raise ParameterError(f"wrench_error must have shape (6,), got {arr.shape}")
    return arr


def _rest_state(wrench_error: ArrayLike | None) -> LawState:
    return LawState(np.zeros(6), np.zeros(6), _vector6(wrench_error))


def _combined_step(
    k1: NDArray[np.float64],
    k2: NDArray[np.float64],
    s: NDArray[np.float64],
    state: LawState,
    wrench_error: ArrayLike,
    dt: float,
) -> tuple[LawState, NDArray[np.float64]]:
    _check_dt(dt)
    e = _vector6(wrench_error)
    twist = s * (k1 * ((e - state.wrench_error) / dt) + k2 * e)
    return LawState(state.offset + twist * dt, twist, e), twist


@dataclass(frozen=True)
class CombinedLaw:
    """ΔV = S (K1 dΔF/dt + K2 ΔF), paper Eq. 26-27.

    Attributes:
        k1_m_per_N: K1, a scalar or diagonal (6,) [m/N; rad/(N*m)], >= 0.
        k2_m_per_s_N: K2, a scalar or diagonal (6,) [m/(s*N); rad/(s*N*m)], >= 0.
        selection: S as axis names (``"z"``), six 0/1 values or a diagonal 6x6 matrix;
            stored as the (6, 6) matrix.

    On a spring contact of stiffness k along one selected axis the force error decays as
    ``exp(-k K2 t / (1 + K1 k))``: K2 sets the speed, K1 adds a lag of ``K1/K2`` per e-fold.
    In discrete time the backward difference adds a mode of ratio about ``-K1 k`` per step:
    keep ``K1 k < 1`` (a stiff surface needs a small K1; a low-pass filter's lag lowers the
    bound further).
    """

    k1_m_per_N: NDArray[np.float64]
    k2_m_per_s_N: NDArray[np.float64]
    selection: NDArray[np.float64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "k1_m_per_N", _frozen_diag("k1_m_per_N", self.k1_m_per_N))
        object.__setattr__(self, "k2_m_per_s_N", _frozen_diag("k2_m_per_s_N", self.k2_m_per_s_N))
        object.__setattr__(self, "selection", _frozen_selection(self.selection))

    def initial_state(self, wrench_error: ArrayLike | None = None) -> LawState:
        """At rest; ``wrench_error`` [N, N*m] is the previous input the derivative starts from."""
        return _rest_state(wrench_error)

    def step(
        self, state: LawState, wrench_error: ArrayLike, dt: float
    ) -> tuple[LawState, NDArray[np.float64]]:
        """One period.

        Args:
            state: from ``initial_state`` or the previous step.
            wrench_error: ΔF [N, N*m], control frame, shape (6,).
            dt: period [s], > 0.

        Returns:
            ``(new_state, twist)``, twist [m/s, rad/s] in the control frame, shape (6,).
        """
        s = np.diag(self.selection)
        return _combined_step(self.k1_m_per_N, self.k2_m_per_s_N, s, state, wrench_error, dt)


# --- controller.py ------------------------------------------------------------------------------

ControlFrame = Literal["base", "sensor"]


class ControllerState(NamedTuple):
    """Everything the controller carries from one period to the next.

    Attributes:
        law: the law's state (offset, twist and wrench error in the control frame).
        filter: the low-pass filter's state.
        watchdog: last sample stamp and repeat count.
        wrench_filtered_sensor: last filtered contact wrench [N, N*m], sensor frame, (6,).
        twist_base: last twist commanded [m/s, rad/s], base frame, (6,).
        travel_base: displacement commanded since the start [m, rad], base frame, (6,).
        stop_reason: None while running; why it stopped otherwise (latched).
    """

    law: LawState
    filter: NDArray[np.float64]
    watchdog: WatchdogState
    wrench_filtered_sensor: NDArray[np.float64]
    twist_base: NDArray[np.float64]
    travel_base: NDArray[np.float64]
    stop_reason: StopReason | None


def _rotate6(R: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.concatenate([R @ v[:3], R @ v[3:]])


def _rotate6_inv(R: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.concatenate([R.T @ v[:3], R.T @ v[3:]])


@dataclass(frozen=True)
class AdmittanceController:
    """Admittance law + wrench filter + safety envelope.

    Attributes:
        law: any :class:`~ftcomp.control.laws.AdmittanceLaw`.
        wrench_filter: low-pass on the contact wrench (its ``period_s`` should be the control
            period), or None for no filtering.
        limits: the safety envelope (base-frame axes).
        frame: the control frame of the law's gains, selection and ``wrench_desired``.
        wrench_desired: F0 [N, N*m] in the control frame, shape (6,); zeros by default.
    """

    law: AdmittanceLaw
    wrench_filter: LowPassFilter | None
    limits: SafetyLimits
    frame: ControlFrame
    wrench_desired: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))

    def __post_init__(self) -> None:
        if self.frame not in ("base", "sensor"):
            raise ParameterError(f"frame must be 'base' or 'sensor', got {self.frame!r}")
        w = np.array(self.wrench_desired, dtype=float)
        if w.shape != (6,) or not np.all(np.isfinite(w)):
            raise ParameterError(f"wrench_desired must be 6 finite values, got {w.tolist()}")
        w.setflags(write=False)
        object.__setattr__(self, "wrench_desired", w)
        if self.wrench_filter is not None and self.wrench_filter.channels != 6:
            raise ParameterError("wrench_filter must filter 6 channels")

    def _to_control(
        self, w_sensor: NDArray[np.float64], R: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        return _rotate6(R, w_sensor) if self.frame == "base" else w_sensor

    def _twist_to_base(
        self, twist: NDArray[np.float64], R: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        return twist if self.frame == "base" else _rotate6(R, twist)

    def wrench_error(
        self, wrench_sensor: ArrayLike, R_base_sensor: ArrayLike
    ) -> NDArray[np.float64]:
        """ΔF = wrench (rotated to the control frame) - wrench_desired, shape (6,)."""
        w = np.asarray(wrench_sensor, dtype=float)
        R = np.asarray(R_base_sensor, dtype=float)
        return self._to_control(w, R) - self.wrench_desired

    def initial_state(
        self, wrench_contact_sensor: ArrayLike, R_base_sensor: ArrayLike
    ) -> ControllerState:
        """Start at rest, bumpless: the filter and the law's derivative begin at this wrench.

        Args:
            wrench_contact_sensor: the contact wrench now [N, N*m], sensor frame, shape (6,),
                finite.
            R_base_sensor: the sensor's orientation now, shape (3, 3).
        """
        w = np.array(wrench_contact_sensor, dtype=float)
        if w.shape != (6,) or not np.all(np.isfinite(w)):
            raise ParameterError(
                f"the initial contact wrench must be 6 finite values, got {w.tolist()}"
            )
        zi = (
            self.wrench_filter.initial_state(w)
            if self.wrench_filter is not None
            else np.zeros((0, 2, 6))
        )
        return ControllerState(
            law=self.law.initial_state(self.wrench_error(w, R_base_sensor)),
            filter=zi,
            watchdog=WatchdogState(),
            wrench_filtered_sensor=w,
            twist_base=np.zeros(6),
            travel_base=np.zeros(6),
            stop_reason=None,
        )

    def step(
        self,
        state: ControllerState,
        t_sample: float,
        wrench_contact_sensor: ArrayLike,
        R_base_sensor: ArrayLike,
        now: float,
        dt: float,
        twist_nominal_base: ArrayLike | None = None,
    ) -> tuple[ControllerState, NDArray[np.float64]]:
        """One control period.

        Args:
            state: from :meth:`initial_state` or the previous step.
            t_sample: the sample's stamp [s].
            wrench_contact_sensor: compensated wrench [N, N*m], sensor frame, shape (6,); may be
                non-finite (the watchdog stops).
            R_base_sensor: the sensor's orientation now, shape (3, 3).
            now: the robot's clock [s].
            dt: control period [s], > 0.
            twist_nominal_base: planned motion [m/s, rad/s], base frame, shape (6,), that the
                law's ΔV is added to (the paper's ΔV is an offset); None: standing still.

        Returns:
            ``(new_state, twist_base)`` [m/s, rad/s], base frame, shape (6,); zeros once
            ``new_state.stop_reason`` is set. Never raises on bad sensor data.
        """
        if state.stop_reason is not None:
            return state, np.zeros(6)
        w = np.asarray(wrench_contact_sensor, dtype=float)
        watchdog, reason = check_sample(self.limits, state.watchdog, t_sample, w, now)
        if reason is None:
            reason = check_wrench(self.limits, w)
        if reason is not None:
            return self._stopped(state, watchdog, reason), np.zeros(6)
        if watchdog.repeats > 0:  # tolerated repeat: nothing new to filter, hold the command
            return state._replace(watchdog=watchdog), state.twist_base
        R = np.asarray(R_base_sensor, dtype=float)
        if self.wrench_filter is not None:
            zi, w_filt = self.wrench_filter.step(state.filter, w)
        else:
            zi, w_filt = state.filter, w
        law_state, twist = self.law.step(
            state.law, self._to_control(w_filt, R) - self.wrench_desired, dt
        )
        twist_base = self._twist_to_base(twist, R)
        if twist_nominal_base is not None:
            twist_base = twist_base + np.asarray(twist_nominal_base, dtype=float)
        twist_base = limit_twist(self.limits, twist_base, state.twist_base, dt)
        travel, reason = check_travel(self.limits, state.travel_base, twist_base, dt)
        new = ControllerState(law_state, zi, watchdog, w_filt, twist_base, travel, None)
        if reason is not None:
            return self._stopped(new, watchdog, reason), np.zeros(6)
        return new, twist_base

    @staticmethod
    def _stopped(
        state: ControllerState, watchdog: WatchdogState, reason: StopReason
    ) -> ControllerState:
        return state._replace(watchdog=watchdog, twist_base=np.zeros(6), stop_reason=reason)
