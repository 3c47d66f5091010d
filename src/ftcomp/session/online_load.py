"""The online load estimate in the live sessions (``ftcomp stream`` and ``ftcomp run`` with
``--online-load``): what a session checks before it weighs a load, and its events as lines.

The estimate itself runs in the cycle's wrench pipeline
(:class:`~ftcomp.compensation.pipeline.WrenchPipeline`: an
:class:`~ftcomp.compensation.online.OnlineLoadCompensator` followed by a
:class:`~ftcomp.compensation.online.LoadTracker`, the log's load columns and the grasp, release
and contact events).
"""

from __future__ import annotations

from ftcomp.calibration_record import Calibration
from ftcomp.compensation.online import LoadEvent
from ftcomp.errors import ParameterError
from ftcomp.model import GravityModel

__all__ = ["event_lines", "require_tool_weight"]


def require_tool_weight(calibration: Calibration | GravityModel, source: str) -> None:
    """Refuse a calibration the online estimator cannot use (a weightless tool gives no gravity
    direction to weigh a load along).

    Raises:
        ParameterError: the tool weight is 0, naming ``source`` (the calibration file).
    """
    model = calibration.model if isinstance(calibration, Calibration) else calibration
    if not model.weight_N:
        raise ParameterError(
            f"{source}: the tool weight is 0 N: online load estimation needs a calibration "
            "with the tool's weight (its direction is gravity's)"
        )


def event_lines(events: list[LoadEvent], *, limit: int = 20) -> list[str]:
    """The events as lines to print (the first ``limit``, then how many more)."""
    if not events:
        return ["online load: no grasp or release detected"]
    lines = ["online load events (t on the log's clock; mass ± 1 standard deviation):"]
    lines += [f"  {e.describe()}" for e in events[:limit]]
    if len(events) > limit:
        lines.append(f"  ... and {len(events) - limit} more")
    return lines
