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
from viapath.planning.viapath import packing, records
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


def _choice_constants(planner: Planning) -> tuple[bytes, np.ndarray]:
    """The compiled choice's settings that do not change within an episode (:func:`.records.choice_episode`) and
    the slow/wait times; rebuilt when the options, limits or critics object is replaced."""
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
    episode = records.choice_episode(
        k1_per_m=distance.weight,
        k2_per_s=time.weight,
        k3_per_mps=speed.weight,
        k4_per_angle=heading.weight,
        side_weight=side.weight,
        hysteresis_weight=hysteresis.weight,
        nominal_speed_mps=planner.nominal_speed_mps,
        corridor_check_spacing_m=config.corridor_check_spacing_m,
        standing_per_s=speed.standing_per_s,
        creep_speed_mps=config.creep_speed_mps,
        max_depth=config.max_depth,
        max_root_obstacles=config.max_root_obstacles,
        max_rollouts=config.max_rollouts,
        heading_in_degrees=heading.degrees,
        preferred_side=side.preferred,
        grows_slow=bool(config.slow_times_s),
        **records.rollout_fields(limits, config),
    )
    slow_times = np.asarray(config.slow_times_s, dtype=np.float64).reshape(-1)
    constants = (episode, slow_times)
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
    settings, slow_times = _cycle_settings(planner, checks, nominal_index, previous, only_way, True)
    slow_checks = planner._slow_checks(checks)
    extra = _extra_terms(planner, checks, previous)
    chosen = packing.choose(checks, slow_checks, speeds, slow_times, settings, extra)
    if chosen.status == records.STEP_ONE:
        plan = straight_plan(checks, float(speeds[nominal_index]))
        if chosen.turn_in_place:
            plan.extras["turn_in_place"] = True
        if planner._inside_shield(plan):
            return straight_chosen(plan)
        # the shield refused it: the candidates decide
        settings, slow_times = _cycle_settings(planner, checks, nominal_index, previous, only_way, False)
        chosen = packing.choose(checks, slow_checks, speeds, slow_times, settings, extra)
    if chosen.status != records.CANDIDATES or chosen.first < 0:  # first: the ranks before it do not follow
        return None
    return _first_admitted(planner, chosen, checks)


def tree_is_empty(planner: Planning, checks: LegChecks, speeds: np.ndarray, nominal_index: int) -> bool:
    """Whether the candidate tree of ``checks`` has no candidate at all (no free root either; step 1 is not
    taken): the compiled choice's tree alone (:func:`.packing.choose` with ``TREE_ONLY``)."""
    settings, slow_times = _cycle_settings(planner, checks, nominal_index, None, None, False)
    found = packing.choose(checks, checks, speeds, slow_times, settings, packing.TREE_ONLY)
    return found.status != records.CANDIDATES


_NO_WAY = Way(0, 0, 0)  # (the record's way fields when there is no way: zeros)


def _cycle_settings(
    planner: Planning,
    checks: LegChecks,
    nominal_index: int,
    previous: Choice | None,
    only_way: Way | None,
    try_step_one: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """The compiled choice's settings of this cycle (a row of :data:`.records.CHOICE`): the episode's
    (:func:`_choice_constants`) with the cycle's (the horizon, the subgoal, last cycle's way and speed, the one way
    allowed, whether to try step 1); and the slow/wait times."""
    episode, slow_times = _choice_constants(planner)
    index = checks.subgoal_index
    # the robot's segment matters only when a corner can lie between it and the subgoal
    segment = int(checks.path.project(checks.position)[0]) if index >= 2 else 0
    way, only = (previous.way if previous is not None else _NO_WAY), (only_way if only_way is not None else _NO_WAY)
    # choice_settings' arguments by position (by keyword the call took 2 µs more, every cycle); their names:
    settings = records.choice_settings(
        episode,
        checks.stop_short_m,
        checks.horizon_s,
        checks.corridor_tolerance_m,
        nominal_index,
        segment,  # robot_segment
        index,  # subgoal_index
        try_step_one,
        previous is not None,  # has_previous
        way.obstacle,  # previous_obstacle
        way.side,  # previous_side
        way.root,  # previous_root
        previous.speed_mmps if previous is not None else 0,  # previous_speed_mmps
        only_way is not None,  # only_one_way
        only.obstacle,  # only_obstacle
        only.side,  # only_side
        only.root,  # only_root
    )
    return settings, slow_times


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
    """The plan of candidate ``k`` of the compiled tree's node store (one Plan call: a dict of the common fields
    unpacked into two took 0.3 us more a cycle)."""
    node = int(leaves[k])
    speed_after, slow_s, slow_speed = store.slowing(node)
    if slow_s > 0:
        status, speed, target = "wait" if slow_speed == 0.0 else "slow", slow_speed, checks.subgoal.copy()
        via_points, line = np.zeros((0, 2)), np.array([checks.position, checks.subgoal])
        extras: dict[str, Any] = {"slow_s": slow_s, "speed_after_mps": speed_after}
    else:
        line = _line(store, node, checks)
        status, speed, target = "avoid" if len(line) > 2 else "straight", speed_after, line[1].copy()
        via_points, extras = line[1:-1].copy(), {}
    return Plan(
        status,
        speed,
        target,
        via_points=via_points,
        waypoints=line,
        subgoal_index=checks.subgoal_index,
        candidate_count=len(leaves),
        candidate_costs=total,
        candidate_polylines=polylines,
        chosen=k,
        extras=extras,
    )
