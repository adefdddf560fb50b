"""Static geometry beyond the paper (it draws its path boundary round static things): the static discs no
candidate can meet are left out of the cycle (:func:`near_corridor`), and when no candidate is free the
corridor's free space, flooded from the robot (:mod:`.flood`), says whether static geometry closes the way.

* **A way round** (:func:`detour`). The subgoal is reachable through the static world, but the candidate
  tree finds nothing even with the people left out (its legs run straight to the subgoal and on along the
  next segment, so a box just past a corner, or a subgoal out of sight round a wall, defeats it for good).
  Then the tree runs again towards an intermediate target: the farthest point of the flood's shortest way
  to the subgoal that the robot reaches by a straight leg clear of static geometry inside the corridor,
  every point of the way before it reached so too; with the subgoal itself in sight, the subgoal without
  the check along the next segment (the robot looks again there). People are checked as in any cycle.
  When people are what leave the tree empty, nothing changes: the robot stops as before.
* **A closed way** (:func:`blocked`). No free candidate, standing is safe, and the flood does not reach the
  subgoal (nor any point of the path past it): the robot drives to the farthest point along the path that
  it reaches with ``blocked_gap_m`` to spare beyond its check radius, by the flood's shortest way (towards
  the farthest point of it in sight, as above), at a speed from which it stops there, and waits; status
  ``blocked``. Where the straight leg to the subgoal gets as far (to within ``STRAIGHT_SLACK_M`` along the
  path: a door across the path, nothing before it), the robot stops on that leg as below, exactly
  ``blocked_gap_m`` short of the door rather than at a cell of the grid. Each cycle looks again, so the robot goes on when a door opens. The leg it drives is
  checked against people and the corridor as any leg; if it is not free the robot stops.
* Without a flood to go by (the robot's own cell and every cell near it within its check radius of static
  geometry), and when the way is open but people leave no candidate, the closed way is what it was before
  the flood: along the straight leg to the subgoal, if static geometry meets it before any person, to
  ``blocked_gap_m`` short of touching it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from viapath.observation import Command
from viapath.options import Settings
from viapath.planning.base import Decision, Inflation, Plan, Situation
from viapath.planning.viapath.candidates import Candidates, RootLegs
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.flood import FloodCache, FreeSpace
from viapath.planning.viapath.plans import Chosen, Planning

# m: a robot this close to where it is to wait is there (it stands)
AT_REST_POINT_M = 0.05
# m: the straight leg's stop is taken when it is no more than this short of the flood's point along the path
STRAIGHT_SLACK_M = 0.3
# the route is tried as legs from the robot to every this many cells of it (a 10 cm step on a 5 cm grid)
ROUTE_STEP_CELLS = 2

Tree = Callable[[LegChecks, RootLegs, Settings], "Candidates | None"]


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


# -- the flood -------------------------------------------------------------------------------------------


def _flood(planner: Planning, checks: LegChecks) -> tuple[FreeSpace, tuple[int, int]] | None:
    """This cycle's free space (kept by the planner while the static discs stay the same) and the cell the
    robot starts from; None without static geometry or a free cell at the robot. Made once per cycle (the
    way round and the closed way both ask)."""
    kept = checks.__dict__.get("_flood")
    if kept is None:
        kept = checks.__dict__["_flood"] = (_flood_of(planner, checks),)
    return kept[0]


def _flood_of(planner: Planning, checks: LegChecks) -> tuple[FreeSpace, tuple[int, int]] | None:
    static = checks.obstacles.is_static
    if not static.any():
        return None
    cache = planner.__dict__.get("_flood_cache")
    if cache is None:
        cache = planner.__dict__["_flood_cache"] = FloodCache()
    rows = np.flatnonzero(static)
    radii = np.broadcast_to(checks.check_radii, static.shape)[rows]
    space = cache.free_space(
        checks.path, checks.position, checks.obstacles.positions[rows], radii, radii + planner.config.blocked_gap_m
    )
    if space is None:
        return None
    start = space.seed(checks.position)
    return None if start is None else (space, start)


def _onward(
    planner: Planning, checks: LegChecks, space: FreeSpace, start: tuple[int, int]
) -> tuple[bool, tuple[int, int]] | None:
    """(open, cell): whether the static world lets the robot reach the subgoal (within the distance at which
    it counts as reached) or a point of the path past it, and the cell to head for: the subgoal's, else the
    resting cell farthest along the path. None when the robot's part of the free space has no resting cell."""
    policy = planner.subgoals.policy
    within = policy.goal_tolerance_m if checks.is_final_subgoal else policy.reach_threshold_m
    at_subgoal = space.reaches(start, checks.subgoal, max(within, space.cell_m))
    if at_subgoal is not None:
        return True, at_subgoal
    farthest = space.farthest(start)
    if farthest is None:
        return None
    past = space.corridor.arc_m[farthest] >= checks.path.cumulative_length_m[checks.subgoal_index]
    return bool(past), farthest


