"""The candidate tree of the paper's §3, grown in one compiled call (:func:`grow`): at
every speed of the set, the straight leg to the subgoal (step 1), the slow and waiting legs, the corners of the path,
and the via points of each person a leg hits, chained from via point to via point to the search's depth
(Tsubouchi's iterated forecast and planning); round static shapes as :mod:`.shapes` says (one branch per shape at
the root, the shape's extremes, slides). What a candidate is: :mod:`.candidates`. Its node store's columns:
:mod:`.records`.
"""

from __future__ import annotations

import math

import numpy as np

from viapath.jit import compiled
from viapath.planning.viapath import records
from viapath.planning.viapath.legs import (
    goal_legs_inside_all,
    goal_legs_of,
    legs_free,
    legs_inside_of,
)
from viapath.planning.viapath.shapes import hugs, one_per_shape, round_static_shapes, slide
from viapath.planning.viapath.via import via_pair

# Columns of the node store (:mod:`.records`): floats, then integers.
_X, _Y, _T, _V, _LENGTH = records.N_X, records.N_Y, records.N_TIME, records.N_SPEED, records.N_LENGTH
_FX, _FY, _SLOW_S, _SLOW_V, _GOAL = (
    records.N_FIRST_X,
    records.N_FIRST_Y,
    records.N_SLOW_S,
    records.N_SLOW_SPEED,
    records.N_TO_GOAL,
)
_PARENT, _WAY0, _WAY1, _WAY2, _LEAF = (
    records.N_PARENT,
    records.N_OBSTACLE,
    records.N_SIDE,
    records.N_ROOT,
    records.N_LEAF,
)
_STRAIGHT, _SLOW, _CORNER = -1, -2, -3  # candidates.STRAIGHT, SLOW, CORNER
_SIDES = (1, -1, 1, -1)  # geometry.VIA_SIDES
_ROOTS = (0, 0, 1, 1)  # geometry.VIA_ROOTS
# The same as int64 values, not literals: every call of _add then has one signature (literal arguments
# would each compile a variant of it, seconds of the first run).
_NONE, _ZERO = np.int64(-1), np.int64(0)
_I_STRAIGHT, _I_SLOW, _I_CORNER = np.int64(_STRAIGHT), np.int64(_SLOW), np.int64(_CORNER)


@compiled(inline=True)
def _reserve(nf, ni, m, count):
    """Room for ``count`` more nodes after the first ``m`` (the store doubles when full)."""
    if m + count <= nf.shape[0]:
        return nf, ni
    capacity = max(2 * nf.shape[0], m + count)
    bigger_f = np.empty((capacity, nf.shape[1]))
    bigger_i = np.empty((capacity, ni.shape[1]), np.int64)
    bigger_f[:m] = nf[:m]
    bigger_i[:m] = ni[:m]
    return bigger_f, bigger_i


@compiled(inline=True)  # inlined: a call passed 16 arguments for each node
def _add(nf, ni, m, x, y, t, v, parent, length, fx, fy, way0, way1, way2, slow_s, slow_v):
    nf, ni = _reserve(nf, ni, m, 1)
    nf[m, _X] = x
    nf[m, _Y] = y
    nf[m, _T] = t
    nf[m, _V] = v
    nf[m, _LENGTH] = length
    nf[m, _FX] = fx
    nf[m, _FY] = fy
    nf[m, _SLOW_S] = slow_s
    nf[m, _SLOW_V] = slow_v
    nf[m, _GOAL] = 0.0
    ni[m, _PARENT] = parent
    ni[m, _WAY0] = way0
    ni[m, _WAY1] = way1
    ni[m, _WAY2] = way2
    ni[m, _LEAF] = 0
    return nf, ni, m + 1


@compiled(inline=True)
def _root_nodes(position, speeds, root_directions, root_lengths, root_free):
    """The tree's first nodes (a store with room to grow): the roots, one per speed, at the robot, now; a root
    whose goal leg is free is a leaf."""
    s_count = speeds.shape[0]
    nf = np.empty((4 * s_count + 32, records.NODE_FLOATS))
    ni = np.empty((4 * s_count + 32, records.NODE_INTEGERS), np.int64)
    m = _ZERO
    for i in range(s_count):
        nf, ni, m = _add(
            nf,
            ni,
            m,
            position[0],
            position[1],
            0.0,
            speeds[i],
            _NONE,
            0.0,
            root_directions[i, 0],
            root_directions[i, 1],
            _I_STRAIGHT,
            _ZERO,
            _ZERO,
            0.0,
            0.0,
        )
        if root_free[i]:
            ni[m - 1, _LEAF] = 1
            nf[m - 1, _GOAL] = root_lengths[i]
    return nf, ni, m


