"""Low-pass filtering of a wrench stream for control, one sample at a time.

:class:`LowPassFilter` is a Butterworth filter as second-order sections for a fixed sample
period (:func:`butterworth_sections`: the transfer function :func:`scipy.signal.butter` designs,
written out; the tests hold the two equal); its ``step`` is pure (state in, state out) and
implements exactly what :func:`scipy.signal.sosfilt` computes (transposed direct form II, the
state layout of :func:`scipy.signal.sosfilt_zi`), over all channels at once.
The derivative the combined law needs (dΔF/dt) is then a backward difference of the *filtered*
signal, which this filter's roll-off keeps from amplifying sensor noise.

One kernel steps the sections (:func:`_sections_step`); its arithmetic is the same on a numpy
array of channels (:meth:`LowPassFilter.step`, the controller's wrench) and on one Python float
(:meth:`LowPassFilter.step_scalar`, for a scalar signal in a 1 kHz loop such as the placement's
decision filter: no array is allocated, a few times cheaper than ``step`` on one channel).

The design is written out rather than called from :mod:`scipy.signal`: importing that package
took 1.8 s of the 3.2 s from ``ftcomp run``'s start to its loop's first cycle on the 2-core
reference machine (it parses the docstrings of every function it exports), for a dozen lines of
exact algebra.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from itertools import chain
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.errors import ParameterError

__all__ = ["LowPassFilter", "butterworth_sections"]

# One second-order section as floats: (b0, b1, b2, a1, a2); a0 is 1 (butter normalises it).
_Section = tuple[float, float, float, float, float]
# A signal: one float, or a numpy array of channels (the arithmetic is the same on both).
_Signal = TypeVar("_Signal", float, NDArray[np.float64])


def _sections_step(
    sections: Sequence[Sequence[_Signal]], state: Iterable[Sequence[_Signal]], x: _Signal
) -> tuple[list[tuple[_Signal, _Signal]], _Signal]:
    """One sample through the second-order sections, as :func:`scipy.signal.sosfilt` computes it
    (transposed direct form II).

    Args:
        sections: ``(b0, b1, b2, a1, a2)`` per section: floats for a float signal; for an array
            of channels, each coefficient repeated per channel (numpy multiplies two arrays
            faster than an array and a float; the products are the same).
        state: ``(z0, z1)`` per section, each a float or an array of channels like ``x``.
        x: the sample.

    Returns:
        The new ``(z0, z1)`` per section and the filtered sample.
    """
    y = x
    new = []
    for (b0, b1, b2, a1, a2), (z0, z1) in zip(sections, state, strict=True):
        out = y * b0 + z0
        new.append((y * b1 - out * a1 + z1, y * b2 - out * a2))
        y = out
    return new, y


def butterworth_sections(order: int, cutoff_hz: float, rate_hz: float) -> NDArray[np.float64]:
    """A digital Butterworth low-pass as second-order sections, ``(n_sections, 6)`` rows
    ``(b0, b1, b2, 1, a1, a2)`` in :func:`scipy.signal.butter`'s ``output="sos"`` layout.

    The analog prototype's poles ``exp(i pi (2k + order - 1) / (2 order))``, k = 1..order,
    scaled to the pre-warped cutoff ``2 rate tan(pi cutoff / rate)`` and mapped by the bilinear
    transform ``z = (2 rate + s) / (2 rate - s)``; every zero at z = -1. A conjugate pair is one
    section, the real pole of an odd order a first-order one (b2 = a2 = 0); the sections go
    from the pole farthest from the unit circle to the nearest (as scipy orders them), each
    with a gain of 1 at DC, so the cascade's is 1: the Butterworth's. (scipy spreads the gain
    differently over the sections: the cascade is the same.)

    Args:
        order: 1..8.
        cutoff_hz: -3 dB frequency, in (0, rate_hz / 2).
        rate_hz: sample rate.
    """
    warped = 2.0 * rate_hz * np.tan(np.pi * cutoff_hz / rate_hz)
    # The real pole -warped of an odd order (the farthest from the unit circle of all: the
    # first section), then the upper half plane's poles, k = order // 2 down to 1 (the others
    # are their conjugates), the farthest from the unit circle first.
    k = np.arange(order // 2, 0, -1)
    analog = [
        *([-warped] if order % 2 else []),
        *warped * np.exp(1j * np.pi * (2 * k + order - 1) / (2 * order)),
    ]
    rows = []
    for s in analog:
        pole = (2.0 * rate_hz + s) / (2.0 * rate_hz - s)
        # 1 - pole from the analog pole: for a low cutoff the pole is near 1, and the
        # difference of two numbers close to 1 would lose the section's gain.
        gap = -2.0 * s / (2.0 * rate_hz - s)
        if np.isreal(s):  # b = gain * (1, 1): the zero at -1, H(1) = 1
            gain = float(np.real(gap)) / 2.0
            rows.append((gain, gain, 0.0, 1.0, -float(np.real(pole)), 0.0))
        else:  # b = gain * (1, 2, 1): the zeros at -1, H(1) = 1
            gain = abs(gap) ** 2 / 4.0
            rows.append((gain, 2.0 * gain, gain, 1.0, -2.0 * pole.real, abs(pole) ** 2))
    return np.array(rows, dtype=float)


def _steady_state(sections: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each section's state after a unit input forever (:func:`scipy.signal.sosfilt_zi`):
    transposed direct form II at rest, ``y = x = 1`` through sections of unit DC gain."""
    b1, b2, a1, a2 = sections[:, 1], sections[:, 2], sections[:, 4], sections[:, 5]
    z1 = b2 - a2
    return np.stack([b1 - a1 + z1, z1], axis=1)


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
    _sections_per_channel: tuple[tuple[NDArray[np.float64], ...], ...] = field(
        init=False, repr=False, compare=False
    )
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
        sos = butterworth_sections(self.order, self.cutoff_hz, 1.0 / self.period_s)
        sos.setflags(write=False)
        object.__setattr__(self, "sos", sos)
        sections = tuple((b0, b1, b2, a1, a2) for b0, b1, b2, _a0, a1, a2 in sos.tolist())
        object.__setattr__(self, "_sections", sections)
        per_channel = tuple(tuple(np.full(self.channels, c) for c in sec) for sec in sections)
        object.__setattr__(self, "_sections_per_channel", per_channel)
        zi = _steady_state(sos)
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
        new, y = _sections_step(self._sections_per_channel, z, self._input(x))
        return np.array(new), y

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
        pairs = zip(state[0::2], state[1::2], strict=True)
        new, y = _sections_step(self._sections, pairs, float(x))
        return tuple(chain.from_iterable(new)), y

    def _input(self, x: ArrayLike) -> NDArray[np.float64]:
        arr = np.asarray(x, dtype=float)
        if arr.shape != (self.channels,):
            raise ParameterError(
                f"filter input must have shape ({self.channels},), got {arr.shape}"
            )
        return arr
