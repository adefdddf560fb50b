"""The choice of the paper's §3 (Eq. 1 and steps 1-4) in one compiled call, :func:`choose`, of two
halves: the roots, step 1 and the candidate tree (:func:`choose_tree`); then Eq. 1's critics, the order and the
motion-limit checks (:func:`choose_candidate`). Between them the candidates' angles, by libm's atan2 as the numpy
recipe took them (geometry.angles_of). :mod:`.choice` takes what it found up to the shield's check.
"""

from __future__ import annotations

import math

import numpy as np

from viapath.jit import compiled
from viapath.planning.viapath.critics import (
    distance_term,
    heading_term,
    hysteresis_term,
    side_term,
    speed_term,
    time_term,
)
from viapath.planning.viapath.legs import goal_legs_of
from viapath.planning.viapath.records import (
    CANDIDATES,
    COST_ROWS,
    COST_SUM,
    COST_TERMS,
    COST_TOTAL,
    N_FIRST_X,
    N_FIRST_Y,
    N_LEAF,
    N_LENGTH,
    N_OBSTACLE,
    N_PARENT,
    N_ROOT,
    N_SIDE,
    N_SLOW_S,
    N_SLOW_SPEED,
    N_SPEED,
    N_TO_GOAL,
    N_X,
    N_Y,
    NO_CANDIDATE,
    NODE_FLOATS,
    NODE_INTEGERS,
    STEP_ONE,
)
from viapath.planning.viapath.rollout import can_follow
from viapath.planning.viapath.tree import grow


@compiled(inline=True)
def _leaf_facts(robot, subgoal, nf, ni):
    """What :func:`choose_tree` hands back of the tree's leaves: ``found`` (status, 0, then the K leaves' nodes)
    and ``facts`` (6, K), as it says."""
    k_count = 0
    for m in range(ni.shape[0]):
        if ni[m, N_LEAF]:
            k_count += 1
    found = np.empty(2 + k_count, np.int64)
    facts = np.empty((6, k_count))
    k = 0
    for m in range(ni.shape[0]):
        if not ni[m, N_LEAF]:
            continue
        found[2 + k] = m
        # _plan_of's target: the subgoal for slow/wait and straight candidates, else the second point of
        # the polyline (the node below the root).
        target_x = subgoal[0]
        target_y = subgoal[1]
        if nf[m, N_SLOW_S] <= 0 and ni[m, N_PARENT] >= 0:
            node = m
            while ni[node, N_PARENT] >= 0:
                target_x = nf[node, N_X]
                target_y = nf[node, N_Y]
                node = ni[node, N_PARENT]
        facts[0, k] = nf[m, N_FIRST_Y]
        facts[1, k] = nf[m, N_FIRST_X]
        facts[2, k] = target_y - robot[1]
        facts[3, k] = target_x - robot[0]
        facts[4, k] = target_x
        facts[5, k] = target_y
        k += 1
    found[0] = CANDIDATES if k_count else NO_CANDIDATE
    found[1] = 0
    return found, facts