@compiled
def _slow_legs(position, subgoal, speeds, nominal, slow_times, creep):
    """The slow/wait legs along the straight leg: 0 (waiting), the creep speed (when it is
    above 0, below the nominal speed and not in the set) and each speed below the nominal one, for
    each slow time, never past the subgoal. Returns the unit direction (dx, dy) to the subgoal, the legs'
    durations and speeds (the first ``count`` of each) and ``count``."""
    s_count = speeds.shape[0]
    creeps = creep > 0.0 and creep < nominal - 1e-9
    for i in range(s_count):
        if abs(speeds[i] - creep) < 1e-9:
            creeps = False
    slow_count = 2 if creeps else 1
    for i in range(s_count):
        if speeds[i] < nominal - 1e-9:
            slow_count += 1
    slow_speeds = np.empty(slow_count)
    slow_speeds[0] = 0.0
    c = 1
    if creeps:
        slow_speeds[1] = creep
        c = 2
    for i in range(s_count):
        if speeds[i] < nominal - 1e-9:
            slow_speeds[c] = speeds[i]
            c += 1
    ox = subgoal[0] - position[0]
    oy = subgoal[1] - position[1]
    distance = math.hypot(ox, oy)
    divisor = distance if distance > 1e-12 else 1e-12
    dx = ox / divisor
    dy = oy / divisor
    t_count = slow_times.shape[0]
    durations = np.empty(slow_count * t_count)
    slows = np.empty(slow_count * t_count)
    c = 0
    for i in range(slow_count):
        for j in range(t_count):
            if slow_speeds[i] * slow_times[j] < distance - 1e-6:  # never past the subgoal while slow
                durations[c] = slow_times[j]
                slows[c] = slow_speeds[i]
                c += 1
    return dx, dy, durations, slows, c


@compiled(inline=True)
def _slow_nodes(nf, ni, m, position, speeds, nominal_index, slow, horizon_s, obstacles, goal, corridor, shape_of):
    """Slow down, creep or wait along the straight leg, then on at the nominal speed or the slowest faster speed
    whose goal leg is free: the slow legs (:func:`_slow_legs`) free of the people at their slow radii, each with
    its first free goal leg, added as leaves. ``slow``: :func:`grow`'s record."""
    slow_radii, slow_growth, slow_growth_until_s, slow_times, creep = slow
    obstacle_positions, obstacle_velocities, _, _, _ = obstacles
    slow_obstacles = (obstacle_positions, obstacle_velocities, slow_radii, slow_growth, slow_growth_until_s)
    nominal = speeds[nominal_index]
    dx, dy, durations, slows, c = _slow_legs(position, goal[0], speeds, nominal, slow_times, creep)
    free = _slow_legs_free(position, dx, dy, durations, slows, c, horizon_s, slow_obstacles, shape_of)
    goes_on = _goes_on(position, speeds, nominal, dx, dy, durations, slows, free)
    ends, times, after, _, _ = goes_on
    if not times.shape[0]:
        return nf, ni, m
    _, lengths, goal_free, _ = goal_legs_of(ends, times, after, math.inf, goal, obstacles, corridor, shape_of)
    return _slow_leaves(nf, ni, m, dx, dy, goes_on, lengths, goal_free)


@compiled(inline=True)
def _slow_legs_free(position, dx, dy, durations, slows, c, horizon_s, slow_obstacles, shape_of):
    """Which of the first ``c`` slow legs (from the robot, now, along (dx, dy)) are free of the people at their slow
    radii (``slow_obstacles``)."""
    starts = np.empty((c, 2))
    velocities = np.empty((c, 2))
    for k in range(c):
        starts[k, 0] = position[0]
        starts[k, 1] = position[1]
        velocities[k, 0] = dx * slows[k]
        velocities[k, 1] = dy * slows[k]
    return legs_free(starts, np.zeros(c), velocities, durations[:c], horizon_s, slow_obstacles, shape_of)


