"""The leg checks of the paper's §3 (the segment check and the path boundary): when a straight leg at constant
velocity first touches a person's oblique cylinder (or cone, when the forecast's uncertainty grows it) in x-y-t, and
whether a leg keeps inside the path's corridor; the legs to the subgoal checked against both. Compiled steps, the one
implementation of each; :mod:`.packing` packs the cycle's arrays for them.

Source: the segment check and the boundary rule of the paper's procedure, each as one scalar loop. Choices:
* hypot costs about 20 ns here; where only the sign of ``hypot - limit`` matters, the squared distance decides
  outside a band of ±1e-9 around the limit (:func:`excess_at_most`).
* Inputs are C-contiguous float64 arrays (the caller makes them so): one compiled signature each.
"""

from __future__ import annotations

import math

import numpy as np

from viapath.jit import compiled


@compiled(inline=True)  # inlined: called per leg and obstacle, a few hundred a cycle
def _contact(px, py, vx, vy, radius, growth, duration):
    """Scalar :func:`viapath.geometry._first_contact`: first τ in [0, duration] with
    |p + v τ| <= radius + growth τ; inf if none, 0 if already touching. (The reference drops the
    growth terms when there is no growth; with growth +0.0 and a finite radius they are exact zeros,
    so one form serves both, and one compiled signature.)"""
    a = vx * vx + vy * vy - growth * growth
    b = px * vx + py * vy - radius * growth
    c = px * px + py * py - radius * radius
    if c <= 0:
        return 0.0
    discriminant = b * b - a * c
    denominator = math.sqrt(discriminant if discriminant > 0.0 else 0.0) - b
    if discriminant >= 0 and denominator > 0:
        tau = c / denominator
        if tau <= duration:
            return tau
    return math.inf


@compiled(inline=True)
def _leg_contact(
    starts,
    start_times,
    velocities,
    duration,
    obstacle_positions,
    obstacle_velocities,
    radii,
    growth,
    growth_until_s,
    leg_radius,
    cylinder_only,
    k,
    j,
):
    """The first contact of leg ``k`` (``duration`` long) with obstacle ``j``: one entry of
    :func:`legs_first_contact` (inlined: :func:`legs_free` asks it leg by leg and stops at the first contact)."""
    t0 = start_times[k]
    ovx = obstacle_velocities[j, 0]
    ovy = obstacle_velocities[j, 1]
    px = starts[k, 0] - (obstacle_positions[j, 0] + ovx * t0)
    py = starts[k, 1] - (obstacle_positions[j, 1] + ovy * t0)
    vx = velocities[k, 0] - ovx
    vy = velocities[k, 1] - ovy
    g = growth[j]
    if cylinder_only:
        return _contact(px, py, vx, vy, (radii[j] + leg_radius) + g * t0, g, duration)
    until = growth_until_s[j]
    cone_duration = until - t0
    if cone_duration < 0.0:
        cone_duration = 0.0
    if cone_duration > duration:
        cone_duration = duration
    early = _contact(
        px,
        py,
        vx,
        vy,
        (radii[j] + leg_radius) + g * (t0 if t0 < until else until),
        g if until > t0 else 0.0,
        cone_duration,
    )
    if math.isfinite(early):
        return early
    if t0 + duration >= until:
        full_growth = g * (until if math.isfinite(until) else 0.0)
        late = _contact(
            px + vx * cone_duration,
            py + vy * cone_duration,
            vx,
            vy,
            (radii[j] + leg_radius) + full_growth,
            0.0,
            duration - cone_duration,
        )
        return late + cone_duration
    return math.inf


@compiled(inline=True)
def _cylinder_only(growth, growth_until_s):
    """Whether no obstacle's radius stops growing within the legs' time (no growth, or none capped): then
    one cylinder per obstacle."""
    any_growth = False
    any_finite_until = False
    for j in range(growth.shape[0]):
        if growth[j] != 0.0:
            any_growth = True
        if math.isfinite(growth_until_s[j]):
            any_finite_until = True
    return (not any_growth) or (not any_finite_until)


