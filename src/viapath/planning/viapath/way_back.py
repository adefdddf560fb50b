"""The way back (``return_lookahead_m``, 0.5 m by default; 0 in the preset ``paper``): off the path line, the
paper's step 1 is tried first towards the path point that far ahead instead of the subgoal (docs/howto/tune-weights.md §6).
"""

from __future__ import annotations

import numpy as np

from viapath.planning.base import Plan
from viapath.planning.viapath.candidates import STRAIGHT, Choice, Way
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.follow import can_follow
from viapath.planning.viapath.plans import Chosen, Planning


def way_back(planner: Planning, checks: LegChecks, speed: float) -> Chosen | None:
    """Beyond the paper (``return_lookahead_m``): off the path line, the paper's step 1 towards the
    path point ``return_lookahead_m`` ahead instead of the subgoal, i.e. the free straight leg at the
    nominal speed, checked on along the path to the subgoal. None if there is none; then the paper's
    candidates decide. Eq. 1 never picks such a leg itself: it turns more (k4·θ) than the leg to a
    far subgoal and nothing in E rewards being on the path, so after a pass the robot would drift
    back on the shallow line to a subgoal metres away (docs/howto/tune-weights.md §6)."""
    back = checks.back_to_path(planner.config.return_lookahead_m)
    if back is None:
        return None
    _, _, free, _ = back.goal_legs(back.position[None], np.zeros(1), np.array([speed]))
    if not free[0]:
        return None
    plan = Plan(
        "straight",
        speed,
        back.subgoal.copy(),
        waypoints=np.array([back.position, back.subgoal, checks.subgoal]),
        subgoal_index=checks.subgoal_index,
        candidate_count=1,
        chosen=0,
        extras={"way_back": True},
    )
    if not (can_follow(plan, back, planner.limits, planner.config) and planner._inside_shield(plan)):
        return None
    return Chosen(Choice(Way(STRAIGHT, 0, 0), int(round(speed * 1000))), plan, None)
