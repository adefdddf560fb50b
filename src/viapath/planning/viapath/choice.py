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


def extra_critics(critics: tuple[Critic, ...]) -> tuple[Critic, ...]:
    """The critics after the paper's (:data:`.critics.PAPER_CRITICS`, whose term functions the compiled choice calls
    itself, with their weights: :class:`ChoiceSetup`): the choice scores these with their own ``score`` between its
    two halves. The critics must begin with the paper's, in Eq. 1's order (:func:`.critics.critics_for`)."""
    if tuple(map(type, critics[: len(PAPER_CRITICS)])) != PAPER_CRITICS:
        raise ValueError(
            "planner.critics: expected the paper's critics first (critics_for(config)), then any others; found "
            + ", ".join(type(critic).__name__ for critic in critics)
        )
    return tuple(critics[len(PAPER_CRITICS) :])


class ChoiceSetup:
    """What the compiled choice takes of the planner's configuration (its options, motion limits, critics and nominal
    speed), made once per configuration (:func:`choice_setup`): the settings row, the episode's fields packed
    (:class:`.records.ChoiceRow`), the slow/wait times, the critics after the paper's (:func:`extra_critics`), the
    names of the cost terms and the options read after the choice."""

    def __init__(self, planner: Planning):
        config, limits, critics = planner.config, planner.limits, planner.critics
        self.made_for = (config, limits, critics, planner.nominal_speed_mps)
        self.extra = extra_critics(critics)
        self.row = records.ChoiceRow(_choice_episode(planner))
        self.slow_times = np.asarray(config.slow_times_s, dtype=np.float64).reshape(-1)
        self.cost_names = tuple(critic.name for critic in critics) + ("total",)
        self.max_rollouts: int = config.max_rollouts
        self.record_candidates: bool = config.record_candidates


def choice_setup(planner: Planning) -> ChoiceSetup:
    """The planner's :class:`ChoiceSetup`, made again when its options, limits, critics or nominal speed is replaced."""
    setup: ChoiceSetup | None = planner.__dict__.get("_choice_setup")
    if setup is not None:
        config, limits, critics, nominal_speed = setup.made_for
        if (
            config is planner.config
            and limits is planner.limits
            and critics is planner.critics
            and nominal_speed is planner.nominal_speed_mps
        ):
            return setup
    setup = planner.__dict__["_choice_setup"] = ChoiceSetup(planner)
    return setup


def _extra_terms(
    critics: tuple[Critic, ...], checks: LegChecks, nominal_speed_mps: float, previous: Choice | None
) -> Callable[[NodeStore, np.ndarray], np.ndarray]:
    """The scoring of the critics after the paper's (:func:`extra_critics`) for :func:`.packing.choose`."""
    context = Context(checks.heading_rad, nominal_speed_mps, previous)

    def terms(store: NodeStore, leaves: np.ndarray) -> np.ndarray:
        candidates = candidates_of(store, checks.subgoal)
        return np.array([critic.score(candidates, context) for critic in critics], dtype=np.float64).reshape(
            len(critics), len(leaves)
        )

    return terms


def _choice_episode(planner: Planning) -> bytes:
    """The compiled choice's settings that do not change within an episode (:func:`.records.choice_episode`)."""
    config = planner.config
    distance, time, speed, heading, side, hysteresis = cast(
        "tuple[Distance, Time, SpeedError, Heading, SidePreference, Hysteresis]", planner.critics[: len(PAPER_CRITICS)]
    )  # the paper's critics (PAPER_CRITICS, first: extra_critics): the ones the compiled choice sums itself
    return records.choice_episode(
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
        **records.rollout_fields(planner.limits, config),
    )


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
    setup = choice_setup(planner)
    settings = _cycle_settings(setup, checks, nominal_index, previous, only_way, True)
    slow_checks = planner._slow_checks(checks)
    extra = _extra_terms(setup.extra, checks, planner.nominal_speed_mps, previous) if setup.extra else None
    chosen = packing.choose(checks, slow_checks, speeds, setup.slow_times, settings, extra)
    if chosen.status == records.STEP_ONE:
        plan = straight_plan(checks, float(speeds[nominal_index]))
        if chosen.turn_in_place:
            plan.extras["turn_in_place"] = True
        if planner._inside_shield(plan):
            return straight_chosen(plan)
        # the shield refused it: the candidates decide
        settings = _cycle_settings(setup, checks, nominal_index, previous, only_way, False)
        chosen = packing.choose(checks, slow_checks, speeds, setup.slow_times, settings, extra)
    if chosen.status != records.CANDIDATES or chosen.first < 0:  # first: the ranks before it do not follow
        return None
    return _first_admitted(planner, setup, chosen, checks)