@compiled
def legs_first_contact(
    starts,
    start_times,
    velocities,
    durations,
    obstacle_positions,
    obstacle_velocities,
    radii,
    growth,
    growth_until_s,
    leg_radii,
):
    """(K, N) first contact of K legs with N moving discs whose radius grows as a capped cone: the
    compiled form of :func:`viapath.geometry.legs_first_contact` (all arguments arrays, one value per
    obstacle for ``radii``, ``growth`` and ``growth_until_s``; ``leg_radii`` (K,) is added per leg:
    zeros leave the radii as they are, x + 0.0 being x)."""
    k_count = starts.shape[0]
    n_count = obstacle_positions.shape[0]
    out = np.empty((k_count, n_count))
    cylinder_only = _cylinder_only(growth, growth_until_s)
    for k in range(k_count):
        for j in range(n_count):
            out[k, j] = _leg_contact(
                starts,
                start_times,
                velocities,
                durations[k],
                obstacle_positions,
                obstacle_velocities,
                radii,
                growth,
                growth_until_s,
                leg_radii[k],
                cylinder_only,
                k,
                j,
            )
    return out


@compiled(inline=True)
def _cylinder_only_by_kind(growth, growth_until_s, shape_of):
    """:func:`_cylinder_only` of the people and of the static discs (``shape_of`` >= 0), each on its own; of all
    obstacles for both without static geometry (an empty ``shape_of``)."""
    if shape_of.shape[0] == 0:
        both = _cylinder_only(growth, growth_until_s)
        return both, both
    growth_of = np.zeros(2, np.bool_)  # [people, static]
    finite_of = np.zeros(2, np.bool_)
    for j in range(growth.shape[0]):
        kind = 1 if shape_of[j] >= 0 else 0
        growth_of[kind] = growth_of[kind] or growth[j] != 0.0
        finite_of[kind] = finite_of[kind] or math.isfinite(growth_until_s[j])
    return (not growth_of[0]) or (not finite_of[0]), (not growth_of[1]) or (not finite_of[1])


@compiled
def first_contacts(starts, start_times, velocities, checked, durations, obstacles, leg_radii, shape_of):
    """(K, N) first contact of each leg with each obstacle (:func:`legs_first_contact`): a person's up to the leg's
    ``checked`` time (the horizon), with the leg's ``leg_radii`` added; a static disc's (``shape_of`` >= 0) over
    the leg's whole ``durations`` with none added: static geometry stays put, a leg into a wall is not made free
    by driving it slowly, and the braking envelope is for where people may walk."""
    obstacle_positions, _, _, growth, growth_until_s = obstacles
    if shape_of.shape[0] == 0:  # one kind of obstacle: the loop whose branches do not vary (as in legs_free)
        return legs_first_contact(starts, start_times, velocities, checked, *obstacles, leg_radii)
    k_count = starts.shape[0]
    n_count = obstacle_positions.shape[0]
    out = np.empty((k_count, n_count))
    cylinders = _cylinder_only_by_kind(growth, growth_until_s, shape_of)
    for k in range(k_count):
        for j in range(n_count):
            static = shape_of[j] >= 0
            out[k, j] = _contact_by_kind(
                starts, start_times, velocities, checked, durations, obstacles, leg_radii[k], cylinders, static, k, j
            )
    return out


@compiled(inline=True)  # inlined: called per leg and obstacle
def _contact_by_kind(
    starts, start_times, velocities, checked, durations, obstacles, leg_radius, cylinders, static, k, j
):
    """:func:`_leg_contact` of leg ``k`` and obstacle ``j`` by its kind: a static disc's (``static``) over the leg's
    whole ``durations[k]``, no leg radius added; a person's up to ``checked[k]``, with ``leg_radius``.
    ``cylinders``: :func:`_cylinder_only_by_kind`'s (people, static)."""
    obstacle_positions, obstacle_velocities, radii, growth, growth_until_s = obstacles
    return _leg_contact(
        starts,
        start_times,
        velocities,
        durations[k] if static else checked[k],
        obstacle_positions,
        obstacle_velocities,
        radii,
        growth,
        growth_until_s,
        0.0 if static else leg_radius,
        cylinders[1] if static else cylinders[0],
        k,
        j,
    )