@compiled(inline=True)
def _goes_on(position, speeds, nominal, dx, dy, durations, slows, free):
    """Where the robot goes on after each free slow leg: at its end and its duration, once at each speed from the
    nominal one up. Returns the goal legs' starts, start times and speeds, the slow speed before each, and how
    many speeds go on from each slow leg."""
    s_count = speeds.shape[0]
    after_count = 0
    for i in range(s_count):
        if speeds[i] >= nominal - 1e-9:
            after_count += 1
    kept = 0
    for k in range(free.shape[0]):
        if free[k]:
            kept += 1
    legs = kept * after_count
    ends = np.empty((legs, 2))
    times = np.empty(legs)
    after = np.empty(legs)
    slow_v = np.empty(legs)
    q = 0
    for k in range(free.shape[0]):
        if not free[k]:
            continue
        for i in range(s_count):
            if speeds[i] >= nominal - 1e-9:
                ends[q, 0] = position[0] + dx * (slows[k] * durations[k])
                ends[q, 1] = position[1] + dy * (slows[k] * durations[k])
                times[q] = durations[k]
                after[q] = speeds[i]
                slow_v[q] = slows[k]
                q += 1
    return ends, times, after, slow_v, after_count


@compiled(inline=True)
def _slow_leaves(nf, ni, m, dx, dy, goes_on, lengths, goal_free):
    """Each slow leg with its first free goal leg (:func:`_goes_on`'s, the slowest speed from the nominal one up),
    added as a leaf."""
    ends, times, after, slow_v, after_count = goes_on
    taken = False
    for q in range(times.shape[0]):
        if q % after_count == 0:
            taken = False  # a new slow leg: its first free continuation only
        if goal_free[q] and not taken:
            taken = True
            nf, ni, m = _add(
                nf,
                ni,
                m,
                ends[q, 0],
                ends[q, 1],
                times[q],
                after[q],
                _NONE,
                slow_v[q] * times[q],
                dx,
                dy,
                _I_SLOW,
                _ZERO,
                _ZERO,
                times[q],
                slow_v[q],
            )
            ni[m - 1, _LEAF] = 1
            nf[m - 1, _GOAL] = lengths[q]
    return nf, ni, m


@compiled
def _corner_legs(position, speeds, waypoints, robot_segment, subgoal_index):
    """The legs from the robot to each corner of the path before the subgoal, at each speed: their targets, starts,
    velocities, unit directions, lengths, durations, corners (waypoint index) and speeds."""
    s_count = speeds.shape[0]
    corners = subgoal_index - robot_segment - 1
    legs = corners * s_count
    targets = np.empty((legs, 2))
    starts = np.empty((legs, 2))
    velocities = np.empty((legs, 2))
    directions = np.empty((legs, 2))
    lengths = np.empty(legs)
    durations = np.empty(legs)
    corner_of = np.empty(legs, np.int64)
    speed_of = np.empty(legs)
    q = 0
    for i in range(s_count):
        for corner in range(robot_segment + 1, subgoal_index):
            targets[q, 0] = waypoints[corner, 0]
            targets[q, 1] = waypoints[corner, 1]
            ox = targets[q, 0] - position[0]
            oy = targets[q, 1] - position[1]
            length = math.hypot(ox, oy)
            divisor = length if length > 1e-12 else 1e-12
            directions[q, 0] = ox / divisor
            directions[q, 1] = oy / divisor
            starts[q, 0] = position[0]
            starts[q, 1] = position[1]
            velocities[q, 0] = directions[q, 0] * speeds[i]
            velocities[q, 1] = directions[q, 1] * speeds[i]
            lengths[q] = length
            durations[q] = length / speeds[i]
            corner_of[q] = corner
            speed_of[q] = speeds[i]
            q += 1
    return targets, starts, velocities, directions, lengths, durations, corner_of, speed_of


@compiled(inline=True)  # inlined: called per corner leg kept
def _root_of(speeds, speed):
    """The root node of ``speed`` (np.searchsorted(speeds, speed): the roots are the speeds, in order)."""
    root = _ZERO
    while root < speeds.shape[0] and speeds[root] < speed:
        root += 1
    return root