def tree_is_empty(planner: Planning, checks: LegChecks, speeds: np.ndarray, nominal_index: int) -> bool:
    """Whether the candidate tree of ``checks`` has no candidate at all (no free root either; step 1 is not
    taken): the compiled choice's tree alone (:func:`.packing.choose` with ``TREE_ONLY``)."""
    setup = choice_setup(planner)
    settings = _cycle_settings(setup, checks, nominal_index, None, None, False)
    found = packing.choose(checks, checks, speeds, setup.slow_times, settings, packing.TREE_ONLY)
    return found.status != records.CANDIDATES


_NO_WAY = Way(0, 0, 0)  # (the record's way fields when there is no way: zeros)


def _cycle_settings(
    setup: ChoiceSetup,
    checks: LegChecks,
    nominal_index: int,
    previous: Choice | None,
    only_way: Way | None,
    try_step_one: bool,
) -> np.ndarray:
    """The compiled choice's settings of this cycle (the row of :class:`.records.ChoiceRow`): the episode's with the
    cycle's (the horizon, the subgoal, last cycle's way and speed, the one way allowed, whether to try step 1)."""
    index = checks.subgoal_index
    # the robot's segment matters only when a corner can lie between it and the subgoal
    segment = int(checks.path.project(checks.position)[0]) if index >= 2 else 0
    way, only = (previous.way if previous is not None else _NO_WAY), (only_way if only_way is not None else _NO_WAY)
    # ChoiceRow.write's arguments by position (by keyword the call took 2 µs more, every cycle); their names:
    return setup.row.write(
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


def _first_admitted(planner: Planning, setup: ChoiceSetup, chosen: CompiledChoice, checks: LegChecks) -> Chosen | None:
    """The cheapest candidate from the compiled choice's first that follows on that the robot can follow and the
    shield admits (past that first one, each is rolled out here: only after the shield refused it)."""
    leaves, order, follow, total, store = chosen.leaves, chosen.order, chosen.follow, chosen.total, chosen.store
    for rank in range(chosen.first, min(len(order), setup.max_rollouts)):
        best = order[rank]
        if not math.isfinite(total[best]):
            break
        verdict = follow[rank]
        if verdict == 0:
            continue
        polylines = [_line(store, int(node), checks) for node in leaves] if setup.record_candidates else []
        plan = _plan_of_nodes(store, leaves, best, total, checks, polylines)
        if verdict < 0:  # past the first that follows: only after the shield refused that one
            verdict = can_follow(plan, checks, planner.limits, planner.config)
        elif verdict == 2:
            plan.extras["turn_in_place"] = True
        if verdict and planner._inside_shield(plan):
            plan.extras["cost_terms"] = cost_terms(_cost_breakdown(setup.cost_names, chosen.terms), order, rank, total)
            node = int(leaves[best])
            way, speed = store.way(node), store.speed(node)
            return Chosen(
                Choice(Way(*way), int(round(speed * 1000))),
                plan,
                CompiledCandidates(store, leaves, checks.subgoal),
            )
    return None


def _cost_breakdown(names: tuple[str, ...], terms: np.ndarray) -> Callable[[int], dict[str, float]]:
    """Each critic's term of candidate k and their sum, by ``names``, as Python floats, of the compiled choice's
    costs (rows: the critics' terms, then E)."""
    return lambda k: dict(zip(names, terms[:, k].tolist()))


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