@compiled
def clip(value: float, low: float, high: float) -> float:
    return low if value < low else high if value > high else value


@compiled
def _excess(px, py, segment_starts, segment_directions, segment_lengths, half_widths):
    """Scalar :meth:`viapath.path.DesignatedPath.corridor_excess` of one point."""
    best = math.inf
    for i in range(segment_starts.shape[0]):
        value = _capsule_excess(px, py, segment_starts, segment_directions, segment_lengths, half_widths, i)
        if value < best:
            best = value
    return best


@compiled(inline=True)
def _along(rx, ry, dx, dy, length):
    """How far along a segment (unit direction (dx, dy), ``length`` long) its nearest point to a point at (rx, ry)
    from its start lies: the projection, clipped to the segment."""
    along = rx * dx + ry * dy
    if along < 0.0:
        along = 0.0
    if along > length:
        along = length
    return along


# The capsule's projection in two inlined steps: the arrays read in one without branches, the arithmetic on
# scalars in the other. One inlined step that takes the arrays and has the clip's branches keeps the arrays'
# reference counting inside the caller's loop: the escape's scores took 4.7 times as long, the corridor check of
# legs 2.7 times (measured on a cycle's arguments).
@compiled(inline=True)
def _capsule_offset(px, py, segment_starts, segment_directions, segment_lengths, i):
    """The offset (x, y) of the point from its nearest point on segment ``i``."""
    return _segment_offset(
        px,
        py,
        segment_starts[i, 0],
        segment_starts[i, 1],
        segment_directions[i, 0],
        segment_directions[i, 1],
        segment_lengths[i],
    )


@compiled(inline=True)
def _segment_offset(px, py, start_x, start_y, dx, dy, length):
    """The offset (x, y) of the point from its nearest point on the segment from (start_x, start_y) along the unit
    direction (dx, dy), ``length`` long."""
    along = _along(px - start_x, py - start_y, dx, dy, length)
    return px - (start_x + along * dx), py - (start_y + along * dy)


@compiled
def _capsule_excess(px, py, segment_starts, segment_directions, segment_lengths, half_widths, i):
    """How far the point lies outside capsule ``i`` (negative inside)."""
    ox, oy = _capsule_offset(px, py, segment_starts, segment_directions, segment_lengths, i)
    return math.hypot(ox, oy) - half_widths[i]


@compiled(inline=True)  # inlined: called per leg of the corridor check
def _ends_inside(starts, ends, k, corridor, tolerance_m):
    """Whether leg ``k``'s start lies in some capsule of the corridor (within ``tolerance_m``), its end in some,
    and both in one (then the leg is inside: a capsule is convex)."""
    segment_starts, segment_directions, segment_lengths, half_widths = corridor
    start_any = False
    end_any = False
    both = False
    for i in range(segment_starts.shape[0]):
        a = (
            _capsule_excess(
                starts[k, 0], starts[k, 1], segment_starts, segment_directions, segment_lengths, half_widths, i
            )
            <= tolerance_m
        )
        b = (
            _capsule_excess(ends[k, 0], ends[k, 1], segment_starts, segment_directions, segment_lengths, half_widths, i)
            <= tolerance_m
        )
        start_any = start_any or a
        end_any = end_any or b
        both = both or (a and b)
    return start_any, end_any, both


