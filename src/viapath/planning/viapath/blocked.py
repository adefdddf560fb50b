"""Static geometry beyond the paper (it draws its path boundary round static things): the static discs no
candidate can meet are left out of the cycle (:func:`near_corridor`), and a way closed by static geometry is not
a plain stop (:func:`blocked`): the robot drives on to ``blocked_gap_m`` short of it and waits, status
``blocked``; every cycle looks again, so it goes on when the door opens.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from viapath.observation import Command
from viapath.planning.base import Decision, Inflation, Plan, Situation
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.plans import Planning


def near_corridor(planner: Planning, situation: Situation) -> Situation:
    """The situation without the static discs no candidate can meet: every leg of a candidate stays in the
    corridor (or within the escape's bound of it), so a static disc farther outside than its check
    radius cannot touch one. Walls of other rooms cost nothing then."""
    obstacles, inflation = situation.obstacles, situation.inflation
    reach = inflation.check_radii + max(situation.corridor_tolerance_m, planner.config.escape_max_excess_m)
    far = obstacles.is_static & (planner.path.corridor_excess(obstacles.positions) > reach)
    if not far.any():
        return situation
    keep = ~far
    kept = Inflation(
        *(getattr(inflation, name)[keep] for name in ("obstacle_radii_m", "check_radii", "growth", "growth_until_s"))
    )
    return dataclasses.replace(situation, obstacles=obstacles.subset(keep), inflation=kept)


def blocked(planner: Planning, situation: Situation, checks: LegChecks, speed_mps: float) -> Decision | None:
    """No candidate is free and standing is safe: if static geometry closes the way to the subgoal (a
    closed door, a wall across the corridor) and nothing else meets the straight leg before it, drive on
    along that leg to ``blocked_gap_m`` short of where the robot would touch it, at a speed from which
    it stops there, and wait; status ``blocked``. Each cycle looks again, so the robot goes on when
    the way opens. None when people block the way first (the caller's stop stands)."""
    position, subgoal = checks.position, checks.subgoal
    offset = subgoal - position
    length = float(np.hypot(*offset))
    if length < 1e-6:
        return None
    direction = offset / length
    contact = checks.contact_times(
        position[None], np.zeros(1), direction[None] * speed_mps, np.array([length / speed_mps]), np.inf
    )[0]
    first = int(np.argmin(contact))
    if not (math.isfinite(contact[first]) and checks.obstacles.is_static[first]):
        return None
    ahead_m = max(0.0, speed_mps * float(contact[first]) - planner.config.blocked_gap_m)
    stop_at = position + direction * ahead_m
    speed = min(speed_mps, math.sqrt(planner.limits.max_accel_mps2 * ahead_m))
    if speed < 0.02 or ahead_m < 0.02:
        speed, stop_at = 0.0, position.copy()
    elif not (
        checks.legs_free(position[None], np.zeros(1), direction[None] * speed, np.array([ahead_m / speed]))[0]
        and checks.legs_inside(position[None], stop_at[None])[0]
    ):
        return None
    plan = Plan(
        "blocked",
        speed,
        stop_at,
        waypoints=np.array([position, stop_at]),
        subgoal_index=checks.subgoal_index,
        extras={"blocked": f"static geometry closes the way {speed_mps * float(contact[first]):.2f} m ahead"},
    )
    command = Command.stop() if speed == 0.0 else planner._command(situation, plan)
    return Decision(command, plan)