@compiled
def _corner_nodes(nf, ni, m, position, speeds, path, horizon_s, goal, obstacles, corridor, shape_of):
    """The path's corners between the robot and the subgoal as via points: one leg per speed and corner
    (:func:`_corner_legs`), added below the root of its speed when free of the people and inside the corridor.
    ``path``: the waypoints and the robot's segment."""
    waypoints, robot_segment = path
    _, _, _, _, subgoal_index, spacing_m, tolerance_m = goal
    legs = _corner_legs(position, speeds, waypoints, robot_segment, subgoal_index)
    targets, starts, velocities, directions, lengths, durations, corner_of, speed_of = legs
    count = lengths.shape[0]
    good = legs_free(starts, np.zeros(count), velocities, durations, horizon_s, obstacles, shape_of)
    inside = legs_inside_of(corridor, starts, targets, spacing_m, tolerance_m)
    for q in range(count):
        if good[q] and inside[q]:
            nf, ni, m = _add(
                nf,
                ni,
                m,
                targets[q, 0],
                targets[q, 1],
                durations[q],
                speed_of[q],
                _root_of(speeds, speed_of[q]),
                lengths[q],
                directions[q, 0],
                directions[q, 1],
                _I_CORNER,
                _ZERO,
                corner_of[q],
                0.0,
                0.0,
            )
    return nf, ni, m


@compiled
def _branch_pairs(free_now, contact_now, frontier_start, frontier_end, n_count, depth, max_root_obstacles):
    """The (node, obstacle) pairs to branch on: at the root every obstacle the leg hits, earliest first (at most
    max_root_obstacles, when there are more pairs than that), deeper the first hit. Returns the
    pairs' nodes and obstacles and how many there are."""
    pair_nodes = np.empty((frontier_end - frontier_start) * n_count, np.int64)
    pair_obstacles = np.empty((frontier_end - frontier_start) * n_count, np.int64)
    pairs = 0
    total = 0
    for r in range(frontier_end - frontier_start):
        if free_now[r]:
            continue
        for j in range(n_count):
            if math.isfinite(contact_now[r, j]):
                total += 1
    if depth == 0 and max_root_obstacles > 0 and total > max_root_obstacles:
        order = np.empty(n_count, np.int64)
        for r in range(frontier_end - frontier_start):
            if free_now[r]:
                continue
            count = 0
            for j in range(n_count):  # a stable insertion sort by contact time
                value = contact_now[r, j]
                if not math.isfinite(value):
                    continue
                place = count
                while place > 0 and contact_now[r, order[place - 1]] > value:
                    order[place] = order[place - 1]
                    place -= 1
                order[place] = j
                count += 1
            for q in range(min(count, max_root_obstacles)):
                pair_nodes[pairs] = frontier_start + r
                pair_obstacles[pairs] = order[q]
                pairs += 1
    else:
        for r in range(frontier_end - frontier_start):
            if free_now[r]:
                continue
            best = -1
            for j in range(n_count):
                value = contact_now[r, j]
                if not math.isfinite(value):
                    continue
                if depth == 0:
                    pair_nodes[pairs] = frontier_start + r
                    pair_obstacles[pairs] = j
                    pairs += 1
                elif best < 0 or value < contact_now[r, best]:
                    best = j
            if depth > 0 and best >= 0:
                pair_nodes[pairs] = frontier_start + r
                pair_obstacles[pairs] = best
                pairs += 1
    return pair_nodes, pair_obstacles, pairs


@compiled(inline=True)
def _pairs(nf, frontier, depth, max_root_obstacles, obstacle_positions, via):
    """The (node, obstacle) pairs to branch on from the frontier (first ``frontier_start`` .. ``frontier_end`` of
    the store, their goal legs' ``free`` and ``contact``): :func:`_branch_pairs`, at the root on each static
    shape's earliest disc only (:func:`.shapes.one_per_shape`), and each static disc replaced by its shape's
    extremes as seen from the node (:func:`.shapes.round_static_shapes`)."""
    frontier_start, frontier_end, free_now, contact_now = frontier
    via_radii, _, shapes = via
    n_count = obstacle_positions.shape[0]
    if shapes.shape_of.shape[0] == 0:
        return _branch_pairs(free_now, contact_now, frontier_start, frontier_end, n_count, depth, max_root_obstacles)
    if depth == 0:
        contact_now = one_per_shape(free_now, contact_now, shapes)
    branch = _branch_pairs(free_now, contact_now, frontier_start, frontier_end, n_count, depth, max_root_obstacles)
    if not branch[2]:
        return branch
    return round_static_shapes(nf, branch, obstacle_positions, via_radii, shapes)