@compiled(inline=True)  # inlined: called per leg the ends leave open
def _samples_inside(starts, ends, k, num, corridor, tolerance_m):
    """Whether leg ``k``'s ``num`` evenly spaced points (both ends among them) are all within ``tolerance_m`` of
    the corridor."""
    segment_starts, segment_directions, segment_lengths, half_widths = corridor
    step = 1.0 / (num - 1)
    ax = starts[k, 0]
    ay = starts[k, 1]
    bx = ends[k, 0] - ax
    by = ends[k, 1] - ay
    for f_index in range(num):
        fraction = 1.0 if f_index == num - 1 else f_index * step
        px = ax + fraction * bx
        py = ay + fraction * by
        if _excess(px, py, segment_starts, segment_directions, segment_lengths, half_widths) > tolerance_m:
            return False
    return True


@compiled
def legs_inside(segment_starts, segment_directions, segment_lengths, half_widths, starts, ends, spacing_m, tolerance_m):
    """The compiled form of :meth:`viapath.path.DesignatedPath.legs_inside`: both ends in one capsule, else
    sampled every ``spacing_m`` (the sample count set by the longest unresolved leg, as there)."""
    corridor = (segment_starts, segment_directions, segment_lengths, half_widths)
    count = starts.shape[0]
    inside = np.zeros(count, np.bool_)
    unresolved = np.zeros(count, np.bool_)
    longest = 0.0
    any_unresolved = False
    for k in range(count):
        start_any, end_any, both = _ends_inside(starts, ends, k, corridor, tolerance_m)
        inside[k] = both
        if not both and start_any and end_any:
            unresolved[k] = True
            any_unresolved = True
            length = math.hypot(ends[k, 0] - starts[k, 0], ends[k, 1] - starts[k, 1])
            if length > longest:
                longest = length
    if not any_unresolved:
        return inside
    num = max(2, int(math.ceil(longest / spacing_m)) + 1)
    for k in range(count):
        if unresolved[k]:
            inside[k] = _samples_inside(starts, ends, k, num, corridor, tolerance_m)
    return inside


@compiled
def goal_legs_inside(
    segment_starts, segment_directions, segment_lengths, half_widths, starts, subgoal_index, tolerance_m
):
    """The first part of :meth:`viapath.planning.viapath.checks.LegChecks.goal_legs_inside`: a leg from a
    point inside a capsule next to the subgoal is inside (the caller checks the others with
    :func:`legs_inside`)."""
    count = starts.shape[0]
    segments = segment_starts.shape[0]
    inside = np.zeros(count, np.bool_)
    for k in range(count):
        for i in (subgoal_index - 1, subgoal_index):
            if i >= segments:
                continue
            j = i if i >= 0 else i + segments  # a Python index: -1 is the last segment
            dx = segment_directions[j, 0]
            dy = segment_directions[j, 1]
            rx = starts[k, 0] - segment_starts[j, 0]
            ry = starts[k, 1] - segment_starts[j, 1]
            along = _along(rx, ry, dx, dy, segment_lengths[j])
            if math.hypot(rx - along * dx, ry - along * dy) - half_widths[j] <= tolerance_m:
                inside[k] = True
    return inside


@compiled(inline=True)  # inlined: a call of _excess, not inlined, measured 40 ns a point
def excess_at_most(px, py, segment_starts, segment_directions, segment_lengths, half_widths, limit):
    """``_excess(px, py, ...) <= limit`` (the point within ``limit`` of the corridor, NaN false), mostly without
    hypot: with ``limit`` and every half width >= 0, a capsule's ``hypot(o) - half <= limit`` is ``hypot(o) <
    half + limit`` or, on the boundary, the difference itself: decided by :func:`_within`'s band where it is
    certain, else by hypot."""
    if not limit >= 0.0:
        return _excess(px, py, segment_starts, segment_directions, segment_lengths, half_widths) <= limit
    for i in range(segment_starts.shape[0]):
        half = half_widths[i]
        ox, oy = _capsule_offset(px, py, segment_starts, segment_directions, segment_lengths, i)
        reach = half + limit
        if half >= 0.0 and 1e-140 < reach < 1e140:
            squared = ox * ox + oy * oy
            below = reach * (1.0 - 1e-9)
            if squared < below * below:
                return True  # the min over the capsules is at most this one
            above = reach * (1.0 + 1e-9)
            if squared > above * above:
                continue
        if math.hypot(ox, oy) - half <= limit:
            return True
    return False