@compiled(inline=True)
def choose_tree(robot, speeds, subgoal, obstacles, via, slow, continuation, envelope, corridor, waypoints, settings):
    """The first half of the viapath planner's ``_choose`` in one call: the root legs (:func:`goal_legs`), the
    paper's step 1 (the free straight leg at the nominal speed, if the robot can follow it: follow.can_follow),
    else the candidate tree (:func:`grow`). ``robot`` is (x, y, heading, speed, turn rate); ``obstacles``,
    ``via``, ``slow`` and ``corridor`` are :func:`grow`'s records (:func:`choose` makes them of its
    arguments); ``settings`` holds the scalars (a record: :data:`.records.CHOICE`).

    Returns (found, floats, integers: grow's node store, facts). ``found`` is (NO_CANDIDATE / STEP_ONE /
    CANDIDATES, step 1 turns on the spot first, then the K leaves: the candidates' nodes); ``facts`` (6, K)
    is each candidate's first direction (y, x) and its target's offset from the robot (y, x), for atan2,
    and the target (x, y): the point it steers for first. (Few arrays: each one returned costs about a
    microsecond.)"""
    result = np.zeros(2, np.int64)
    s_count = speeds.shape[0]
    nominal_index = settings.nominal_index
    horizon_s = settings.horizon_s
    goal = (
        subgoal,
        settings.stop_short_m,
        continuation,
        envelope,
        settings.subgoal_index,
        settings.corridor_check_spacing_m,
        settings.corridor_tolerance_m,
    )
    starts = np.empty((s_count, 2))
    for i in range(s_count):
        starts[i, 0] = robot[0]
        starts[i, 1] = robot[1]
    roots = goal_legs_of(starts, np.zeros(s_count), speeds, horizon_s, goal, obstacles, corridor, via[2].shape_of)
    if roots[2][nominal_index] and settings.try_step_one and not settings.only_one_way:
        straight_angle = math.atan2(subgoal[1] - robot[1], subgoal[0] - robot[0])
        follows = can_follow(
            robot,
            subgoal[0],
            subgoal[1],
            straight_angle,
            speeds[nominal_index],
            settings,
            settings.rollout_steps,
            obstacles,
            corridor,
        )
        if follows:
            result[0] = STEP_ONE
            result[1] = follows == 2
            return result, np.empty((0, NODE_FLOATS)), np.empty((0, NODE_INTEGERS), np.int64), np.empty((6, 0))
    tree = (
        waypoints,
        settings.robot_segment,
        settings.grows_slow != 0,
        settings.max_depth,
        settings.max_root_obstacles,
    )
    nf, ni = grow(robot[:2].copy(), speeds, nominal_index, roots, via, slow, horizon_s, goal, obstacles, corridor, tree)
    found, facts = _leaf_facts(robot, subgoal, nf, ni)
    return found, nf, ni, facts


@compiled(inline=True)
def _leaf_features(nf, ni, leaves):
    """What Eq. 1's terms read of the K candidates (``leaves``: their last nodes): ``features`` (6, K), each
    candidate's length to the subgoal, speed, slow/wait time and speed, time driven at its speed and travel time;
    ``ways`` (K, 3) its way round (obstacle, side, root). As :class:`.candidates.Candidates` has them."""
    k_count = leaves.shape[0]
    features = np.empty((6, k_count))
    ways = np.empty((k_count, 3), np.int64)
    for k in range(k_count):
        m = leaves[k]
        length = nf[m, N_LENGTH] + nf[m, N_TO_GOAL]
        speed = nf[m, N_SPEED]
        slow_s = nf[m, N_SLOW_S]
        slow_v = nf[m, N_SLOW_SPEED]
        driven_s = (length - slow_v * slow_s) / speed
        features[0, k] = length
        features[1, k] = speed
        features[2, k] = slow_s
        features[3, k] = slow_v
        features[4, k] = driven_s
        features[5, k] = slow_s + driven_s
        ways[k, 0] = ni[m, N_OBSTACLE]
        ways[k, 1] = ni[m, N_SIDE]
        ways[k, 2] = ni[m, N_ROOT]
    return features, ways


@compiled(inline=True)
def _paper_terms(features, ways, first_angles, heading_rad, settings, terms):
    """Eq. 1's terms, in its order (:func:`.critics.critics_for`'s), into ``terms`` (6, K), of
    :func:`_leaf_features`' ``features`` and ``ways`` and the first legs' angles: each term's function of
    :mod:`.critics`, with its weight and settings."""
    length, speed, slow_s = features[0], features[1], features[2]
    slow_v, driven_s, travel_s = features[3], features[4], features[5]
    distance_term(settings.k1_per_m, length, terms[0])
    time_term(settings.k2_per_s, travel_s, terms[1])
    nominal = settings.nominal_speed_mps
    speed_term(
        settings.k3_per_mps, settings.standing_per_s, nominal, speed, slow_s, slow_v, driven_s, travel_s, terms[2]
    )
    heading_term(settings.k4_per_angle, settings.heading_in_degrees != 0, heading_rad, first_angles, terms[3])
    side_term(settings.side_weight, settings.preferred_side, ways, terms[4])
    previous = settings.has_previous != 0
    hysteresis = settings.hysteresis_weight
    way = (settings.previous_obstacle, settings.previous_side, settings.previous_root)
    hysteresis_term(hysteresis, previous, way[0], way[1], way[2], settings.previous_speed_mmps, ways, speed, terms[5])


