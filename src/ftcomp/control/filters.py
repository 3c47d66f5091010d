"""Low-pass filtering of a wrench stream for control, one sample at a time.

:class:`LowPassFilter` is a Butterworth filter designed with :func:`scipy.signal.butter` as
second-order sections for a fixed sample period; its ``step`` is pure (state in, state out) and
implements exactly what :func:`scipy.signal.sosfilt` computes (transposed direct form II, the
state layout of :func:`scipy.signal.sosfilt_zi`), vectorised over the six wrench channels.
The derivative the combined law needs (dΔF/dt) is then a backward difference of the *filtered*
signal, which this filter's roll-off keeps from amplifying sensor noise.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from ftcomp.errors import ParameterError

__all__ = ["LowPassFilter"]


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
