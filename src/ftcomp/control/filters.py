"""Low-pass filtering of a wrench stream for control, one sample at a time.

:class:`LowPassFilter` is a Butterworth filter designed with :func:`scipy.signal.butter` as
second-order sections for a fixed sample period; its ``step`` is pure (state in, state out) and
implements exactly what :func:`scipy.signal.sosfilt` computes (transposed direct form II, the
state layout of :func:`scipy.signal.sosfilt_zi`), over all channels at once.
The derivative the combined law needs (dΔF/dt) is then a backward difference of the *filtered*
signal, which this filter's roll-off keeps from amplifying sensor noise.

A filter of a few channels is cheaper on Python floats than as numpy arrays (a numpy operation on
six numbers costs about a microsecond, a float operation a few tens of nanoseconds): ``step``
runs :meth:`LowPassFilter.step_scalar` on each channel, and the controller uses a six-channel
kernel written out per channel. A scalar signal in a 1 kHz loop (the placement's decision
filter) should call ``step_scalar`` itself: its state is a tuple of floats, its input and output
a float, and it allocates no array (about 20 times cheaper than ``step`` on one channel).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from ftcomp.errors import ParameterError

__all__ = ["LowPassFilter"]

# One second-order section as floats: (b0, b1, b2, a1, a2); a0 is 1 (butter normalises it).
_Section = tuple[float, float, float, float, float]
# A state as nested lists, the layout of ``NDArray.tolist()``: [section][0 or 1][channel].
_ListState = list[list[list[float]]]


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
    _sections: tuple[_Section, ...] = field(init=False, repr=False, compare=False)
    _zi: NDArray[np.float64] = field(init=False, repr=False, compare=False)

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
        sections = tuple((b0, b1, b2, a1, a2) for b0, b1, b2, _a0, a1, a2 in sos.tolist())
        object.__setattr__(self, "_sections", sections)
        zi = np.asarray(signal.sosfilt_zi(sos), dtype=float)
        zi.setflags(write=False)
        object.__setattr__(self, "_zi", zi)

    def initial_state(self, x0: ArrayLike) -> NDArray[np.float64]:
        """The state of a filter that has seen ``x0`` forever (steady output ``x0``).

        Args:
            x0: shape (channels,).

        Returns:
            shape (n_sections, 2, channels), as ``sosfilt_zi(sos)[..., None] * x0``.
        """
        x = self._input(x0)
        return self._zi[:, :, None] * x[None, None, :]

    def step(
        self, state: NDArray[np.float64], x: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Filter one sample: ``(new_state, y)``, y shape (channels,). ``state`` is not modified.

        A non-finite input would poison the state for good: the caller (the controller's
        watchdog) must not feed one.
        """
        z = np.asarray(state, dtype=float)
        n = len(self._sections)
        if z.shape != (n, 2, self.channels):
            raise ParameterError(
                f"filter state must have shape ({n}, 2, {self.channels}), got {z.shape}"
            )
        # One flat scalar state per channel (the layout of step_scalar), stepped one by one.
        columns = z.reshape(2 * n, self.channels).T.tolist()
        new, y = [], []
        for column, x_channel in zip(columns, self._input(x).tolist(), strict=True):
            z_channel, y_channel = self.step_scalar(column, x_channel)
            new.append(z_channel)
            y.append(y_channel)
        return np.array(new).T.reshape(z.shape), np.array(y)

    def initial_state_scalar(self, x0: float) -> tuple[float, ...]:
        """:meth:`initial_state` of a one-channel filter as a flat tuple of floats.

        Args:
            x0: the input the filter has seen forever (steady output ``x0``).

        Returns:
            ``(z0, z1)`` per section, ``2 * n_sections`` floats: ``initial_state([x0]).ravel()``.
        """
        if self.channels != 1:
            raise ParameterError(f"initial_state_scalar needs channels=1, got {self.channels}")
        return tuple(z * float(x0) for z in self._zi.ravel().tolist())

    def step_scalar(self, state: Sequence[float], x: float) -> tuple[tuple[float, ...], float]:
        """:meth:`step` of a one-channel filter on floats: ``(new_state, y)``, no numpy at all.

        The same arithmetic as :meth:`step` (and :func:`scipy.signal.sosfilt`) in the same order,
        so the results are identical; the cheap path for a scalar signal in a 1 kHz loop.

        Args:
            state: from :meth:`initial_state_scalar` or the previous call, ``2 * n_sections``
                floats (``initial_state([x0]).ravel()`` is the same state).
            x: the sample, finite (see :meth:`step`).

        Returns:
            The new state (a new tuple; ``state`` is not modified) and the filtered sample.
        """
        if len(state) != 2 * len(self._sections):
            raise ParameterError(
                f"filter state must hold {2 * len(self._sections)} floats, got {len(state)}"
            )
        y = x
        new: tuple[float, ...] = ()
        i = 0
        for b0, b1, b2, a1, a2 in self._sections:
            out = b0 * y + state[i]
            new += (b1 * y - a1 * out + state[i + 1], b2 * y - a2 * out)
            y = out
            i += 2
        return new, y

    def _step6(self, state: _ListState, x: Sequence[float]) -> tuple[list[float], list[float]]:
        """:meth:`step` of a six-channel filter on floats (the controller's kernel).

        Args:
            state: ``state.tolist()`` of a (n_sections, 2, 6) state.
            x: six floats.

        Returns:
            The new state as ``12 * n_sections`` floats in the (n_sections, 2, 6) order, and the
            six outputs. The arithmetic of :meth:`step_scalar`, written out per channel.
        """
        y0, y1, y2, y3, y4, y5 = x
        new: list[float] = []
        # Not strict: a state of the wrong size makes the controller's buffer the wrong size.
        for (b0, b1, b2, a1, a2), (z0, z1) in zip(self._sections, state, strict=False):
            p0, p1, p2, p3, p4, p5 = z0
            q0, q1, q2, q3, q4, q5 = z1
            o0, o1, o2 = b0 * y0 + p0, b0 * y1 + p1, b0 * y2 + p2
            o3, o4, o5 = b0 * y3 + p3, b0 * y4 + p4, b0 * y5 + p5
            new += (
                b1 * y0 - a1 * o0 + q0,
                b1 * y1 - a1 * o1 + q1,
                b1 * y2 - a1 * o2 + q2,
                b1 * y3 - a1 * o3 + q3,
                b1 * y4 - a1 * o4 + q4,
                b1 * y5 - a1 * o5 + q5,
                b2 * y0 - a2 * o0,
                b2 * y1 - a2 * o1,
                b2 * y2 - a2 * o2,
                b2 * y3 - a2 * o3,
                b2 * y4 - a2 * o4,
                b2 * y5 - a2 * o5,
            )
            y0, y1, y2, y3, y4, y5 = o0, o1, o2, o3, o4, o5
        return new, [y0, y1, y2, y3, y4, y5]

    def _input(self, x: ArrayLike) -> NDArray[np.float64]:
        arr = np.asarray(x, dtype=float)
        if arr.shape != (self.channels,):
            raise ParameterError(
                f"filter input must have shape ({self.channels},), got {arr.shape}"
            )
        return arr