def _in_sight(checks: LegChecks, route: np.ndarray) -> int:
    """How many points of ``route`` (every ``ROUTE_STEP_CELLS``-th and its last) the robot reaches, one after
    another, by straight legs from where it is that keep clear of static geometry and inside the corridor:
    the index + 1 of the farthest point so reached (0: not even the first)."""
    picked = np.unique(np.r_[np.arange(0, len(route), ROUTE_STEP_CELLS), len(route) - 1])
    points = route[picked]
    starts = np.repeat(checks.position[None], len(points), axis=0)
    offsets = points - starts
    lengths = np.hypot(offsets[:, 0], offsets[:, 1])
    velocities = offsets / np.maximum(lengths, 1e-9)[:, None]  # 1 m/s: the leg's duration is its length
    contact = checks.contact_times(starts, np.zeros(len(points)), velocities, lengths, np.inf)
    ok = np.isinf(contact[:, checks.obstacles.is_static]).all(axis=1) & checks.legs_inside(starts, points)
    reached = int(np.argmin(ok)) if not ok.all() else len(ok)
    return 0 if reached == 0 else int(picked[reached - 1]) + 1


def _continuation_meets_static(checks: LegChecks, speed_mps: float) -> bool:
    """Whether the leg along the next segment from the subgoal meets static geometry."""
    if checks.continuation is None:
        return False
    direction, length = checks.continuation
    contact = checks.contact_times(
        checks.subgoal[None], np.zeros(1), (direction * speed_mps)[None], np.array([length / speed_mps]), np.inf
    )
    return bool(np.isfinite(contact[0, checks.obstacles.is_static]).any())


def _static_closes_the_tree(
    planner: Planning, checks: LegChecks, speeds: np.ndarray, nominal_index: int, tree: Tree
) -> bool:
    """Whether the candidate tree finds no candidate even with the people left out: static geometry alone
    leaves it empty, for as long as the static world stays as it is. Kept for the same robot position,
    speeds, subgoal and static discs (a waiting robot asks every cycle)."""
    static = checks.obstacles.is_static
    positions = checks.obstacles.positions[static]
    key = (
        checks.position.tobytes(),
        np.asarray(speeds).tobytes(),
        checks.subgoal.tobytes(),
        positions.tobytes(),
        np.broadcast_to(checks.check_radii, static.shape)[static].tobytes(),
    )
    kept = planner.__dict__.get("_static_tree")
    if kept is not None and kept[0] == key:
        return bool(kept[1])
    rows = np.flatnonzero(static)

    def kept_rows(values: np.ndarray) -> np.ndarray:
        return np.broadcast_to(values, static.shape)[rows]

    alone = dataclasses.replace(
        checks,
        obstacles=checks.obstacles.subset(rows),
        check_radii=kept_rows(checks.check_radii),
        growth=kept_rows(checks.growth),
        growth_until_s=kept_rows(checks.growth_until_s),
        via_radii=kept_rows(checks.via_radii),
    )
    roots = RootLegs.of(alone, speeds, nominal_index)
    closes = not roots.free.any()
    if closes:
        candidates = tree(alone, roots, planner.config)
        closes = candidates is None or len(candidates) == 0
    planner.__dict__["_static_tree"] = (key, closes)
    return closes


# -- a way round ------------------------------------------------------------------------------------------