@compiled(inline=True)
def _sums(costs, extra, ways, settings):
    """E of each candidate into ``costs`` (its rows COST_SUM and COST_TOTAL), after its terms (the paper's six, then
    ``extra``'s rows, in that order), and with ``only_way`` (``integers``) every other way priced out (inf) in
    COST_TOTAL. Returns whether any E there is finite."""
    only = settings.only_one_way != 0
    only_way = (settings.only_obstacle, settings.only_side, settings.only_root)
    any_finite = False
    for k in range(costs.shape[1]):
        value = costs[0, k] + costs[1, k]
        for c in range(2, COST_TERMS):
            value = value + costs[c, k]
        for e in range(extra.shape[0]):
            value = value + extra[e, k]
        costs[COST_SUM, k] = value
        if only and not (ways[k, 0] == only_way[0] and ways[k, 1] == only_way[1] and ways[k, 2] == only_way[2]):
            value = math.inf
        costs[COST_TOTAL, k] = value
        if math.isfinite(value):
            any_finite = True
    return any_finite


@compiled
def _before(a, b):
    """np.argsort's order of two costs: NaN after everything (ties are kept in index order by the caller)."""
    if b != b:
        return a == a
    return a < b


@compiled(inline=True)
def _cheapest_first(total, order):
    """The first ``len(order)`` candidates of np.argsort(total, kind="stable")'s order, into ``order``."""
    taken = np.zeros(total.shape[0], np.bool_)
    for r in range(order.shape[0]):
        best = -1
        for k in range(total.shape[0]):
            if not taken[k] and (best < 0 or _before(total[k], total[best])):
                best = k
        taken[best] = True
        order[r] = best


@compiled(inline=True)
def _first_that_follows(robot, nf, leaves, facts, angles, total, ranking, obstacles, corridor, settings):
    """follow.can_follow of each rank of ``ranking`` in order (up to ``max_rollouts``, none past an inf E) into its
    follow entries, until one passes: its rank into ``ranking[0]``."""
    ranks = ranking[1]
    order = ranking[2 : 2 + ranks]
    follow = ranking[2 + ranks :]
    follow[:] = -1
    for r in range(min(ranks, settings.max_rollouts)):
        k = order[r]
        if not math.isfinite(total[k]):
            break
        m = leaves[k]
        speed = nf[m, N_SLOW_SPEED] if nf[m, N_SLOW_S] > 0 else nf[m, N_SPEED]
        follow[r] = can_follow(
            robot, facts[4, k], facts[5, k], angles[1, k], speed, settings, settings.rollout_steps, obstacles, corridor
        )
        if follow[r]:
            ranking[0] = r
            break


