"""The mass-damper-spring admittance law (ros2_controllers' ``admittance_controller`` form).

The same :class:`~ftcomp.control.laws.AdmittanceLaw` interface and :class:`LawState` as the
paper's laws (:mod:`ftcomp.control.laws`), so the controller runs it unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.control.laws import (
    LawState,
    _check_dt,
    _diagonal,
    _frozen_diag,
    _frozen_selection,
    _rest_state,
    _vector6,
)

__all__ = ["MassDamperSpringLaw"]


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
