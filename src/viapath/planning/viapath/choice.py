"""The planner's choice (paper steps 1-4: step 1, the candidates, Eq. 1, the cheapest the robot can follow) in
one compiled call, :func:`viapath.planning.viapath.packing.choose`, up to the shield's check of the candidate it
found; a candidate the shield refuses sends the search on to the next ones here. Every cycle takes it, with static
geometry in view or not; critics beyond the paper's (:func:`extra_critics`) are scored between its two halves.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from viapath.planning.base import Plan
from viapath.planning.viapath import packing
from viapath.planning.viapath import slots as slot
from viapath.planning.viapath.candidates import Choice, Way, candidates_of
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.critics import PAPER_CRITICS, Context, Critic
from viapath.planning.viapath.follow import can_follow
from viapath.planning.viapath.packing import CompiledChoice, NodeStore
from viapath.planning.viapath.plans import (
    Chosen,
    CompiledCandidates,
    Planning,
    cost_terms,
    straight_chosen,
    straight_plan,
)

if TYPE_CHECKING:
    from viapath.planning.viapath.critics import Distance, Heading, Hysteresis, SidePreference, SpeedError, Time


def extra_critics(planner: Planning) -> tuple[Critic, ...]:
    """The planner's critics after the paper's (:data:`.critics.PAPER_CRITICS`, whose term functions the compiled
    choice calls itself, with their weights: :func:`_choice_constants`): the choice scores these with their own
    ``score`` between its two halves. The critics must begin with the paper's, in Eq. 1's order
    (:func:`.critics.critics_for`)."""
    critics = planner.critics
    cached = planner.__dict__.get("_extra_critics")  # (critics, the answer): every cycle asks
    if cached is None or cached[0] is not critics:
        if tuple(map(type, critics[: len(PAPER_CRITICS)])) != PAPER_CRITICS:
            raise ValueError(
                "planner.critics: expected the paper's critics first (critics_for(config)), then any others; found "
                + ", ".join(type(critic).__name__ for critic in critics)
            )
        cached = planner.__dict__["_extra_critics"] = (critics, tuple(critics[len(PAPER_CRITICS) :]))
    return cached[1]


def _extra_terms(
    planner: Planning, checks: LegChecks, previous: Choice | None
) -> Callable[[NodeStore, np.ndarray], np.ndarray] | None:
    """The scoring of :func:`extra_critics` for :func:`.packing.choose` (None: there are none)."""
    critics = extra_critics(planner)
    if not critics:
        return None
    context = Context(checks.heading_rad, planner.nominal_speed_mps, previous)

    def terms(store: NodeStore, leaves: np.ndarray) -> np.ndarray:
        candidates = candidates_of(store, checks.subgoal)
        return np.array([critic.score(candidates, context) for critic in critics], dtype=np.float64).reshape(
            len(critics), len(leaves)
        )

    return terms


def _choice_constants(planner: Planning) -> tuple[Any, ...]:
    """The compiled choice's settings that do not change within an episode (rebuilt when the options, limits or
    critics object is replaced); their slots: :mod:`viapath.planning.viapath.slots`."""
    config, limits, critics, nominal_speed = planner.config, planner.limits, planner.critics, planner.nominal_speed_mps
    cached = planner.__dict__.get("_choice_cache")
    if (
        cached is not None
        and cached[0] is config
        and cached[1] is limits
        and cached[2] is critics
        and cached[3] is nominal_speed
    ):
        return cached[4]
    distance, time, speed, heading, side, hysteresis = cast(
        "tuple[Distance, Time, SpeedError, Heading, SidePreference, Hysteresis]", planner.critics[: len(PAPER_CRITICS)]
    )  # the paper's critics (PAPER_CRITICS, first: extra_critics): the ones the compiled choice sums itself
    settings = np.zeros(slot.F_COUNT, dtype=np.float64)
    settings[[slot.F_K1, slot.F_K2, slot.F_K3, slot.F_K4, slot.F_SIDE, slot.F_HYSTERESIS]] = (
        distance.weight,
        time.weight,
        speed.weight,
        heading.weight,
        side.weight,
        hysteresis.weight,
    )
    settings[slot.F_NOMINAL] = planner.nominal_speed_mps
    settings[slot.F_ROLLOUT_HEADING] = config.rollout_heading_rad
    settings[slot.F_ACCEL] = limits.max_accel_mps2
    settings[slot.F_DT] = config.rollout_dt_s
    settings[slot.F_TURN_RATE] = limits.max_turn_rate_radps
    settings[slot.F_TURN_ACCEL] = limits.max_turn_accel_radps2
    settings[slot.F_SPEED] = limits.max_speed_mps
    settings[slot.F_GAIN] = config.heading_gain
    settings[slot.F_TURN_IN_PLACE] = config.turn_in_place_min_rad
    settings[slot.F_SPACING] = config.corridor_check_spacing_m
    settings[slot.F_STANDING] = speed.standing_per_s
    settings[slot.F_CREEP] = config.creep_speed_mps
    integers = np.zeros(slot.C_COUNT, dtype=np.int64)
    integers[slot.C_DEPTH] = config.max_depth
    integers[slot.C_ROOT_LIMIT] = config.max_root_obstacles
    integers[slot.C_ROLLOUTS] = config.max_rollouts
    integers[slot.C_STEPS] = max(1, int(round(config.rollout_s / config.rollout_dt_s)))
    integers[slot.C_DEGREES] = heading.degrees
    integers[slot.C_PREFERRED] = side.preferred
    integers[slot.C_SLOW] = bool(config.slow_times_s)
    slow_times = np.asarray(config.slow_times_s, dtype=np.float64).reshape(-1)
    constants = (settings, integers, slow_times)
    planner.__dict__["_choice_cache"] = (config, limits, critics, nominal_speed, constants)
    return constants


def choose_compiled(
    planner: Planning,
    checks: LegChecks,
    speeds: np.ndarray,
    nominal_index: int,
    previous: Choice | None,
    only_way: Way | None,
) -> Chosen | None:
    """The planner's choice with one compiled call doing everything up to the shield check
    (:func:`viapath.planning.viapath.selection.choose`): it rolls out candidates cheapest first until one follows; a
    candidate the shield refuses sends the search on to the next ones here (:func:`_first_admitted`)."""
    settings, integers, slow_times = _cycle_settings(planner, checks, nominal_index, previous, only_way)
    slow_checks = planner._slow_checks(checks)
    extra = _extra_terms(planner, checks, previous)
    chosen = packing.choose(checks, slow_checks, speeds, slow_times, settings, integers, extra)
    if chosen.status == slot.STEP_ONE:
        plan = straight_plan(checks, float(speeds[nominal_index]))
        if chosen.turn_in_place:
            plan.extras["turn_in_place"] = True
        if planner._inside_shield(plan):
            return straight_chosen(plan)
        integers[slot.C_TRY_STRAIGHT] = 0  # the shield refused it: the candidates decide
        chosen = packing.choose(checks, slow_checks, speeds, slow_times, settings, integers, extra)
    if chosen.status != slot.CANDIDATES or chosen.first < 0:  # first: the ranks before it do not follow
        return None
    return _first_admitted(planner, chosen, checks)


def tree_is_empty(planner: Planning, checks: LegChecks, speeds: np.ndarray, nominal_index: int) -> bool:
    """Whether the candidate tree of ``checks`` has no candidate at all (no free root either; step 1 is not
    taken): the compiled choice's tree alone (:func:`.packing.choose` with ``TREE_ONLY``)."""
    settings, integers, slow_times = _cycle_settings(planner, checks, nominal_index, None, None)
    integers[slot.C_TRY_STRAIGHT] = 0
    found = packing.choose(checks, checks, speeds, slow_times, settings, integers, packing.TREE_ONLY)
    return found.status != slot.CANDIDATES


