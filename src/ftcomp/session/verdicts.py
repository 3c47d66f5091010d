"""What became of the load in a placement run, judged from the *true* contact force.

The controller decides from the force it senses; a wrong calibration (or none) makes it decide
wrongly while its own signal looks perfect (the paper's Fig. 7 without compensation settles at
0 N sensed while the load is pressed into the sponge). The verdict therefore looks at what the
surface really carries (the simulator's truth, or a scale under a real surface):

- ``"placed gently"``: the run reached its decision and the surface carries the load's weight
  within ``tolerance_N``, at the decision and at every moment before it;
- ``"pressed"``: the run reached its decision, but the surface carries more than the load's
  weight plus ``tolerance_N`` at the decision or at some moment before it (the robot pushes
  the load into the surface);
- ``"released early"``: the run decided while the gripper still held more than ``tolerance_N``
  of the load (it drops when the gripper opens);
- ``"stopped"``: a safety limit or the time-out ended the run before any decision.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final, Literal

from ftcomp.errors import ParameterError

__all__ = ["DECIDED_OUTCOMES", "VERDICTS", "PlacementVerdict", "Verdict", "judge_placement"]

Verdict = Literal["placed gently", "pressed", "released early", "stopped"]

#: Every verdict, best first.
VERDICTS: Final[tuple[Verdict, ...]] = ("placed gently", "pressed", "released early", "stopped")

#: Run outcomes (``stop_reason``) where the experiment reached its decision: the admittance
#: band was held (``placed``) or the position-only descent reached its depth.
DECIDED_OUTCOMES: Final = ("placed", "depth_reached")


@dataclass(frozen=True)
class PlacementVerdict:
    """A run's verdict, the true press behind it and a one-line reason.

    Attributes:
        verdict: one of :data:`VERDICTS`.
        true_press_N: surface force beyond the load's weight when the run was decided or
            stopped [N] (> 0: pressed into the surface, < 0: the gripper still held part of it).
        reason: one line for a person, with the numbers.
    """

    verdict: Verdict
    true_press_N: float
    reason: str

    @property
    def failed(self) -> bool:
        """The run never reached its decision (a stop or the time-out)."""
        return self.verdict == "stopped"


def judge_placement(
    outcome: str,
    final_true_contact_N: float,
    peak_press_N: float,
    load_weight_N: float,
    tolerance_N: float,
) -> PlacementVerdict:
    """Judge one run from the true contact force.

    Args:
        outcome: how the run ended (``stop_reason``: ``placed``, ``depth_reached``, a safety
            stop such as ``force_limit``, or ``timeout``).
        final_true_contact_N: force the surface pushes up on the load when the run was decided
            or stopped [N].
        peak_press_N: the largest surface force beyond the load's weight during the run [N].
        load_weight_N: the load's true weight [N].
        tolerance_N: the largest press (or weight still held) that counts as gentle [N].

    Returns:
        The verdict, the true press and its reason.
    """
    if not (math.isfinite(tolerance_N) and tolerance_N > 0.0):
        raise ParameterError(f"tolerance_N must be finite and > 0, got {tolerance_N}")
    press = final_true_contact_N - load_weight_N
    if outcome not in DECIDED_OUTCOMES:
        return PlacementVerdict(
            "stopped",
            press,
            f"stopped by {outcome.replace('_', ' ')} before placing; the surface then pushed "
            f"{final_true_contact_N:.3f} N against the load's {load_weight_N:.3f} N "
            f"(true press {press:+.3f} N)",
        )
    worst = max(press, peak_press_N)
    if worst > tolerance_N:
        when = "at the end" if press >= peak_press_N else f"at the peak ({press:+.3f} N at the end)"
        return PlacementVerdict(
            "pressed",
            press,
            f"pressed {worst:.3f} N into the surface {when}: more than the ±{tolerance_N:g} N a "
            f"gentle placement allows (surface force {final_true_contact_N:.3f} N, load "
            f"{load_weight_N:.3f} N)",
        )
    if press < -tolerance_N:
        return PlacementVerdict(
            "released early",
            press,
            f"decided with {-press:.3f} N of the load still held: it drops when the gripper "
            f"opens (allowed ±{tolerance_N:g} N)",
        )
    return PlacementVerdict(
        "placed gently",
        press,
        f"the surface carries the load's weight within {abs(press):.3f} N "
        f"(allowed ±{tolerance_N:g} N, peak press {peak_press_N:.3f} N)",
    )