@compiled
def _via_legs(nf, branch, via_radii, envelope, horizon_s, obstacles, shapes):
    """The via points of each pair (for :func:`_via_children`): both sides, both roots (none round static geometry
    keeps the braking envelope: :func:`_braking_margin`), reached within three horizons (:func:`_legs_to_via_points`),
    then the slides of the pairs whose node hugs a static disc (:func:`_slides`). The pairs' options as via_options
    gives them, its arithmetic (via_pair) on the nodes and obstacles themselves: no copies of them per pair.
    Returns, per leg (the first ``count``): its pair, its option, its duration, its start and start time, its
    velocity and its via point; and ``count``. ``branch``: :func:`_branch_pairs`' pairs."""
    pair_nodes, pair_obstacles, pairs = branch
    obstacle_positions, obstacle_velocities, _, growth, growth_until_s = obstacles
    any_static = shapes.shape_of.shape[0] > 0
    capacity = (6 if any_static else 4) * pairs
    pair = np.empty(capacity, np.int64)
    option = np.empty(capacity, np.int64)
    t_k = np.empty(capacity)
    starts_k = np.empty((capacity, 2))
    times_k = np.empty(capacity)
    leg_velocity = np.empty((capacity, 2))
    via = np.empty((capacity, 2))
    legs = (pair, option, t_k, starts_k, times_k, leg_velocity, via)
    t_via = np.empty(4)
    w_via = np.empty((2, 2))
    max_time_s = 3 * horizon_s
    count = 0
    for p in range(pairs):
        node = pair_nodes[p]
        j = pair_obstacles[p]
        margin = _braking_margin(nf[node, _V], envelope, any_static and shapes.shape_of[j] >= 0)
        # The helper holds the loop over the options only: with the via_pair call inside it too, the choice at
        # 100 people took 6 % longer (measured).
        if via_pair(
            nf[node, _X],
            nf[node, _Y],
            nf[node, _T],
            nf[node, _V],
            obstacle_positions[j, 0],
            obstacle_positions[j, 1],
            obstacle_velocities[j, 0],
            obstacle_velocities[j, 1],
            via_radii[j],
            growth[j],
            growth_until_s[j],
            margin,
            t_via,
            w_via,
        ):
            ovx = obstacle_velocities[j, 0]
            ovy = obstacle_velocities[j, 1]
            count = _legs_to_via_points(nf, node, p, ovx, ovy, t_via, w_via, max_time_s, legs, count)
    if any_static:
        count = _slides(nf, branch, obstacle_positions, via_radii, shapes, legs, count)
    return pair, option, t_k, starts_k, times_k, leg_velocity, via, count


@compiled(inline=True)  # inlined: called per pair
def _braking_margin(speed, envelope, static):
    """The braking envelope's margin at ``speed`` (``envelope``: deceleration, reaction time, braking rate; none
    when the deceleration is 0 or round static geometry)."""
    if envelope[0] > 0 and not static:
        half_accel = 0.5 * envelope[0]
        stop_s = envelope[1] + speed / envelope[2]
        return half_accel * (stop_s * stop_s)
    return 0.0


@compiled(inline=True)  # inlined: called per leg, with the legs' arrays
def _put_leg(legs, q, p, o, duration, sx, sy, start_s, vx, vy, ex, ey):
    """Leg ``q`` of ``legs`` (:func:`_via_legs`' arrays): pair ``p``'s option ``o``, ``duration`` long, from (sx, sy)
    at ``start_s`` at velocity (vx, vy) to its via point (ex, ey)."""
    pair, option, t_k, starts_k, times_k, leg_velocity, via = legs
    pair[q] = p
    option[q] = o
    t_k[q] = duration
    starts_k[q, 0] = sx
    starts_k[q, 1] = sy
    times_k[q] = start_s
    leg_velocity[q, 0] = vx
    leg_velocity[q, 1] = vy
    via[q, 0] = ex
    via[q, 1] = ey


@compiled(inline=True)  # inlined: called per pair, with the legs' arrays
def _legs_to_via_points(nf, node, p, ovx, ovy, t_via, w_via, max_time_s, legs, count):
    """The legs from pair ``p``'s node to its via points (via_pair's durations ``t_via`` and offsets ``w_via``, the
    obstacle's velocity (ovx, ovy)) reached within ``max_time_s``, written after the first ``count`` of ``legs``
    (:func:`_via_legs`' arrays). Returns the new count."""
    sx = nf[node, _X]
    sy = nf[node, _Y]
    for o in range(4):
        t = t_via[o]
        if t <= max_time_s:
            vx = (w_via[o % 2, 0] + ovx * t) / t
            vy = (w_via[o % 2, 1] + ovy * t) / t
            _put_leg(legs, count, p, o, t, sx, sy, nf[node, _T], vx, vy, sx + vx * t, sy + vy * t)
            count += 1
    return count


