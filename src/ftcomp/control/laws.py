"""Admittance laws (paper Eq. 24-27 and the mass-damper-spring form), as pure step functions.

Every law maps a *wrench error* to a *twist*, both in the same control frame (the caller picks the
frame, see :class:`ftcomp.control.controller.AdmittanceController`)::

    wrench_error = wrench_contact - wrench_desired      # [N, N*m], shape (6,)
    twist        = [vx, vy, vz, wx, wy, wz]             # [m/s, rad/s], shape (6,)

Sign convention: ``wrench_contact`` is the compensated wrench the environment exerts on the robot
through the tool (what the sensor reads once bias and tool gravity are removed). With positive
gains a law *yields*: it moves the tool along the excess force. The paper's Fig. 3 writes the
deviation as ``F0 - F'``; with its sensor z axis pointing down the sign is absorbed by the frame.
We fix one sign so that positive gains are always stable on a passive environment.

Selection matrix ``S`` (Eq. 27): a 6x6 diagonal of 0/1, 1 where that axis yields to force. Axes
with 0 get zero twist.

Each law is a frozen dataclass holding its gains; ``initial_state`` and ``step(state,
wrench_error, dt)`` are pure (no clock, no I/O), so the same law runs in the simulator, on a robot
and over a recorded log. Every law returns the same :class:`LawState`: ``offset`` is the
displacement the law has commanded so far (ΔX, [m, rad], control frame) and ``wrench_error`` the
input the last step acted on, so a state always says which error produced its ``twist``. Each
law has one implementation, its ``step`` on (6,) arrays, which the controller calls.

Laws:

- :class:`PositionLaw` (Eq. 24): ΔX = S K1 ΔF, executed incrementally:
  ``twist = S K1 (ΔF_k - ΔF_{k-1}) / dt``. With constant gains ``offset = S K1 (ΔF - ΔF_0)``;
  a gain change affects only later force changes, so the command does not jump (bumpless).
- :class:`VelocityLaw` (Eq. 25): ΔV = S K2 ΔF.
- :class:`CombinedLaw` (Eq. 26-27): ΔV = S (K1 dΔF/dt + K2 ΔF), the derivative a backward
  difference of the input (give it a filtered wrench error, see :mod:`ftcomp.control.filters`).
- :class:`MassDamperSpringLaw`: M x'' + D x' + K x = S ΔF per axis, integrated with
  semi-implicit Euler as ros2_controllers' ``admittance_controller`` does.

Units: K1 [m/N] (rad/(N*m) on rotation axes), K2 [m/(s*N)], M [kg], D [N*s/m], K [N/m]
(rotational analogues on axes 3-5). The paper quotes k13 in mm/N and k23 in mm/(s*N): convert at
the edges (``k1_mm_per_N * 1e-3``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.arrays import frozen_array
from ftcomp.errors import ParameterError

__all__ = [
    "AdmittanceLaw",
    "CombinedLaw",
    "LawState",
    "MassDamperSpringLaw",
    "PositionLaw",
    "VelocityLaw",
    "selection_matrix",
]

_AXES = ("x", "y", "z", "rx", "ry", "rz")
_ZERO6 = frozen_array(np.zeros(6), (6,), name="zero")


class LawState(NamedTuple):
    """State shared by all laws (immutable; each step returns a new one).

    Attributes:
        offset: displacement commanded so far, ΔX [m, rad], control frame, shape (6,).
        twist: the twist the last step returned [m/s, rad/s], control frame, shape (6,).
        wrench_error: the wrench error ΔF the last step acted on, the one that produced
            ``twist`` [N, N*m], control frame, shape (6,) (in :meth:`AdmittanceLaw.initial_state`,
            the error to start from). In a controller's state this is the *filtered* error.
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
    arr = np.asarray(value, dtype=float)
    if arr.shape == (6, 6):
        if np.any(arr - np.diag(np.diag(arr))):
            raise ParameterError(f"{name} must be diagonal, got off-diagonal terms")
        arr = np.diag(arr)
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
    return frozen_array(arr, (6,), name=name)


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
    return frozen_array(matrix, (6, 6), name="selection")


def _diagonal(selection: NDArray[np.float64]) -> NDArray[np.float64]:
    """The diagonal of S, six 0/1 values, read-only (S itself is kept as the (6, 6) matrix)."""
    return frozen_array(np.diag(selection), (6,), name="selection")


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


# (S K1, S K2): the gains of Eq. 24-27 with the selection folded in, prepared once per law.
_SelectedGains = tuple[NDArray[np.float64], NDArray[np.float64]]


def _selected_gains(
    k1: NDArray[np.float64], k2: NDArray[np.float64], selection: NDArray[np.float64]
) -> _SelectedGains:
    s = _diagonal(selection)
    return frozen_array(s * k1, (6,), name="S K1"), frozen_array(s * k2, (6,), name="S K2")


def _rate_law_step(
    gains: _SelectedGains, state: LawState, wrench_error: ArrayLike, dt: float
) -> tuple[LawState, NDArray[np.float64]]:
    """The one step of Eq. 24-27: ``twist = S K1 (ΔF - ΔF_prev) / dt + S K2 ΔF``.

    S is 0 or 1 per axis, so ``(S K1) x`` is ``S (K1 x)``: this is Eq. 26-27 as written, with
    K2 = 0 for the position law (Eq. 24, incremental) and K1 = 0 for the velocity law (Eq. 25).
    """
    _check_dt(dt)
    e = _vector6(wrench_error)
    sk1, sk2 = gains
    twist = sk1 * ((e - state.wrench_error) / dt) + sk2 * e
    return LawState(state.offset + twist * dt, twist, e), twist