@compiled(inline=True)
def _legs_to_subgoal(starts, start_times, speeds, subgoal, stop_short_m, continuation, two):
    """The straight legs of :func:`goal_legs_of`: from each of the K starts, its direction to the subgoal (K, 2), its
    distance (K,) and its leg's duration at its speed, ending ``stop_short_m`` short (K,); and the legs whose
    contacts are checked, (starts, start times, velocities, durations): the K legs, then, with ``two``, the K
    continuations past the subgoal, each starting when its leg ends."""
    k_count = starts.shape[0]
    legs = 2 * k_count if two else k_count
    directions = np.empty((k_count, 2))
    lengths = np.empty(k_count)
    durations = np.empty(k_count)
    leg_starts = np.empty((legs, 2))
    leg_times = np.empty(legs)
    leg_velocities = np.empty((legs, 2))
    leg_durations = np.empty(legs)
    for k in range(k_count):
        ox = subgoal[0] - starts[k, 0]
        oy = subgoal[1] - starts[k, 1]
        length = math.hypot(ox, oy)
        lengths[k] = length
        divisor = length if length > 1e-12 else 1e-12
        dx = ox / divisor
        dy = oy / divisor
        directions[k, 0] = dx
        directions[k, 1] = dy
        short = length - stop_short_m
        duration = (short if short > 0.0 else 0.0) / speeds[k]
        durations[k] = duration
        leg_starts[k, 0] = starts[k, 0]
        leg_starts[k, 1] = starts[k, 1]
        leg_times[k] = start_times[k]
        leg_velocities[k, 0] = dx * speeds[k]
        leg_velocities[k, 1] = dy * speeds[k]
        leg_durations[k] = duration
        if two:
            m = k_count + k
            leg_starts[m, 0] = subgoal[0]
            leg_starts[m, 1] = subgoal[1]
            leg_times[m] = start_times[k] + duration
            leg_velocities[m, 0] = continuation[0] * speeds[k]
            leg_velocities[m, 1] = continuation[1] * speeds[k]
            leg_durations[m] = continuation[2] / speeds[k]
    return directions, lengths, durations, (leg_starts, leg_times, leg_velocities, leg_durations)


@compiled(inline=True)
def _envelope_contacts(legs, horizon_s, envelope, obstacles, shape_of):
    """:func:`first_contacts` of the legs (the record of :func:`_legs_to_subgoal`), a person's up to the horizon
    and with the braking envelope's radius: how far a person accelerating at ``envelope[0]`` gets in the robot's
    stopping time (the period ``envelope[1]``, then braking from the leg's speed at ``envelope[2]``; none with
    accel 0)."""
    leg_starts, leg_times, leg_velocities, leg_durations = legs
    count = leg_times.shape[0]
    checked = np.empty(count)
    leg_radii = np.empty(count)
    half_accel = 0.5 * envelope[0]
    for m in range(count):
        checked[m] = clip(horizon_s - leg_times[m], 0.0, leg_durations[m])
        if envelope[0] > 0:
            stop_s = envelope[1] + math.hypot(leg_velocities[m, 0], leg_velocities[m, 1]) / envelope[2]
            leg_radii[m] = half_accel * (stop_s * stop_s)
        else:
            leg_radii[m] = 0.0
    return first_contacts(leg_starts, leg_times, leg_velocities, checked, leg_durations, obstacles, leg_radii, shape_of)