@compiled
def _slides(nf, branch, obstacle_positions, via_radii, shapes, legs, count):
    """The slides (:func:`.shapes.slide`, options 0 and 1: left and right) of each pair whose node hugs its
    static disc, after the first ``count`` of ``legs`` (:func:`_via_legs`' arrays); returns the new count."""
    pair_nodes, pair_obstacles, pairs = branch
    for p in range(pairs):
        node = pair_nodes[p]
        j = pair_obstacles[p]
        sx = nf[node, _X]
        sy = nf[node, _Y]
        cx = obstacle_positions[j, 0]
        cy = obstacle_positions[j, 1]
        if shapes.shape_of[j] < 0 or not hugs(sx, sy, cx, cy, via_radii[j], shapes.hug_factor):
            continue
        for o in range(2):
            duration, vx, vy, ex, ey = slide(sx, sy, cx, cy, via_radii[j], nf[node, _V], _SIDES[o])
            _put_leg(legs, count, p, o, duration, sx, sy, nf[node, _T], vx, vy, ex, ey)
            count += 1
    return count


@compiled(inline=True)
def _keep_inside(good, starts_k, via, count, corridor, spacing_m, tolerance_m):
    """Keep the free via legs (``good``, of the first ``count`` legs) that stay inside the corridor: ``good`` turned
    False for the others (the corridor checked on the free legs only), and returned."""
    kept = 0
    for q in range(count):
        if good[q]:
            kept += 1
    if not kept:
        return good
    good_starts = np.empty((kept, 2))
    good_vias = np.empty((kept, 2))
    g = 0
    for q in range(count):
        if good[q]:
            good_starts[g, 0] = starts_k[q, 0]
            good_starts[g, 1] = starts_k[q, 1]
            good_vias[g, 0] = via[q, 0]
            good_vias[g, 1] = via[q, 1]
            g += 1
    inside = legs_inside_of(corridor, good_starts, good_vias, spacing_m, tolerance_m)
    g = 0
    for q in range(count):
        if good[q]:
            good[q] = inside[g]
            g += 1
    return good


@compiled(inline=True)  # inlined: called per child
def _way_of(nf, ni, parent, depth, vx, vy, speed, obstacle_id, option):
    """The way round a child carries (first direction, obstacle id, side, root): a root's child starts it with its
    leg's direction and its option, deeper ones keep their parent's."""
    if depth == 0:
        return vx / speed, vy / speed, obstacle_id, _SIDES[option], _ROOTS[option]
    return nf[parent, _FX], nf[parent, _FY], ni[parent, _WAY0], ni[parent, _WAY1], ni[parent, _WAY2]


@compiled(inline=True)
def _via_children(nf, ni, m, depth, branch, via, horizon_s, goal, obstacles, corridor):
    """The pairs' children: the legs to their via points (:func:`_via_legs`) free of the people
    and inside the corridor, added below their nodes (a root's child starts the way round: obstacle id, side,
    root; deeper ones keep their parent's). ``branch``: :func:`_branch_pairs`' pairs."""
    pair_nodes, pair_obstacles, _ = branch
    via_radii, ids, shapes = via
    _, _, _, envelope, _, spacing_m, tolerance_m = goal
    legs = _via_legs(nf, branch, via_radii, envelope, horizon_s, obstacles, shapes)
    pair, option, t_k, starts_k, times_k, leg_velocity, via, count = legs
    if not count:
        return nf, ni, m
    good = legs_free(
        starts_k[:count], times_k[:count], leg_velocity[:count], t_k[:count], horizon_s, obstacles, shapes.shape_of
    )
    kept = _keep_inside(good, starts_k, via, count, corridor, spacing_m, tolerance_m)
    for q in range(count):
        if not kept[q]:
            continue
        p = pair[q]
        parent = pair_nodes[p]
        speed = nf[parent, _V]
        way = _way_of(
            nf, ni, parent, depth, leg_velocity[q, 0], leg_velocity[q, 1], speed, ids[pair_obstacles[p]], option[q]
        )
        fx, fy, way0, way1, way2 = way
        nf, ni, m = _add(
            nf,
            ni,
            m,
            via[q, 0],
            via[q, 1],
            times_k[q] + t_k[q],
            speed,
            parent,
            nf[parent, _LENGTH] + speed * t_k[q],
            fx,
            fy,
            way0,
            way1,
            way2,
            0.0,
            0.0,
        )
    return nf, ni, m