class _RateLaw:
    """The Eq. 24-27 laws' common part: at rest to start, then :func:`_rate_law_step` with the
    gains a law prepared (``_gains``, S folded in)."""

    _gains: _SelectedGains

    def initial_state(self, wrench_error: ArrayLike | None = None) -> LawState:
        """At rest; ``wrench_error`` [N, N*m] is the previous input (the derivative starts from
        it; for the position law, the input at which ΔX = 0)."""
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
        return _rate_law_step(self._gains, state, wrench_error, dt)


@dataclass(frozen=True)
class CombinedLaw(_RateLaw):
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
    _gains: _SelectedGains = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "k1_m_per_N", _frozen_diag("k1_m_per_N", self.k1_m_per_N))
        object.__setattr__(self, "k2_m_per_s_N", _frozen_diag("k2_m_per_s_N", self.k2_m_per_s_N))
        object.__setattr__(self, "selection", _frozen_selection(self.selection))
        gains = _selected_gains(self.k1_m_per_N, self.k2_m_per_s_N, self.selection)
        object.__setattr__(self, "_gains", gains)


@dataclass(frozen=True)
class PositionLaw(_RateLaw):
    """ΔX = S K1 ΔF, paper Eq. 24, executed incrementally (see the module docstring).

    Attributes:
        k1_m_per_N: K1, a scalar or diagonal (6,) [m/N; rad/(N*m)], >= 0.
        selection: S (see :class:`CombinedLaw`).
    """

    k1_m_per_N: NDArray[np.float64]
    selection: NDArray[np.float64]
    _gains: _SelectedGains = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "k1_m_per_N", _frozen_diag("k1_m_per_N", self.k1_m_per_N))
        object.__setattr__(self, "selection", _frozen_selection(self.selection))
        gains = _selected_gains(self.k1_m_per_N, _ZERO6, self.selection)
        object.__setattr__(self, "_gains", gains)


@dataclass(frozen=True)
class VelocityLaw(_RateLaw):
    """ΔV = S K2 ΔF, paper Eq. 25.

    Attributes:
        k2_m_per_s_N: K2, a scalar or diagonal (6,) [m/(s*N); rad/(s*N*m)], >= 0.
        selection: S (see :class:`CombinedLaw`).
    """

    k2_m_per_s_N: NDArray[np.float64]
    selection: NDArray[np.float64]
    _gains: _SelectedGains = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "k2_m_per_s_N", _frozen_diag("k2_m_per_s_N", self.k2_m_per_s_N))
        object.__setattr__(self, "selection", _frozen_selection(self.selection))
        gains = _selected_gains(_ZERO6, self.k2_m_per_s_N, self.selection)
        object.__setattr__(self, "_gains", gains)


@dataclass(frozen=True)
class MassDamperSpringLaw:
    """M x'' + D x' + K x = S ΔF per axis (ros2_controllers' admittance_controller).

    ``x`` is the law's ``offset`` from where it started. Integrated with semi-implicit Euler:
    ``a = (ΔF - D v - K x) / M; v += a dt; x += v dt``, stable for ``dt < 2 sqrt(M/K)``
    on each axis.

    Attributes:
        mass_kg: M, a scalar or diagonal (6,) [kg; kg*m^2], > 0.
        damping_N_s_per_m: D, a scalar or diagonal (6,) [N*s/m; N*m*s/rad], >= 0.
        stiffness_N_per_m: K, a scalar or diagonal (6,) [N/m; N*m/rad], >= 0 (0: no return).
        selection: S (see :class:`CombinedLaw`).
    """

    mass_kg: NDArray[np.float64]
    damping_N_s_per_m: NDArray[np.float64]
    stiffness_N_per_m: NDArray[np.float64]
    selection: NDArray[np.float64]
    _s: NDArray[np.float64] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "mass_kg", _frozen_diag("mass_kg", self.mass_kg, positive=True))
        for name in ("damping_N_s_per_m", "stiffness_N_per_m"):
            object.__setattr__(self, name, _frozen_diag(name, getattr(self, name)))
        object.__setattr__(self, "selection", _frozen_selection(self.selection))
        object.__setattr__(self, "_s", _diagonal(self.selection))

    def initial_state(self, wrench_error: ArrayLike | None = None) -> LawState:
        """At rest at the start point (offset 0, twist 0)."""
        return _rest_state(wrench_error)

    def step(
        self, state: LawState, wrench_error: ArrayLike, dt: float
    ) -> tuple[LawState, NDArray[np.float64]]:
        """One period: see :meth:`CombinedLaw.step`."""
        _check_dt(dt)
        e = _vector6(wrench_error)
        s = self._s
        accel = (
            s * e - self.damping_N_s_per_m * state.twist - self.stiffness_N_per_m * state.offset
        ) / self.mass_kg
        twist = s * (state.twist + accel * dt)
        offset = state.offset + twist * dt
        return LawState(offset, twist, e), twist
