"""Staying ahead of someone catching up from behind (``outrun_hold_s``; 0 in the preset ``paper``).

Eq. 1's time term makes the fastest free straight leg the cheapest, and step 1 takes the nominal leg back as soon
as it is free over the horizon, so the robot flipped between the top speed and nominal every few cycles at the
horizon's edge. When the straight leg at nominal is blocked by someone from behind whom the top speed outruns, the
straight leg faster than nominal is at the slowest speed whose leg stays free ``outrun_hold_s`` past the horizon
(:func:`outrun`), and the robot goes back to a slower one only when that leg stays free that long too, and not to
nominal within ``outrun_hold_s`` of last seeing someone to outrun (:func:`outrun_held`).
"""

from __future__ import annotations

from typing import cast

import numpy as np

from viapath.planning.base import Situation
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.plans import Chosen, Planning


def outrun_held(planner: Planning, checks: LegChecks, speeds: np.ndarray, nominal_index: int) -> Chosen | None:
    """Last cycle drove the straight leg faster than nominal and the nominal leg is free again, but
    only just: someone from behind would catch it within ``outrun_hold_s`` past the horizon. Then
    the slowest straight speed from nominal up whose leg is free that long (None: the usual choice).
    Free that long too, the robot still keeps above nominal for ``outrun_hold_s`` after it last saw
    someone to outrun. Without this the robot drops to nominal, is caught up with within a few
    cycles, speeds up again: a speed flip every half second at the horizon's edge."""
    nominal = float(speeds[nominal_index])
    if cast(float, planner._straight_speed) <= nominal + 1e-9:
        return None
    lookahead = planner.config.return_lookahead_m
    if lookahead > 0 and checks.back_to_path(lookahead) is not None:
        return None  # off the path line: the way back (:meth:`_way_back`) comes first
    at_nominal = np.array([nominal])
    if not checks.goal_legs(checks.position[None], np.zeros(1), at_nominal)[2][0]:
        return None
    hold = checks.horizon_s + planner.config.outrun_hold_s
    direction, _, free, contact = checks.goal_legs(checks.position[None], np.zeros(1), at_nominal, hold)
    if free[0]:
        # Free that long too: back to nominal, unless someone was being outrun within the hold (under
        # noise the nominal leg looks free in single cycles while the person still comes on).
        recently = _now(planner) - planner._outrun_seen_s < planner.config.outrun_hold_s
        return _slowest_holding(planner, checks, speeds[nominal_index + 1 :]) if recently else None
    if not catching_up(checks, direction[0], contact[0], nominal, float(speeds[-1])):
        return None
    planner._outrun_seen_s = _now(planner)
    return _slowest_holding(planner, checks, speeds[nominal_index:])


def outrun(
    planner: Planning, checks: LegChecks, speeds: np.ndarray, nominal_index: int, chosen: Chosen
) -> Chosen | None:
    """The cheapest plan is the straight leg faster than nominal, and the nominal leg is blocked by
    someone catching up from behind whom the top speed outruns: the slowest faster straight speed
    whose leg stays free ``outrun_hold_s`` past the horizon instead (None: keep ``chosen``). Eq. 1's
    time term prefers the fastest, from which the robot would drop back to nominal as soon as that
    leg is free, and so on."""
    plan, nominal = chosen.plan, float(speeds[nominal_index])
    if plan.status != "straight" or len(plan.waypoints) != 2 or plan.speed_mps <= nominal + 1e-9:
        return None
    direction, _, _, contact = checks.goal_legs(checks.position[None], np.zeros(1), np.array([nominal]))
    if not catching_up(checks, direction[0], contact[0], nominal, float(speeds[-1])):
        return None
    planner._outrun_seen_s = _now(planner)
    slower = speeds[(speeds > nominal + 1e-9) & (speeds < plan.speed_mps - 1e-9)]
    return _slowest_holding(planner, checks, slower) if len(slower) else None


def _now(planner: Planning) -> float:
    return float(cast(Situation, planner._situation).observation.time_s)


def catching_up(checks: LegChecks, direction: np.ndarray, contact: np.ndarray, nominal: float, top: float) -> bool:
    """Whether the first obstacle the straight leg meets (``contact``: its contact times) is behind the
    robot, coming along the leg faster than ``nominal`` and slower than ``top`` (one to outrun)."""
    if not np.isfinite(contact).any():
        return False
    first = int(np.argmin(contact))
    obstacles = checks.obstacles
    behind = float((obstacles.positions[first] - checks.position) @ direction) < 0
    along = float(obstacles.velocities[first] @ direction)
    return behind and nominal < along < top


def _slowest_holding(planner: Planning, checks: LegChecks, speeds: np.ndarray) -> Chosen | None:
    """The straight leg at the slowest of ``speeds`` (ascending) whose leg is free ``outrun_hold_s``
    past the horizon, if the robot can follow it (None: the first such cannot, or none is free)."""
    hold = checks.horizon_s + planner.config.outrun_hold_s
    speeds = np.asarray(speeds, dtype=float)
    starts = checks.position[None].repeat(len(speeds), axis=0)
    _, _, free, _ = checks.goal_legs(starts, np.zeros(len(speeds)), speeds, hold)
    if not free.any():
        return None
    return planner._straight(checks, float(speeds[int(np.argmax(free))]))