@compiled(inline=True)
def _sooner_of_two(both, durations, two, contact):
    """Fills ``contact`` (K, N) with each start's first contacts: its leg's (``both``'s first K rows), or, with
    ``two``, the sooner of that and its continuation's (the next K rows, from the leg's end), NaN if either is."""
    k_count = contact.shape[0]
    for k in range(k_count):
        for j in range(contact.shape[1]):
            value = both[k, j]
            if two:
                later = both[k_count + k, j] + durations[k]
                if value != value or later != later:
                    value = math.nan
                elif later < value:
                    value = later
            contact[k, j] = value


@compiled(inline=True)
def _free_and_inside(contact, corridor, starts, goal):
    """Which legs are free: no contact, then inside. The corridor check only when some leg has no contact (a blocked
    batch, the usual case in the tree, needs none); then of all the legs, as the sample spacing is the longest's."""
    k_count = contact.shape[0]
    free = np.empty(k_count, np.bool_)
    any_clear = False
    for k in range(k_count):
        ok = True
        for j in range(contact.shape[1]):
            if not math.isinf(contact[k, j]):
                ok = False
                break
        free[k] = ok
        any_clear = any_clear or ok
    if any_clear:
        inside = goal_legs_inside_all(corridor, starts, goal)
        for k in range(k_count):
            free[k] = free[k] and inside[k]
    return free


# The compiled steps' records (tuples, so that their pieces take a few names instead of a dozen arguments each):
# obstacles (positions, velocities, radii, growth, growth until), as legs_first_contact takes them;
# corridor (segment starts, directions, lengths, half widths); goal (subgoal, how far short of it legs end,
# continuation, braking envelope, subgoal index, corridor check spacing, corridor tolerance).


@compiled
def goal_legs_of(starts, start_times, speeds, horizon_s, goal, obstacles, corridor, shape_of):
    """:func:`goal_legs` on its records; ``shape_of``: :class:`.shapes.StaticShapes`' (static discs checked to
    the legs' end, without the braking envelope: :func:`first_contacts`)."""
    subgoal, stop_short_m, continuation, envelope, _, _, _ = goal
    n_count = obstacles[0].shape[0]
    two = continuation.shape[0] == 3 and n_count > 0
    directions, lengths, durations, legs = _legs_to_subgoal(
        starts, start_times, speeds, subgoal, stop_short_m, continuation, two
    )
    contact = np.empty((starts.shape[0], n_count))
    if n_count > 0:
        both = _envelope_contacts(legs, horizon_s, envelope, obstacles, shape_of)
        _sooner_of_two(both, durations, two, contact)
    return directions, lengths, _free_and_inside(contact, corridor, starts, goal), contact


@compiled
def goal_legs(
    starts,
    start_times,
    speeds,
    subgoal,
    stop_short_m,
    horizon_s,
    continuation,
    obstacle_positions,
    obstacle_velocities,
    radii,
    growth,
    growth_until_s,
    envelope,
    segment_starts,
    segment_directions,
    segment_lengths,
    half_widths,
    subgoal_index,
    spacing_m,
    tolerance_m,
    shape_of,
):
    """The compiled form of :meth:`viapath.planning.viapath.checks.LegChecks.goal_legs`, whole: the straight
    legs from K nodes to the subgoal (with the continuation past an intermediate subgoal as K more legs),
    their first contacts with the braking envelope kept, and the corridor check (:func:`goal_legs_inside`,
    then :func:`legs_inside` for the legs it leaves open, as the backend does). One call instead of
    three kernels and some thirty small array operations; called a few times every cycle.

    ``continuation`` is (dx, dy, length) or empty (none); ``envelope`` is (person accel, period, robot
    accel), accel 0 for none; ``shape_of`` :class:`.shapes.StaticShapes`' (empty: no static geometry). Returns
    (directions (K, 2), lengths (K,), free (K,), contact (K, N))."""
    goal = (subgoal, stop_short_m, continuation, envelope, subgoal_index, spacing_m, tolerance_m)
    obstacles = (obstacle_positions, obstacle_velocities, radii, growth, growth_until_s)
    corridor = (segment_starts, segment_directions, segment_lengths, half_widths)
    return goal_legs_of(starts, start_times, speeds, horizon_s, goal, obstacles, corridor, shape_of)