@compiled(inline=True)
def choose_candidate(robot, nf, ni, found, facts, angles, extra, obstacles, corridor, settings):
    """The second half of ``_choose`` up to its shield check: Eq. 1's terms (:mod:`.critics`, summed in
    :func:`.critics.critics_for`'s order), with ``only_way`` the other ways priced out, the
    cheapest-first order (np.argsort's, stable) of the first ``max_rollouts`` candidates (and at least two,
    for the runner-up), and follow.can_follow of each in that order until one passes. ``found`` and ``facts``
    are :func:`choose_tree`'s, ``angles`` (2, K) atan2 of its facts, ``extra`` (E, K) the terms of critics after
    the paper's, added after them in their order; ``obstacles`` and ``corridor`` :func:`grow`'s records.

    Returns (ranking, costs). ``ranking`` is (the rank that follows or -1, R: the ranks in order (0: with
    only_way, no candidate goes that way), the order (R), can_follow of each rank tried (R): 0/1/2, -1 not
    tried); ``costs`` (8, K) the critics' terms, their sum and the sum with only_way applied. Its parts and
    Eq. 1's term functions are inlined: as calls, with their arrays, they took 0.3 µs more a call (choose_ranked:
    5.3 µs against 5.0 a call, on the static benchmark's cycles)."""
    leaves = found[2:]
    k_count = leaves.shape[0]
    features, ways = _leaf_features(nf, ni, leaves)
    costs = np.empty((COST_ROWS, k_count))
    _paper_terms(features, ways, angles[0], robot[2], settings, costs[:COST_TERMS])
    any_finite = _sums(costs, extra, ways, settings)
    if settings.only_one_way != 0 and not any_finite:
        ranking = np.zeros(2, np.int64)
        ranking[0] = -1
        return ranking, costs
    ranks = min(k_count, max(settings.max_rollouts, 2))
    ranking = np.empty(2 + 2 * ranks, np.int64)
    ranking[0] = -1
    ranking[1] = ranks
    _cheapest_first(costs[COST_TOTAL], ranking[2 : 2 + ranks])
    _first_that_follows(robot, nf, leaves, facts, angles, costs[COST_TOTAL], ranking, obstacles, corridor, settings)
    return ranking, costs


@compiled(inline=True)
def choose_ranked(robot, found, nf, ni, facts, extra, obstacles, corridor, settings):
    """The second half of :func:`choose`, after :func:`choose_tree`: when it found candidates, their angles and
    :func:`choose_candidate` (``extra``: its terms of further critics, (E, K)). Returns (found, costs): ``found``
    followed by :func:`choose_candidate`'s ranking when it says CANDIDATES (one array fewer to hand back),
    ``costs`` (8, K) :func:`choose_candidate`'s, empty unless CANDIDATES."""
    if found[0] != CANDIDATES:
        return found, np.empty((8, 0))
    k_count = facts.shape[1]
    angles = np.empty((2, k_count))
    for k in range(k_count):
        angles[0, k] = math.atan2(facts[0, k], facts[1, k])
        angles[1, k] = math.atan2(facts[2, k], facts[3, k])
    ranking, costs = choose_candidate(robot, nf, ni, found, facts, angles, extra, obstacles, corridor, settings)
    found_and_ranking = np.empty(found.shape[0] + ranking.shape[0], np.int64)
    found_and_ranking[: found.shape[0]] = found
    found_and_ranking[found.shape[0] :] = ranking
    return found_and_ranking, costs


@compiled(inline=True)
def choose(
    robot,
    speeds,
    subgoal,
    obstacle_positions,
    obstacle_velocities,
    radii,
    growth,
    growth_until_s,
    via_radii,
    ids,
    shapes,
    slow_radii,
    slow_growth,
    slow_growth_until_s,
    slow_times,
    continuation,
    envelope,
    segment_starts,
    segment_directions,
    segment_lengths,
    half_widths,
    waypoints,
    settings,
):
    """``_choose`` up to its shield check in one call (each array handed back to Python costs about a
    microsecond): :func:`choose_tree`, then :func:`choose_ranked` with the paper's critics only. Takes
    :func:`choose_tree`'s arguments (``shapes``: :class:`.shapes.StaticShapes`); returns (found, floats,
    integers: the node store, costs) of :func:`choose_ranked`."""
    obstacles = (obstacle_positions, obstacle_velocities, radii, growth, growth_until_s)
    corridor = (segment_starts, segment_directions, segment_lengths, half_widths)
    found, nf, ni, facts = choose_tree(
        robot,
        speeds,
        subgoal,
        obstacles,
        (via_radii, ids, shapes),
        (slow_radii, slow_growth, slow_growth_until_s, slow_times, settings.creep_speed_mps),
        continuation,
        envelope,
        corridor,
        waypoints,
        settings,
    )
    extra = np.empty((0, facts.shape[1]))
    found, costs = choose_ranked(robot, found, nf, ni, facts, extra, obstacles, corridor, settings)
    return found, nf, ni, costs
