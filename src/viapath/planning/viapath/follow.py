"""Step 4, the motion limits: the cheapest candidate the robot can actually follow.

Source: beyond the paper (its §5.2 names the robot's dynamics as future work); docs/design.md §2.

The x-y-t legs assume instant turns and speed changes. A candidate whose first leg needs a sharp turn
(more than ``rollout_heading_rad``) or a large speed change is rolled forward for ``rollout_s`` with
the controller that will drive it (arcs and lines within the limits, :func:`viapath.kinematics.track`)
and dropped if the roll-out touches an obstacle or leaves the corridor. Turning while moving can
swing out of the corridor: then the robot turns on the spot first, if standing is safe meanwhile
(the next cycles find it facing its leg). Even a small turn: at the corridor edge, or outside it
after an escape, a robot facing a little outwards would otherwise never get going again.

The check is compiled (:func:`.rollout.can_follow`); the compiled choice runs it on its candidates itself, and
this is its call for the plans made outside it (the way back, the straight leg, the ranks after a candidate
the shield refused).
"""

from __future__ import annotations

from viapath.observation import MotionLimits, Plan
from viapath.options import Settings
from viapath.planning.viapath import packing
from viapath.planning.viapath.checks import LegChecks


def can_follow(plan: Plan, checks: LegChecks, limits: MotionLimits, config: Settings) -> bool:
    """Whether the robot, steering for the plan's target within its limits, keeps clear of every
    obstacle and inside the corridor. May mark the plan ``extras["turn_in_place"]``."""
    verdict = packing.can_follow(checks, plan.target, plan.speed_mps, limits, config)
    if verdict == 2:
        plan.extras["turn_in_place"] = True
    return verdict > 0
