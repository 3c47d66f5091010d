"""Where a loop's timing was before it joined the rest of time in :mod:`ftcomp.hardware.pacing`.

:class:`~ftcomp.hardware.pacing.LoopTiming` and :class:`~ftcomp.hardware.pacing.TimingSummary`
are defined there; this module names them for ``ftcomp twin`` (``twin/serve.py``) until it keeps
time with :class:`~ftcomp.hardware.pacing.LoopClock`, and then goes.
"""

from __future__ import annotations

from ftcomp.hardware.pacing import LoopTiming, TimingSummary

__all__ = ["LoopTiming", "TimingSummary"]