def detour(planner: Planning, checks: LegChecks, speeds: np.ndarray, nominal_index: int, tree: Tree) -> Chosen | None:
    """No candidate is free: if static geometry alone leaves the candidate tree empty while the flood reaches
    the subgoal, the candidates towards an intermediate target on the flood's way there (see the module
    docstring); the plan says ``detour`` in its extras. None otherwise."""
    flood = _flood(planner, checks)
    if flood is None:
        return None
    space, start = flood
    onward = _onward(planner, checks, space, start)
    if onward is None or not onward[0]:
        return None
    if not _static_closes_the_tree(planner, checks, speeds, nominal_index, tree):
        return None
    route = space.route(start, onward[1])
    seen = _in_sight(checks, route) if len(route) else 0
    if seen < min(2, len(route)):  # not even the route's first step in sight
        return None
    if seen == len(route) and space.reaches(start, checks.subgoal, space.cell_m) is not None:
        # The subgoal is in sight: what leaves the tree empty is the way on along the next segment.
        if not _continuation_meets_static(checks, float(speeds[nominal_index])):
            return None
        target = checks.subgoal.copy()
    else:
        target = route[seen - 1]
    towards = dataclasses.replace(checks, subgoal=target, continuation=None, stop_short_m=0.0)
    chosen = planner._choose(towards, speeds, nominal_index, None)
    if chosen is not None:
        chosen.plan.subgoal_index = checks.subgoal_index
        chosen.plan.extras["detour"] = {"target": target.tolist(), "subgoal": checks.subgoal.tolist()}
    return chosen


# -- a closed way -----------------------------------------------------------------------------------------


def blocked(planner: Planning, situation: Situation, checks: LegChecks, speed_mps: float) -> Decision | None:
    """No candidate is free and standing is safe: if the flood does not reach the subgoal, drive to the
    farthest point along the path the static world lets the robot reach and wait there, status ``blocked``
    (see the module docstring); None when people block that way (the caller's stop stands)."""
    flood = _flood(planner, checks)
    onward = None if flood is None else _onward(planner, checks, *flood)
    if flood is None or onward is None or onward[0]:
        return _straight_blocked(planner, situation, checks, speed_mps)
    space, start = flood
    goal = space.centre(onward[1])
    position = checks.position
    straight = _straight_blocked(planner, situation, checks, speed_mps)
    arc = checks.path.project(np.stack([position, goal, position if straight is None else straight.plan.target]))[1]
    if straight is not None and arc[2] >= arc[1] - STRAIGHT_SLACK_M:
        return straight  # the straight leg gets as far as the flood's point (a door across the path)
    route = space.route(start, onward[1])
    if len(route) == 0 or arc[1] <= arc[0] + space.cell_m or float(np.hypot(*(goal - position))) <= AT_REST_POINT_M:
        return _standing(checks, goal, "static geometry closes the way; waiting at the farthest point it leaves")
    seen = _in_sight(checks, route)
    if seen < min(2, len(route)):  # not even the route's first step in sight
        return None
    target = route[seen - 1]
    steps = np.diff(route[seen - 1 :], axis=0)
    ahead_m = float(np.hypot(*(target - position))) + float(np.hypot(steps[:, 0], steps[:, 1]).sum())
    speed = min(speed_mps, math.sqrt(planner.limits.max_accel_mps2 * ahead_m))
    leg_m = float(np.hypot(*(target - position)))
    if speed < 0.02 or ahead_m < 0.02 or leg_m < 1e-3:
        return _standing(checks, goal, "static geometry closes the way; waiting at the farthest point it leaves")
    direction = (target - position) / leg_m
    if not (
        checks.legs_free(position[None], np.zeros(1), direction[None] * speed, np.array([leg_m / speed]))[0]
        and checks.legs_inside(position[None], target[None])[0]
    ):
        return None
    plan = Plan(
        "blocked",
        speed,
        target.copy(),
        waypoints=np.concatenate([position[None], route[seen - 1 :]]),
        subgoal_index=checks.subgoal_index,
        extras={
            "blocked": f"static geometry closes the way; driving {ahead_m:.2f} m to the farthest point it leaves",
            "wait_at": goal.tolist(),
        },
    )
    return Decision(planner._command(situation, plan), plan)


def _standing(checks: LegChecks, goal: np.ndarray, reason: str) -> Decision:
    plan = Plan(
        "blocked",
        0.0,
        checks.position.copy(),
        waypoints=np.array([checks.position, goal]),
        subgoal_index=checks.subgoal_index,
        extras={"blocked": reason, "wait_at": goal.tolist()},
    )
    return Decision(Command.stop(), plan)


def _straight_blocked(planner: Planning, situation: Situation, checks: LegChecks, speed_mps: float) -> Decision | None:
    """The closed way along the straight leg: if static geometry meets the straight leg to the subgoal before
    anything else, drive on along it to ``blocked_gap_m`` short of where the robot would touch it, at a
    speed from which it stops there, and wait; status ``blocked``. None when people block the way first."""
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
