"""Constraint hysteresis (``keep_previous_way``): under velocity noise last cycle's way round often looks blocked
for one cycle only because its inflation grew with the estimate's error; the plan then flips and flips back. If
last cycle's way is gone, it is searched for once more with ``keep_previous_inflation`` of the uncertainty
inflation (the safety margin stays) and kept if it still costs less than the new choice.

The other edge of the same band (``switch_inflation``): a way round that fits only just, under one cycle's
estimate, is gone the next under another; a pass taken on it is dropped a cycle later and the robot alternates
between trailing a walker and passing them. So while last cycle's way is still free, a new way round that goes
round someone (a plan with via points) replaces it only if it is free with ``switch_inflation`` times the
uncertainty inflation (its σ terms and the cap of the cone's growth); otherwise last cycle's way is kept (its
cheapest candidate). Slowing, waiting and the straight leg are never held back: they take the robot round
nobody. Where the estimates carry no σ (exact perception) both edges are the plain choice.
"""

from __future__ import annotations

from typing import cast

import numpy as np

from viapath.planning.viapath.candidates import Choice
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.plans import Chosen, Planning


def keep_previous_way(
    planner: Planning, chosen: Chosen, checks: LegChecks, speeds: np.ndarray, nominal_index: int
) -> Chosen:
    previous = cast(Choice, planner._previous)  # called only when there is one
    if chosen.candidates is None:
        return chosen  # a free straight leg at nominal speed (the paper's first choice)
    if chosen.choice.way == previous.way:
        return chosen  # the previous way chosen again (the test below would find it among the candidates)
    # Why the way changed, for analysis (tests/planning/test_motion_noise.py counts it): the relaxed search helps only
    # where the previous way vanished with the inflation, not where the forecast itself moved.
    why = chosen.plan.extras
    obstacles = checks.obstacles
    uncertain = bool(np.any(obstacles.position_sigma_m) or np.any(obstacles.velocity_sigma_mps))
    if previous.way.same(chosen.candidates.ways).any():
        if uncertain and not _fits_with_room(planner, chosen, checks, speeds, nominal_index):
            held = planner._choose(checks, speeds, nominal_index, previous, only_way=previous.way)
            if held is not None:
                held.plan.extras["kept_previous_way"] = True
                held.plan.extras["way_change"] = "held_new_way_too_tight"
                return held
        why["way_change"] = "cost"  # the previous way is still there: a fair switch on cost
        return chosen
    if not uncertain:
        why["way_change"] = "gone"  # no inflation to relax: the search would be the same
        return chosen
    relaxed = checks.with_less_inflation(
        planner.config.keep_previous_inflation, planner.robot_radius_m, planner.settings
    )
    kept = planner._choose(relaxed, speeds, nominal_index, previous, only_way=previous.way)
    if kept is None:
        why["way_change"] = "gone_relaxed_too"
        return chosen
    if kept.plan.candidate_costs[kept.plan.chosen] < chosen.plan.candidate_costs[chosen.plan.chosen]:
        kept.plan.extras["kept_previous_way"] = True
        return kept
    why["way_change"] = "relaxed_costs_more"
    return chosen


def _fits_with_room(
    planner: Planning, chosen: Chosen, checks: LegChecks, speeds: np.ndarray, nominal_index: int
) -> bool:
    """Whether the new way may replace last cycle's: it goes round nobody, or it is free with
    ``switch_inflation`` times the uncertainty inflation."""
    factor = float(planner.config.switch_inflation)
    if factor <= 1.0 or chosen.plan.status != "avoid":
        return True
    wider = checks.with_less_inflation(factor, planner.robot_radius_m, planner.settings, cap_too=True)
    return planner._choose(wider, speeds, nominal_index, None, only_way=chosen.choice.way) is not None