@compiled
def goal_legs_inside_all(corridor, starts, goal):
    """What the backend's ``goal_legs_inside`` returns: :func:`goal_legs_inside`, then :func:`legs_inside`
    on the legs it leaves open (all of them in one call: the sample spacing depends on the longest)."""
    segment_starts, segment_directions, segment_lengths, half_widths = corridor
    subgoal, _, _, _, subgoal_index, spacing_m, tolerance_m = goal
    k_count = starts.shape[0]
    inside = goal_legs_inside(
        segment_starts, segment_directions, segment_lengths, half_widths, starts, subgoal_index, tolerance_m
    )
    rest = 0
    for k in range(k_count):
        if not inside[k]:
            rest += 1
    if rest:
        rest_starts = np.empty((rest, 2))
        rest_ends = np.empty((rest, 2))
        index = np.empty(rest, np.int64)
        r = 0
        for k in range(k_count):
            if not inside[k]:
                rest_starts[r, 0] = starts[k, 0]
                rest_starts[r, 1] = starts[k, 1]
                rest_ends[r, 0] = subgoal[0]
                rest_ends[r, 1] = subgoal[1]
                index[r] = k
                r += 1
        rest_inside = legs_inside(
            segment_starts,
            segment_directions,
            segment_lengths,
            half_widths,
            rest_starts,
            rest_ends,
            spacing_m,
            tolerance_m,
        )
        for r in range(rest):
            inside[index[r]] = rest_inside[r]
    return inside


@compiled
def legs_free(starts, start_times, velocities, durations, horizon_s, obstacles, shape_of):
    """LegChecks.legs_free: no contact with a person up to the horizon nor with static geometry (``shape_of`` >= 0:
    :class:`.shapes.StaticShapes`') over the whole leg, plain radii (no braking envelope). Leg by leg, up to
    its first contact: whether any contact is finite (or NaN) is all that is asked. ``obstacles``: the record
    (positions, velocities, radii, growth, growth until)."""
    k_count = starts.shape[0]
    checked = np.empty(k_count)
    for k in range(k_count):
        checked[k] = clip(horizon_s - start_times[k], 0.0, durations[k])
    # Without static geometry the loop's branches do not vary from obstacle to obstacle (any_static a constant of
    # the inlined loop): with 100 people the cycle's choice took 2.3 times as long with one loop for both kinds.
    if shape_of.shape[0] == 0:
        return _free_of(starts, start_times, velocities, checked, checked, obstacles, shape_of, False)
    return _free_of(starts, start_times, velocities, checked, durations, obstacles, shape_of, True)


@compiled(inline=True)
def _free_of(starts, start_times, velocities, checked, durations, obstacles, shape_of, any_static):
    """:func:`legs_free`'s loop: a person's contact up to ``checked``, a static disc's (with ``any_static``) up to
    ``durations``."""
    k_count = starts.shape[0]
    cylinders = _cylinder_only_by_kind(obstacles[3], obstacles[4], shape_of)
    free = np.empty(k_count, np.bool_)
    for k in range(k_count):
        ok = True
        for j in range(obstacles[0].shape[0]):
            static = any_static and shape_of[j] >= 0
            # leg radius 0.0, as legs_first_contact with np.zeros(k_count)
            contact = _contact_by_kind(
                starts, start_times, velocities, checked, durations, obstacles, 0.0, cylinders, static, k, j
            )
            if not math.isinf(contact):
                ok = False
                break
        free[k] = ok
    return free


@compiled(inline=True)
def legs_inside_of(corridor, starts, ends, spacing_m, tolerance_m):
    """:func:`legs_inside` with the corridor's record unpacked."""
    segment_starts, segment_directions, segment_lengths, half_widths = corridor
    return legs_inside(
        segment_starts, segment_directions, segment_lengths, half_widths, starts, ends, spacing_m, tolerance_m
    )
