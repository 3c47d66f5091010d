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

Where the cell reports the whole contact wrench (six axes, :class:`ContactWrench` on the
simulated cell and the twin), the verdict also gives the lateral contact force, the surface's
force across gravity, and says where it comes from. A load set down by a position-servoed arm
sticks to a surface with friction; whatever the arm then does across the surface normal is held
by static friction and read as lateral contact force: the springback of the arm's servos that
sagged under the load's weight and are unloaded as the surface takes it (on the simulated cell:
about 25 um, pressed into the servo's ~70 N/mm, about 1.7 N on the sponge), and a descent along
the base's z axis that is not the surface normal (a tilted base). It does not change the
verdict, which is about what the surface carries along gravity.
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
        true_lateral_N: the surface's force across gravity at the decision [N] (None: the cell
            reports only the force along gravity).
    """

    verdict: Verdict
    true_press_N: float
    reason: str
    true_lateral_N: float | None = None

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
    lateral_N: float | None = None,
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
        lateral_N: the surface's force across gravity at the decision [N], from the six-axis
            true contact wrench; None where the cell reports only the force along gravity.

    Returns:
        The verdict, the true press and its reason.
    """
    if not (math.isfinite(tolerance_N) and tolerance_N > 0.0):
        raise ParameterError(f"tolerance_N must be finite and > 0, got {tolerance_N}")
    verdict = _judge_along_gravity(
        outcome, final_true_contact_N, peak_press_N, load_weight_N, tolerance_N
    )
    if lateral_N is None:
        return verdict
    if not (math.isfinite(lateral_N) and lateral_N >= 0.0):
        raise ParameterError(f"lateral_N must be finite and >= 0, got {lateral_N}")
    cause = (
        "held by static friction: the arm's servo springback as the surface takes the load's "
        "weight, and any descent across the surface normal"
        if lateral_N > tolerance_N
        else "negligible"
    )
    return PlacementVerdict(
        verdict.verdict,
        verdict.true_press_N,
        f"{verdict.reason}; lateral contact {lateral_N:.3f} N ({cause})",
        lateral_N,
    )


def _judge_along_gravity(
    outcome: str,
    final_true_contact_N: float,
    peak_press_N: float,
    load_weight_N: float,
    tolerance_N: float,
) -> PlacementVerdict:
    """The verdict from the surface's force along gravity alone."""
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