def _cycle_settings(
    planner: Planning, checks: LegChecks, nominal_index: int, previous: Choice | None, only_way: Way | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The compiled choice's settings of this cycle: the episode's (:func:`_choice_constants`) with the cycle's
    entries (the horizon, the subgoal, last cycle's way and speed, the one way allowed)."""
    constants, integers_0, slow_times = _choice_constants(planner)
    settings = constants.copy()  # with this cycle's entries:
    settings[slot.F_STOP_SHORT] = checks.stop_short_m
    settings[slot.F_HORIZON] = checks.horizon_s
    settings[slot.F_TOLERANCE] = checks.corridor_tolerance_m
    integers = integers_0.copy()  # (one item at a time: a slice from a tuple converts it first, slower)
    index = checks.subgoal_index
    integers[slot.C_NOMINAL] = nominal_index
    if index >= 2:  # the robot's segment matters only when a corner can lie between it and the subgoal
        integers[slot.C_SEGMENT] = int(checks.path.project(checks.position)[0])
    integers[slot.C_SUBGOAL] = index
    integers[slot.C_TRY_STRAIGHT] = 1
    if previous is not None:
        way = previous.way
        integers[slot.C_PREVIOUS] = 1
        integers[slot.C_PREV_OBSTACLE] = way.obstacle
        integers[slot.C_PREV_SIDE] = way.side
        integers[slot.C_PREV_ROOT] = way.root
        integers[slot.C_PREV_MMPS] = previous.speed_mmps
    if only_way is not None:
        integers[slot.C_ONLY] = 1
        integers[slot.C_ONLY_OBSTACLE] = only_way.obstacle
        integers[slot.C_ONLY_SIDE] = only_way.side
        integers[slot.C_ONLY_ROOT] = only_way.root
    return settings, integers, slow_times


def _first_admitted(planner: Planning, chosen: CompiledChoice, checks: LegChecks) -> Chosen | None:
    """The cheapest candidate from the compiled choice's first that follows on that the robot can follow and the
    shield admits (past that first one, each is rolled out here: only after the shield refused it)."""
    leaves, order, follow, total, store = chosen.leaves, chosen.order, chosen.follow, chosen.total, chosen.store
    for rank in range(chosen.first, min(len(order), planner.config.max_rollouts)):
        best = order[rank]
        if not math.isfinite(total[best]):
            break
        verdict = follow[rank]
        if verdict == 0:
            continue
        plan = _plan_of_nodes(store, leaves, best, total, checks, _polylines(planner, store, leaves, checks))
        if verdict < 0:  # past the first that follows: only after the shield refused that one
            verdict = can_follow(plan, checks, planner.limits, planner.config)
        elif verdict == 2:
            plan.extras["turn_in_place"] = True
        if verdict and planner._inside_shield(plan):
            plan.extras["cost_terms"] = cost_terms(_cost_breakdown(planner, chosen.terms), order, rank, total)
            node = int(leaves[best])
            way, speed = store.way(node), store.speed(node)
            return Chosen(
                Choice(Way(*way), int(round(speed * 1000))),
                plan,
                CompiledCandidates(store, leaves, checks.subgoal),
            )
    return None


def _cost_breakdown(planner: Planning, terms: np.ndarray) -> Callable[[int], dict[str, float]]:
    """Each critic's term of candidate k and their sum, by name, as Python floats, of the compiled choice's costs
    (rows: the critics' terms, then E)."""
    critics = planner.critics
    cached = planner.__dict__.get("_cost_names")
    if cached is None or cached[0] is not critics:
        cached = planner.__dict__["_cost_names"] = (critics, tuple(critic.name for critic in critics) + ("total",))
    names = cached[1]
    return lambda k: dict(zip(names, terms[:, k].tolist()))


def _polylines(planner: Planning, store: NodeStore, leaves: np.ndarray, checks: LegChecks) -> list[np.ndarray]:
    """Every candidate's polyline, with ``record_candidates`` (else none)."""
    if not planner.config.record_candidates:
        return []
    return [_line(store, int(node), checks) for node in leaves]


def _line(store: NodeStore, node: int, checks: LegChecks) -> np.ndarray:
    """The polyline of the candidate ending in ``node``: from the robot through its via points to the subgoal."""
    points = [checks.subgoal]
    while node >= 0:
        points.append(store.position(node))
        node = store.parent(node)
    return np.array(points[::-1])


def _plan_of_nodes(
    store: NodeStore, leaves: np.ndarray, k: int, total: np.ndarray, checks: LegChecks, polylines: list[np.ndarray]
) -> Plan:
    """The plan of candidate ``k`` of the compiled tree's node store."""
    node = int(leaves[k])
    speed_after, slow_s, slow_speed = store.slowing(node)
    common: dict[str, Any] = dict(
        subgoal_index=checks.subgoal_index,
        candidate_count=len(leaves),
        candidate_costs=total,
        candidate_polylines=polylines,
        chosen=k,
    )
    if slow_s > 0:
        return Plan(
            "wait" if slow_speed == 0.0 else "slow",
            slow_speed,
            checks.subgoal.copy(),
            waypoints=np.array([checks.position, checks.subgoal]),
            extras={"slow_s": slow_s, "speed_after_mps": speed_after},
            **common,
        )
    line = _line(store, node, checks)
    return Plan(
        "avoid" if len(line) > 2 else "straight",
        speed_after,
        line[1].copy(),
        via_points=line[1:-1].copy(),
        waypoints=line,
        **common,
    )