@compiled(inline=True)
def _straight_inside(position, goal, corridor):
    """Whether the straight leg from the robot to the subgoal stays inside the corridor."""
    here = np.empty((1, 2))
    here[0, 0] = position[0]
    here[0, 1] = position[1]
    return goal_legs_inside_all(corridor, here, goal)[0]


@compiled(inline=True)
def _frontier_leaves(nf, ni, batch, m, horizon_s, goal, obstacles, corridor, shape_of):
    """The goal legs of the new frontier (the nodes ``batch`` .. ``m``): the free ones complete candidates, made
    leaves. Returns the legs' free and first contacts, which the next depth branches on."""
    starts = np.ascontiguousarray(nf[batch:m, _X : _Y + 1])
    _, lengths, free_now, contact_now = goal_legs_of(
        starts, nf[batch:m, _T].copy(), nf[batch:m, _V].copy(), horizon_s, goal, obstacles, corridor, shape_of
    )
    for r in range(m - batch):
        if free_now[r]:
            ni[batch + r, _LEAF] = 1
            nf[batch + r, _GOAL] = lengths[r]
    return free_now, contact_now


@compiled
def grow(position, speeds, nominal_index, roots, via, slow, horizon_s, goal, obstacles, corridor, tree):
    """Every complete candidate of the cycle (straight, slow/wait, corners, via-point chains), in this order: the
    roots, slow/wait, corners, then the via-point children depth by depth. Returns the node store, floats (M, 10) and integers (M, 5), in
    the columns named above; a node is a leaf (a complete candidate) when its goal leg is free.

    Takes records (tuples): ``roots`` (directions, lengths, free, contact of the root legs: :func:`goal_legs`'),
    ``via`` (via radii, ids, :class:`.shapes.StaticShapes`), ``slow`` (slow radii, growth, growth until, slow times, creep speed), ``goal``, ``obstacles``
    and ``corridor`` (the kernels' records, named above :func:`goal_legs_of`), ``tree`` (the waypoints, the robot's segment, whether slow/wait
    candidates are grown, the depth, the most obstacles a root branches on)."""
    waypoints, robot_segment, slow_enabled, max_depth, max_root_obstacles = tree
    subgoal_index = goal[4]
    root_directions, root_lengths, root_free, root_contact = roots
    obstacle_positions = obstacles[0]
    shape_of = via[2].shape_of
    n_count = obstacle_positions.shape[0]
    nf, ni, m = _root_nodes(position, speeds, root_directions, root_lengths, root_free)
    straight_inside = _straight_inside(position, goal, corridor)
    if slow_enabled and n_count > 0 and straight_inside:
        nf, ni, m = _slow_nodes(
            nf, ni, m, position, speeds, nominal_index, slow, horizon_s, obstacles, goal, corridor, shape_of
        )
    frontier_start = 0
    frontier_end = speeds.shape[0]
    free_now = root_free.copy()
    contact_now = root_contact
    for depth in range(max_depth):
        batch = m
        if depth == 0 and robot_segment + 1 < subgoal_index and not straight_inside:
            path = (waypoints, robot_segment)
            nf, ni, m = _corner_nodes(nf, ni, m, position, speeds, path, horizon_s, goal, obstacles, corridor, shape_of)
        if n_count > 0:
            frontier = (frontier_start, frontier_end, free_now, contact_now)
            branch = _pairs(nf, frontier, depth, max_root_obstacles, obstacle_positions, via)
            if branch[2]:
                nf, ni, m = _via_children(nf, ni, m, depth, branch, via, horizon_s, goal, obstacles, corridor)
        if m == batch:
            break
        frontier_start = batch
        frontier_end = m
        free_now, contact_now = _frontier_leaves(nf, ni, batch, m, horizon_s, goal, obstacles, corridor, shape_of)
    return nf[:m].copy(), ni[:m].copy()
