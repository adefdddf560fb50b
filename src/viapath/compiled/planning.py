"""The viapath planner's compiled steps, each the one implementation of its step: the leg-against-people
checks, the via points, the corridor checks, the candidate tree, Eq. 1's sum and the choice, the roll-outs
and the escape. Called through :mod:`viapath.compiled.arithmetic`, which packs the cycle's arrays.

Source: the paper's procedure (:mod:`viapath.planning.viapath.planner`); each step as one scalar loop instead
of a few dozen array operations (the profile of ``benchmarks/bench_planner.py``, docs/speed.md). The tests hold
them to independent oracles: the brute-force x-y-t checks, dense sampling of legs and corridors, the escape's
scores worked out command by command, the controller stepped as the simulator steps it
(``tests/planning/test_planner_oracles.py``, ``tests/planning/test_compiled_choice.py``, ``tests/test_kinematics.py``).

Choices:
* Every kernel is a plain module-level function decorated with :func:`viapath.jit.compiled` (numba, cached on
  disk: a process after the first pays no compilation; docs/speed.md gives the first run's cost). With
  ``NUMBA_DISABLE_JIT=1`` the same functions run as plain Python.
* Inputs are C-contiguous float64 arrays (the caller makes them so): one compiled signature each.
* The escape's sines and cosines of its headings are numpy's (taken between :func:`escape_headings` and
  :func:`escape_scores`), its sums numpy's pairwise summation (:func:`viapath.compiled.sums.pairwise_sum`):
  the figures they were first specified with, kept bit for bit.
* hypot costs about 20 ns here; where only the sign of ``hypot - limit`` matters, the squared distance
  decides outside a band of ±1e-9 around the limit (:func:`_within`, :func:`_excess_at_most`,
  :func:`_furthest`).
"""

from __future__ import annotations

import math

import numpy as np

from viapath.compiled import dependency_digest
from viapath.compiled.slots import (
    C_DEGREES,
    C_DEPTH,
    C_NOMINAL,
    C_ONLY,
    C_ONLY_OBSTACLE,
    C_ONLY_ROOT,
    C_ONLY_SIDE,
    C_PREFERRED,
    C_PREV_MMPS,
    C_PREV_OBSTACLE,
    C_PREV_ROOT,
    C_PREV_SIDE,
    C_PREVIOUS,
    C_ROLLOUTS,
    C_ROOT_LIMIT,
    C_SEGMENT,
    C_SLOW,
    C_STEPS,
    C_SUBGOAL,
    C_TRY_STRAIGHT,
    CANDIDATES,
    F_ACCEL,
    F_CREEP,
    F_DT,
    F_GAIN,
    F_HORIZON,
    F_HYSTERESIS,
    F_K1,
    F_K2,
    F_K3,
    F_K4,
    F_NOMINAL,
    F_ROLLOUT_HEADING,
    F_SIDE,
    F_SPACING,
    F_SPEED,
    F_STANDING,
    F_STOP_SHORT,
    F_TOLERANCE,
    F_TURN_ACCEL,
    F_TURN_IN_PLACE,
    F_TURN_RATE,
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
    N_TIME,
    N_TO_GOAL,
    N_X,
    N_Y,
    NO_CANDIDATE,
    NODE_FLOATS,
    NODE_INTEGERS,
    STEP_ONE,
)
from viapath.compiled.sums import pairwise_sum
from viapath.jit import compiled

# numba's cache keys on this file alone; the layouts and the sums it compiles in are in these two files, so their
# digest is written here: a change there stops this import until the digest here is updated (which recompiles).
DEPENDENCIES = ("slots", "sums")
DEPENDENCY_DIGEST = "4c68e579030776c4"
if dependency_digest(DEPENDENCIES) != DEPENDENCY_DIGEST:
    raise RuntimeError(
        f"viapath.compiled.planning: {', '.join(DEPENDENCIES)} changed: set DEPENDENCY_DIGEST in "
        f"{__file__} to {dependency_digest(DEPENDENCIES)!r} (numba then compiles the kernels again)"
    )


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
    durations,
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
    """The first contact of leg ``k`` with obstacle ``j``: one entry of :func:`legs_first_contact` (inlined:
    :func:`_legs_free` asks it leg by leg and stops at the first contact)."""
    t0 = start_times[k]
    duration = durations[k]
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


@compiled
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
    numba twin of :func:`viapath.geometry.legs_first_contact` (all arguments arrays, one value per
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
                durations,
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


@compiled
def _clip(value, low, high):
    return low if value < low else high if value > high else value


@compiled
def track(
    x,
    y,
    heading,
    speed,
    turn,
    target_x,
    target_y,
    speed_mps,
    max_speed_mps,
    max_turn_rate_radps,
    max_accel_mps2,
    max_turn_accel_radps2,
    dt_s,
    steps,
    heading_gain,
):
    """(steps, 2) positions of the robot steering for the target: the numba twin of
    :func:`viapath.kinematics.track` (with :func:`~viapath.kinematics.steer_towards` and the exact arcs)."""
    dv = max_accel_mps2 * dt_s
    dw = max_turn_accel_radps2 * dt_s
    positions = np.empty((steps, 2))
    for k in range(steps):
        # steer_towards
        dx = target_x - x
        dy = target_y - y
        if dx * dx + dy * dy < 1e-18 or speed_mps <= 0:
            v_cmd = 0.0
            w_cmd = 0.0
        else:
            error = math.atan2(dy, dx) - heading
            error = math.atan2(math.sin(error), math.cos(error))
            w_cmd = _clip(heading_gain * error, -max_turn_rate_radps, max_turn_rate_radps)
            scale = _clip((math.pi / 2 - abs(error)) / (math.pi / 4), 0.0, 1.0)
            v_cmd = min(speed_mps, max_speed_mps) * scale
        speed += _clip(v_cmd - speed, -dv, dv)
        turn += _clip(w_cmd - turn, -dw, dw)
        # _arc
        new_heading = heading + turn * dt_s
        half = 0.5 * turn * dt_s
        chord = speed * dt_s * (1.0 - half * half / 6.0 if abs(half) < 1e-6 else math.sin(half) / half)
        x += chord * math.cos(heading + half)
        y += chord * math.sin(heading + half)
        heading = math.atan2(math.sin(new_heading), math.cos(new_heading))
        positions[k, 0] = x
        positions[k, 1] = y
    return positions


@compiled(inline=True)
def _via_pair(sx, sy, t0, speed, ox, oy, vx, vy, via_radius, growth, until, envelope_m, t_via, w_via):
    """:func:`via_options` of one pair (a leg from (sx, sy) at t0 at ``speed``, the obstacle at (ox, oy) now
    moving at (vx, vy)): the four options' via times into ``t_via`` (inf: none) and the two sides' offsets
    into ``w_via``; False when the start is within the via radius (no option). Inlined: :func:`grow` takes
    its pairs' options with it straight from its node store."""
    cx = ox + vx * t0
    cy = oy + vy * t0
    distance = math.hypot(cx - sx, cy - sy)
    passing_time = t0 + distance / speed
    if until < passing_time:
        passing_time = until
    radius = via_radius + growth * passing_time + envelope_m
    limit = 0.98 * distance
    if limit < radius:
        radius = limit
    if radius < 0.0:
        radius = 0.0
    # tangent_vectors, both sides
    dx = cx - sx
    dy = cy - sy
    distance_sq = dx * dx + dy * dy
    radius_sq = radius * radius
    valid = distance_sq > radius_sq
    gap = distance_sq - radius_sq
    length = math.sqrt(gap if gap > 0.0 else 0.0)
    scale = length / (distance_sq if valid else 1.0)
    for s in range(2):
        side_radius = (1.0 if s == 0 else -1.0) * radius
        wx = scale * (length * dx - side_radius * dy)
        wy = scale * (side_radius * dx + length * dy)
        w_via[s, 0] = wx
        w_via[s, 1] = wy
        # via_times
        w_length = math.sqrt(wx * wx + wy * wy)
        positive = w_length > 0
        inverse = 1.0 / (w_length if positive else 1.0)
        along = (wx * vx + wy * vy) * inverse
        across = (wx * vy - wy * vx) * inverse
        discriminant = speed * speed - across * across
        root = math.sqrt(discriminant if discriminant > 0.0 else 0.0)
        s_early = root - along
        s_late = -along - root
        ok = positive and discriminant >= 0
        t_via[s] = w_length / s_early if (ok and s_early > 1e-12) else math.inf
        t_via[2 + s] = w_length / s_late if (ok and s_late > 1e-12 and discriminant > 0) else math.inf
    return valid


@compiled
def via_options(
    starts,
    start_times,
    speeds,
    obstacle_positions,
    obstacle_velocities,
    via_radii,
    growth,
    growth_until_s,
    envelope_m,
    max_time_s,
):
    """The numba twin of :func:`viapath.geometry.via_options` (tangent points, via times on both
    sides and both roots, the legs to the via points), same options in the same order."""
    count = starts.shape[0]
    pair = np.empty(4 * count, np.int64)
    option = np.empty(4 * count, np.int64)
    t_out = np.empty(4 * count)
    w_out = np.empty((4 * count, 2))
    m = 0
    t_via = np.empty(4)
    w_via = np.empty((2, 2))
    for p in range(count):
        if not _via_pair(
            starts[p, 0],
            starts[p, 1],
            start_times[p],
            speeds[p],
            obstacle_positions[p, 0],
            obstacle_positions[p, 1],
            obstacle_velocities[p, 0],
            obstacle_velocities[p, 1],
            via_radii[p],
            growth[p],
            growth_until_s[p],
            envelope_m[p],
            t_via,
            w_via,
        ):
            continue
        for o in range(4):
            if t_via[o] <= max_time_s:
                pair[m] = p
                option[m] = o
                t_out[m] = t_via[o]
                w_out[m, 0] = w_via[o % 2, 0]
                w_out[m, 1] = w_via[o % 2, 1]
                m += 1
    leg_velocity = np.empty((m, 2))
    via = np.empty((m, 2))
    for i in range(m):
        p = pair[i]
        t = t_out[i]
        leg_velocity[i, 0] = (w_out[i, 0] + obstacle_velocities[p, 0] * t) / t
        leg_velocity[i, 1] = (w_out[i, 1] + obstacle_velocities[p, 1] * t) / t
        via[i, 0] = starts[p, 0] + leg_velocity[i, 0] * t
        via[i, 1] = starts[p, 1] + leg_velocity[i, 1] * t
    return pair[:m].copy(), option[:m].copy(), t_out[:m].copy(), leg_velocity, via


@compiled
def _excess(px, py, segment_starts, segment_directions, segment_lengths, half_widths):
    """Scalar :meth:`viapath.path.DesignatedPath.corridor_excess` of one point."""
    best = math.inf
    for i in range(segment_starts.shape[0]):
        value = _capsule_excess(px, py, segment_starts, segment_directions, segment_lengths, half_widths, i)
        if value < best:
            best = value
    return best


@compiled
def _capsule_excess(px, py, segment_starts, segment_directions, segment_lengths, half_widths, i):
    dx = segment_directions[i, 0]
    dy = segment_directions[i, 1]
    rx = px - segment_starts[i, 0]
    ry = py - segment_starts[i, 1]
    along = rx * dx + ry * dy
    if along < 0.0:
        along = 0.0
    if along > segment_lengths[i]:
        along = segment_lengths[i]
    ox = px - (segment_starts[i, 0] + along * dx)
    oy = py - (segment_starts[i, 1] + along * dy)
    return math.hypot(ox, oy) - half_widths[i]


@compiled
def legs_inside(segment_starts, segment_directions, segment_lengths, half_widths, starts, ends, spacing_m, tolerance_m):
    """The numba twin of :meth:`viapath.path.DesignatedPath.legs_inside`: both ends in one capsule, else
    sampled every ``spacing_m`` (the sample count set by the longest unresolved leg, as there)."""
    count = starts.shape[0]
    segments = segment_starts.shape[0]
    inside = np.zeros(count, np.bool_)
    unresolved = np.zeros(count, np.bool_)
    longest = 0.0
    any_unresolved = False
    for k in range(count):
        start_any = False
        end_any = False
        both = False
        for i in range(segments):
            a = (
                _capsule_excess(
                    starts[k, 0], starts[k, 1], segment_starts, segment_directions, segment_lengths, half_widths, i
                )
                <= tolerance_m
            )
            b = (
                _capsule_excess(
                    ends[k, 0], ends[k, 1], segment_starts, segment_directions, segment_lengths, half_widths, i
                )
                <= tolerance_m
            )
            start_any = start_any or a
            end_any = end_any or b
            both = both or (a and b)
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
    step = 1.0 / (num - 1)
    for k in range(count):
        if not unresolved[k]:
            continue
        ax = starts[k, 0]
        ay = starts[k, 1]
        bx = ends[k, 0] - ax
        by = ends[k, 1] - ay
        ok = True
        for f_index in range(num):
            fraction = 1.0 if f_index == num - 1 else f_index * step
            if (
                _excess(
                    ax + fraction * bx,
                    ay + fraction * by,
                    segment_starts,
                    segment_directions,
                    segment_lengths,
                    half_widths,
                )
                > tolerance_m
            ):
                ok = False
                break
        inside[k] = ok
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
            along = rx * dx + ry * dy
            if along < 0.0:
                along = 0.0
            if along > segment_lengths[j]:
                along = segment_lengths[j]
            if math.hypot(rx - along * dx, ry - along * dy) - half_widths[j] <= tolerance_m:
                inside[k] = True
    return inside


@compiled
def escape_contacts(
    positions, times, obstacle_positions, obstacle_velocities, check_radii, growth, growth_until_s, overlapping, steps
):
    """For K rolled-out commands (K, S, 2) against N people (centre ``p + v t``, radius ``r + g min(t, cap)``):
    the first step at which each command touches someone it does not overlap now (``steps`` if never),
    and, for the people it overlaps now (``overlapping``), the smallest gap over the roll-out and the gap
    at its end, (K, N_overlapping) each: the arrays :func:`viapath.planning.viapath.escape.escape_scores`
    scores with.

    Only the first contact counts, so a person not overlapped now is looked at up to the roll-out's first
    contact found so far, and over the steps in which the gap cannot close: between two steps it closes by
    at most the robot's longest step plus what the person walks and grows in a step (the triangle
    inequality), so a gap of g leaves g / that steps free. The skip keeps a margin (1e-6 m, and 1e-9
    relative) far above the rounding of the gaps, so the steps it passes over are those the full scan finds
    free: the same first contacts."""
    k_count = positions.shape[0]
    s_count = positions.shape[1]
    n_count = obstacle_positions.shape[0]
    n_overlapping = 0
    for j in range(n_count):
        if overlapping[j]:
            n_overlapping += 1
    first = np.full(k_count, steps, np.int64)
    gap_min = np.full((k_count, n_overlapping), np.inf)
    gap_last = np.empty((k_count, n_overlapping))
    tick = 0.0  # the longest time between two steps
    for s in range(1, s_count):
        tick = _maximum(tick, times[s] - times[s - 1])
    for k in range(k_count):
        hop_squared = 0.0  # the robot's longest step in roll-out k (NaN: no skipping)
        for s in range(1, s_count):
            dx = positions[k, s, 0] - positions[k, s - 1, 0]
            dy = positions[k, s, 1] - positions[k, s - 1, 1]
            hop_squared = _maximum(hop_squared, dx * dx + dy * dy)
        hop = math.sqrt(hop_squared)
        column = 0
        for j in range(n_count):
            px = obstacle_positions[j, 0]
            py = obstacle_positions[j, 1]
            vx = obstacle_velocities[j, 0]
            vy = obstacle_velocities[j, 1]
            if overlapping[j]:
                for s in range(s_count):
                    t = times[s]
                    reach = check_radii[j] + growth[j] * (t if t < growth_until_s[j] else growth_until_s[j])
                    gap = math.hypot(positions[k, s, 0] - (px + vx * t), positions[k, s, 1] - (py + vy * t)) - reach
                    if gap < gap_min[k, column]:
                        gap_min[k, column] = gap
                    if s == s_count - 1:
                        gap_last[k, column] = gap
                column += 1
                continue
            # (at least 1e-300: a gap that cannot close leaves every step free; NaN stays NaN)
            closing = _maximum((hop + (math.hypot(vx, vy) + abs(growth[j])) * tick) * (1.0 + 1e-9), 1e-300)
            s = 0
            while s < first[k]:  # (first[k] <= steps, the roll-out's length)
                t = times[s]
                reach = check_radii[j] + growth[j] * (t if t < growth_until_s[j] else growth_until_s[j])
                dx = positions[k, s, 0] - (px + vx * t)
                dy = positions[k, s, 1] - (py + vy * t)
                if _within(dx, dy, reach):  # hypot - reach < 0: the sign of a difference is exact
                    first[k] = s
                    break
                free_steps = (math.sqrt(dx * dx + dy * dy) - reach - 1e-6) * (1.0 - 1e-9) / closing
                if free_steps >= s_count:  # (NaN: not skipped)
                    break
                s += 1 + (int(free_steps) if free_steps >= 1.0 else 0)
    return first, gap_min, gap_last


# -- the escape (escape.stop_or_escape) in two calls: the standing check and the fan's headings; then, with numpy's
# sines and cosines of those headings, the roll-outs, their corridor excess, the people near, the contacts and the
# score. numpy takes the sines and cosines between the two (as kinematics.rollout does, np.sin and np.cos of arrays:
# numpy may dispatch its own SIMD routines for them, numba calls libm).

# Entries of the escape's float settings.
_E_DT, _E_ESCAPE_S, _E_SPEED_STEP, _E_TURN_STEP, _E_MAX_SPEED, _E_MAX_TURN, _E_TOLERANCE, _E_BOUND = range(8)
_E_TOP, _E_CONTINUITY, _E_PREVIOUS_SPEED, _E_PREVIOUS_TURN, _E_HORIZON, _E_STANDING_S = range(8, 14)
ESCAPE_SETTINGS = 14


@compiled
def _minimum(a, b):
    """np.minimum of two scalars: NaN first, and the second of two equal values (-0.0 against 0.0), as numpy."""
    return a if (a < b or a != a) else b


@compiled
def _maximum(a, b):
    """np.maximum of two scalars (as :func:`_minimum`)."""
    return a if (a > b or a != a) else b


@compiled
def _within(dx, dy, limit):
    """``math.hypot(dx, dy) < limit``, mostly without hypot (about 20 ns each here, most of the escape's
    time): outside a band of ±1e-9 (relative) around ``limit`` the squared distance (a few 1e-16 from the
    square of hypot's result) decides; inside it, and for limits whose square could underflow or overflow
    (or NaN), hypot decides."""
    if 1e-140 < limit < 1e140:
        squared = dx * dx + dy * dy
        below = limit * (1.0 - 1e-9)
        if squared < below * below:
            return True
        above = limit * (1.0 + 1e-9)
        if squared > above * above:
            return False
    return math.hypot(dx, dy) < limit


@compiled(inline=True)  # inlined: a call of _excess, not inlined, measured 40 ns a point
def _excess_at_most(px, py, segment_starts, segment_directions, segment_lengths, half_widths, limit):
    """``_excess(px, py, ...) <= limit`` (the point within ``limit`` of the corridor, NaN false), mostly without
    hypot: with ``limit`` and every half width >= 0, a capsule's ``hypot(o) - half <= limit`` is ``hypot(o) <
    half + limit`` or, on the boundary, the difference itself: decided by :func:`_within`'s band where it is
    certain, else by hypot."""
    if not limit >= 0.0:
        return _excess(px, py, segment_starts, segment_directions, segment_lengths, half_widths) <= limit
    for i in range(segment_starts.shape[0]):
        # _capsule_excess's projection written out again: an inlined helper returning the offset (x, y) made the
        # escape a third slower (0.21 -> 0.30 ms a cycle, measured), so the copy stays.
        half = half_widths[i]
        dx = segment_directions[i, 0]
        dy = segment_directions[i, 1]
        rx = px - segment_starts[i, 0]
        ry = py - segment_starts[i, 1]
        along = rx * dx + ry * dy
        if along < 0.0:
            along = 0.0
        if along > segment_lengths[i]:
            along = segment_lengths[i]
        ox = px - (segment_starts[i, 0] + along * dx)
        oy = py - (segment_starts[i, 1] + along * dy)
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


@compiled
def _roll_outs_within(positions, segment_starts, segment_directions, segment_lengths, half_widths, limit, known):
    """Whether each roll-out (K, S, 2) keeps every point within ``limit`` of the corridor (excess <= limit);
    those ``known`` to are not looked at. (A function of its own: the same loop inside :func:`escape_scores`
    took several times as long.)"""
    out = np.ones(positions.shape[0], np.bool_)
    for k in range(positions.shape[0]):
        if known[k]:
            continue
        for s in range(positions.shape[1]):
            if not _excess_at_most(
                positions[k, s, 0],
                positions[k, s, 1],
                segment_starts,
                segment_directions,
                segment_lengths,
                half_widths,
                limit,
            ):
                out[k] = False
                break
    return out


@compiled
def _furthest(positions, x0, y0):
    """np.max of ``np.hypot`` of the positions' (K, S, 2) offsets from (x0, y0), NaN first: hypot (about 20 ns)
    only of the squared distances within 1e-9 (relative) of the largest, the others' hypots being certainly
    smaller; of all of them where a square could have underflowed or overflowed, or is NaN."""
    k_count = positions.shape[0]
    s_count = positions.shape[1]
    squares = np.empty((k_count, s_count))
    largest = -math.inf
    for k in range(k_count):
        for s in range(s_count):
            dx = positions[k, s, 0] - x0
            dy = positions[k, s, 1] - y0
            squared = dx * dx + dy * dy
            squares[k, s] = squared
            if squared > largest:
                largest = squared
    cut = largest * (1.0 - 1e-9) if 1e-280 < largest < 1e280 else -math.inf
    furthest = -math.inf
    for k in range(k_count):
        for s in range(s_count):
            squared = squares[k, s]
            if squared >= cut or squared != squared:
                distance = math.hypot(positions[k, s, 0] - x0, positions[k, s, 1] - y0)
                if distance != distance:
                    return distance
                if distance > furthest:
                    furthest = distance
    return furthest


@compiled
def escape_headings(
    robot, obstacle_positions, obstacle_velocities, radii, growth, growth_until_s, row_turns, settings, steps
):
    """The first half of :func:`viapath.planning.viapath.escape.stop_or_escape`: whether standing still is free
    over the horizon (its ``contact_times`` of the robot's position at rest, with :func:`legs_first_contact`,
    as the compiled path checked it before), and the headings (T, steps + 1) of the escape's roll-outs
    (:func:`viapath.kinematics.rollout`), one row per distinct turn command ``row_turns`` (the fan's commands
    of one turn rate share them), before the first step and after each: numpy takes their sines and cosines
    for :func:`escape_scores`."""
    dt = settings[_E_DT]
    free = True
    n_count = obstacle_positions.shape[0]
    if n_count:
        starts = np.empty((1, 2))
        starts[0, 0] = robot[0]
        starts[0, 1] = robot[1]
        durations = np.empty(1)
        durations[0] = _minimum(_maximum(settings[_E_HORIZON] - 0.0, 0.0), settings[_E_STANDING_S])
        contact = legs_first_contact(
            starts,
            np.zeros(1),
            np.zeros((1, 2)),
            durations,
            obstacle_positions,
            obstacle_velocities,
            radii,
            growth,
            growth_until_s,
            np.zeros(1),
        )
        for j in range(n_count):
            if not math.isinf(contact[0, j]):
                free = False
    max_turn = settings[_E_MAX_TURN]
    turn0 = robot[4]
    heading0 = robot[2]
    headings = np.empty((row_turns.shape[0], steps + 1))
    for r in range(row_turns.shape[0]):
        w_cmd = _minimum(_maximum(row_turns[r], -max_turn), max_turn)
        headings[r, 0] = heading0
        turned = 0.0
        for s in range(steps):
            dw = settings[_E_TURN_STEP] * float(s + 1)
            turn = turn0 + _minimum(_maximum(w_cmd - turn0, -dw), dw)
            # np.cumsum: the first term as it is, then each added in order
            turned = turn * dt if s == 0 else turned + turn * dt
            headings[r, s + 1] = heading0 + turned
    return free, headings


@compiled
def _escape_roll_outs(robot, commands, turn_rows, sines, cosines, settings, steps):
    """The positions (K, steps, 2) of :func:`escape_scores`' roll-outs (:func:`viapath.kinematics.rollout`: the
    ramps of speed and turn rate, the exact arcs, the positions as running sums)."""
    k_count = commands.shape[0]
    dt = settings[_E_DT]
    max_speed = settings[_E_MAX_SPEED]
    x0 = robot[0]
    y0 = robot[1]
    speed0 = robot[3]
    turn0 = robot[4]
    max_turn = settings[_E_MAX_TURN]
    positions = np.empty((k_count, steps, 2))
    for k in range(k_count):
        row = turn_rows[k]
        v_cmd = _minimum(_maximum(commands[k, 0], 0.0), max_speed)
        w_cmd = _minimum(_maximum(commands[k, 1], -max_turn), max_turn)
        x_sum = 0.0
        y_sum = 0.0
        for s in range(steps):
            dv = settings[_E_SPEED_STEP] * float(s + 1)
            dw = settings[_E_TURN_STEP] * float(s + 1)
            speed = speed0 + _minimum(_maximum(v_cmd - speed0, -dv), dv)
            turn = turn0 + _minimum(_maximum(w_cmd - turn0, -dw), dw)
            sin_before = sines[row, s]
            sin_after = sines[row, s + 1]
            cos_before = cosines[row, s]
            cos_after = cosines[row, s + 1]
            if abs(turn) < 1e-9:
                dx = speed * dt * cos_before
                dy = speed * dt * sin_before
            else:
                radius = speed / turn
                dx = radius * (sin_after - sin_before)
                dy = -radius * (cos_after - cos_before)
            x_sum = dx if s == 0 else x_sum + dx
            y_sum = dy if s == 0 else y_sum + dy
            px = x0 + x_sum
            py = y0 + y_sum
            positions[k, s, 0] = px
            positions[k, s, 1] = py
    return positions


@compiled
def _escape_contacts_near(
    positions, robot, obstacle_positions, obstacle_velocities, radii, growth, growth_until_s, dt, steps, travel
):
    """:func:`escape_contacts` of the roll-outs with the people who could come within reach of them (the
    triangle-inequality bound, ``travel`` the furthest the roll-outs get from the robot): the first contact
    steps (K,), the smallest and last gaps (K, M) to the M people overlapped now, and their gaps now (M,)."""
    x0 = robot[0]
    y0 = robot[1]
    # The people who could come within reach during the roll-out.
    horizon = steps * dt
    n_count = obstacle_positions.shape[0]
    near = np.zeros(n_count, np.bool_)
    gap_now_all = np.empty(n_count)
    for j in range(n_count):
        gap = math.hypot(x0 - obstacle_positions[j, 0], y0 - obstacle_positions[j, 1]) - radii[j]
        gap_now_all[j] = gap
        grown = growth[j] * _minimum(horizon, growth_until_s[j])
        speed_j = math.hypot(obstacle_velocities[j, 0], obstacle_velocities[j, 1])
        near[j] = gap - grown - speed_j * horizon - travel <= 0
    near_positions = obstacle_positions[near]
    near_velocities = obstacle_velocities[near]
    gap_now = gap_now_all[near]
    overlapping = gap_now <= 0
    times = np.empty(steps)
    for s in range(steps):
        times[s] = dt * float(s + 1)
    first_step, gap_min, gap_last = escape_contacts(
        positions,
        times,
        near_positions,
        near_velocities,
        radii[near],
        growth[near],
        growth_until_s[near],
        overlapping,
        steps,
    )
    gap_overlapped = gap_now[overlapping]
    return first_step, gap_min, gap_last, gap_overlapped


@compiled
def escape_scores(
    robot,
    commands,
    turn_rows,
    sines,
    cosines,
    obstacle_positions,
    obstacle_velocities,
    radii,
    growth,
    growth_until_s,
    segment_starts,
    segment_directions,
    segment_lengths,
    half_widths,
    subgoal,
    settings,
    steps,
    calm,
):
    """:func:`viapath.planning.viapath.escape.escape_scores` compiled, operation for operation: the roll-outs of
    the K commands (:func:`viapath.kinematics.rollout`: the ramps of speed and turn rate, the exact arcs, the
    positions as running sums), their corridor excess (:func:`_excess`), the people who could come within
    reach (the triangle-inequality bound), the contacts (:func:`escape_contacts`), the separation from the
    people overlapped now (summed as np.sum does: :func:`viapath.compiled.sums.pairwise_sum`), the progress towards the subgoal and
    the score. Returns the ends (K, 2) and the scores (K,).

    ``sines`` and ``cosines`` are numpy's, of :func:`escape_headings`' rows (command k's row is
    ``turn_rows[k]``). ``calm``: a calm escape with last cycle's command (the continuity term)."""
    k_count = commands.shape[0]
    dt = settings[_E_DT]
    x0 = robot[0]
    y0 = robot[1]
    max_turn = settings[_E_MAX_TURN]
    tolerance = settings[_E_TOLERANCE]
    bound = settings[_E_BOUND]
    positions = _escape_roll_outs(robot, commands, turn_rows, sines, cosines, settings, steps)
    # all(excess <= tolerance); np.max(excess) <= bound is all(excess <= bound), NaN included: with the bound
    # at least the tolerance (as the caller sets it), true of every roll-out inside
    inside = _roll_outs_within(
        positions,
        segment_starts,
        segment_directions,
        segment_lengths,
        half_widths,
        tolerance,
        np.zeros(k_count, np.bool_),
    )
    within_bound = _roll_outs_within(
        positions,
        segment_starts,
        segment_directions,
        segment_lengths,
        half_widths,
        bound,
        inside if bound >= tolerance else np.zeros(k_count, np.bool_),
    )
    travel = _furthest(positions, x0, y0)

    first_step, gap_min, gap_last, gap_overlapped = _escape_contacts_near(
        positions, robot, obstacle_positions, obstacle_velocities, radii, growth, growth_until_s, dt, steps, travel
    )
    m_count = gap_overlapped.shape[0]
    terms = np.empty(m_count)

    toward_x = subgoal[0] - x0
    toward_y = subgoal[1] - y0
    norm = math.hypot(toward_x, toward_y)
    norm = 1e-9 if norm < 1e-9 else norm  # Python's max(norm, 1e-9)
    toward_x = toward_x / norm
    toward_y = toward_y / norm
    ends = np.empty((k_count, 2))
    score = np.empty(k_count)
    for k in range(k_count):
        separation = 0.0
        if m_count:
            for column in range(m_count):
                deeper = gap_min[k, column] - gap_overlapped[column]
                terms[column] = _minimum(deeper, 0.0) + _minimum(gap_last[k, column], 0.0)
            separation = 0.0 + pairwise_sum(terms, 0, m_count)
        time_to_contact = first_step[k] * dt
        free = time_to_contact >= steps * dt
        end_x = positions[k, steps - 1, 0]
        end_y = positions[k, steps - 1, 1]
        ends[k, 0] = end_x
        ends[k, 1] = end_y
        progress = ((end_x - x0) * toward_x + (end_y - y0) * toward_y) / settings[_E_ESCAPE_S]
        speed = commands[k, 0]
        value = (
            1e2 * separation
            + 20.0 * (1.0 if free else 0.0)
            + 2.0 * (1.0 if inside[k] else 0.0)
            + time_to_contact
            - (0.005 if free else 0.5) * speed
            + 0.01 * progress
        )
        if calm:
            change = (
                abs(speed - settings[_E_PREVIOUS_SPEED]) / settings[_E_TOP]
                + abs(commands[k, 1] - settings[_E_PREVIOUS_TURN]) / max_turn
            )
            value = value - settings[_E_CONTINUITY] * _minimum(change, 1.0)
        score[k] = value if (within_bound[k] or speed == 0.0) else -math.inf
    return ends, score


# The kernels' records (tuples, so that their pieces take a few names instead of a dozen arguments each):
# obstacles (positions, velocities, radii, growth, growth until), as legs_first_contact takes them;
# corridor (segment starts, directions, lengths, half widths); goal (subgoal, how far short of it legs end,
# continuation, braking envelope, subgoal index, corridor check spacing, corridor tolerance).


@compiled
def _goal_legs_of(starts, start_times, speeds, horizon_s, goal, obstacles, corridor):
    """:func:`goal_legs` on its records."""
    subgoal, stop_short_m, continuation, envelope, _, _, _ = goal
    obstacle_positions, obstacle_velocities, radii, growth, growth_until_s = obstacles
    k_count = starts.shape[0]
    n_count = obstacle_positions.shape[0]
    two = continuation.shape[0] == 3 and n_count > 0
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
    contact = np.empty((k_count, n_count))
    if n_count > 0:
        checked = np.empty(legs)
        leg_radii = np.empty(legs)
        half_accel = 0.5 * envelope[0]
        for m in range(legs):
            checked[m] = _clip(horizon_s - leg_times[m], 0.0, leg_durations[m])
            if envelope[0] > 0:
                stop_s = envelope[1] + math.hypot(leg_velocities[m, 0], leg_velocities[m, 1]) / envelope[2]
                leg_radii[m] = half_accel * (stop_s * stop_s)
            else:
                leg_radii[m] = 0.0
        both = legs_first_contact(
            leg_starts,
            leg_times,
            leg_velocities,
            checked,
            obstacle_positions,
            obstacle_velocities,
            radii,
            growth,
            growth_until_s,
            leg_radii,
        )
        for k in range(k_count):
            for j in range(n_count):
                value = both[k, j]
                if two:
                    later = both[k_count + k, j] + durations[k]
                    if value != value or later != later:
                        value = math.nan
                    elif later < value:
                        value = later
                contact[k, j] = value
    # Free: no contact, then inside. The corridor check only when some leg has no contact (a blocked batch,
    # the usual case in the tree, needs none); then of all the legs, as the sample spacing is the longest's.
    free = np.empty(k_count, np.bool_)
    any_clear = False
    for k in range(k_count):
        ok = True
        for j in range(n_count):
            if not math.isinf(contact[k, j]):
                ok = False
                break
        free[k] = ok
        any_clear = any_clear or ok
    if any_clear:
        inside = _goal_legs_inside_all(corridor, starts, goal)
        for k in range(k_count):
            free[k] = free[k] and inside[k]
    return directions, lengths, free, contact


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
):
    """The numba twin of :meth:`viapath.planning.viapath.checks.LegChecks.goal_legs`, whole: the straight
    legs from K nodes to the subgoal (with the continuation past an intermediate subgoal as K more legs),
    their first contacts with the braking envelope kept, and the corridor check (:func:`goal_legs_inside`,
    then :func:`legs_inside` for the legs it leaves open, as the backend does). One call instead of
    three kernels and some thirty small array operations; called a few times every cycle.

    ``continuation`` is (dx, dy, length) or empty (none); ``envelope`` is (person accel, period, robot
    accel), accel 0 for none. Returns (directions (K, 2), lengths (K,), free (K,), contact (K, N))."""
    goal = (subgoal, stop_short_m, continuation, envelope, subgoal_index, spacing_m, tolerance_m)
    obstacles = (obstacle_positions, obstacle_velocities, radii, growth, growth_until_s)
    corridor = (segment_starts, segment_directions, segment_lengths, half_widths)
    return _goal_legs_of(starts, start_times, speeds, horizon_s, goal, obstacles, corridor)


@compiled
def _goal_legs_inside_all(corridor, starts, goal):
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


# -- the candidate tree (candidates.grow) in one call --------------------------------------------------------

# Columns of the node store: floats, then integers.
_X, _Y, _T, _V, _LENGTH, _FX, _FY = N_X, N_Y, N_TIME, N_SPEED, N_LENGTH, N_FIRST_X, N_FIRST_Y
_SLOW_S, _SLOW_V, _GOAL = N_SLOW_S, N_SLOW_SPEED, N_TO_GOAL
_PARENT, _WAY0, _WAY1, _WAY2, _LEAF = N_PARENT, N_OBSTACLE, N_SIDE, N_ROOT, N_LEAF
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


@compiled
def _legs_free(starts, start_times, velocities, durations, horizon_s, obstacles):
    """LegChecks.legs_free: no contact up to the horizon, plain radii (no braking envelope). Leg by leg, up to
    its first contact: whether any contact is finite (or NaN) is all that is asked. ``obstacles``: the record
    (positions, velocities, radii, growth, growth until)."""
    obstacle_positions, obstacle_velocities, radii, growth, growth_until_s = obstacles
    k_count = starts.shape[0]
    checked = np.empty(k_count)
    for k in range(k_count):
        checked[k] = _clip(horizon_s - start_times[k], 0.0, durations[k])
    cylinder_only = _cylinder_only(growth, growth_until_s)
    free = np.empty(k_count, np.bool_)
    for k in range(k_count):
        ok = True
        for j in range(obstacle_positions.shape[0]):
            # leg radius 0.0, as legs_first_contact with np.zeros(k_count)
            if not math.isinf(
                _leg_contact(
                    starts,
                    start_times,
                    velocities,
                    checked,
                    obstacle_positions,
                    obstacle_velocities,
                    radii,
                    growth,
                    growth_until_s,
                    0.0,
                    cylinder_only,
                    k,
                    j,
                )
            ):
                ok = False
                break
        free[k] = ok
    return free


@compiled
def _legs_inside_of(corridor, starts, ends, spacing_m, tolerance_m):
    """:func:`legs_inside` with the corridor's record unpacked."""
    segment_starts, segment_directions, segment_lengths, half_widths = corridor
    return legs_inside(
        segment_starts, segment_directions, segment_lengths, half_widths, starts, ends, spacing_m, tolerance_m
    )


@compiled
def _root_nodes(position, speeds, root_directions, root_lengths, root_free):
    """The tree's first nodes (a store with room to grow): the roots, one per speed, at the robot, now; a root
    whose goal leg is free is a leaf."""
    s_count = speeds.shape[0]
    nf = np.empty((4 * s_count + 32, NODE_FLOATS))
    ni = np.empty((4 * s_count + 32, NODE_INTEGERS), np.int64)
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
    """The slow/wait legs along the straight leg (_slow_candidates): 0 (waiting), the creep speed (when it is
    above 0, below the nominal speed and not in the set: creep_speeds) and each speed below the nominal one, for
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


@compiled
def _slow_nodes(
    nf, ni, m, position, speeds, nominal_index, slow_times, creep, horizon_s, slow_obstacles, obstacles, goal, corridor
):
    """Slow down, creep or wait along the straight leg, then on at the nominal speed or the slowest faster speed
    whose goal leg is free (_slow_candidates): the slow legs free of the people (at their slow radii:
    ``slow_obstacles``) with a free goal leg, added as leaves."""
    s_count = speeds.shape[0]
    nominal = speeds[nominal_index]
    dx, dy, durations, slows, c = _slow_legs(position, goal[0], speeds, nominal, slow_times, creep)
    starts = np.empty((c, 2))
    velocities = np.empty((c, 2))
    for k in range(c):
        starts[k, 0] = position[0]
        starts[k, 1] = position[1]
        velocities[k, 0] = dx * slows[k]
        velocities[k, 1] = dy * slows[k]
    free = _legs_free(starts, np.zeros(c), velocities, durations[:c], horizon_s, slow_obstacles)
    after_count = 0
    for i in range(s_count):
        if speeds[i] >= nominal - 1e-9:
            after_count += 1
    kept = 0
    for k in range(c):
        if free[k]:
            kept += 1
    if not kept:
        return nf, ni, m
    legs = kept * after_count
    ends = np.empty((legs, 2))
    times = np.empty(legs)
    after = np.empty(legs)
    slow_v = np.empty(legs)
    q = 0
    for k in range(c):
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
    _, lengths, goal_free, _ = _goal_legs_of(ends, times, after, math.inf, goal, obstacles, corridor)
    taken = False
    for q in range(legs):
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
def _corner_nodes(nf, ni, m, position, speeds, path, horizon_s, goal, obstacles, corridor):
    """The path's corners between the robot and the subgoal as via points (_corner_nodes): one leg per speed
    and corner, added when free of the people and inside the corridor. ``path``: the waypoints and the
    robot's segment."""
    waypoints, robot_segment = path
    _, _, _, _, subgoal_index, spacing_m, tolerance_m = goal
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
    good = _legs_free(starts, np.zeros(legs), velocities, durations, horizon_s, obstacles)
    inside = _legs_inside_of(corridor, starts, targets, spacing_m, tolerance_m)
    for q in range(legs):
        if good[q] and inside[q]:
            root = _ZERO  # np.searchsorted(speeds, speed): the root node of that speed
            while root < s_count and speeds[root] < speed_of[q]:
                root += 1
            nf, ni, m = _add(
                nf,
                ni,
                m,
                targets[q, 0],
                targets[q, 1],
                durations[q],
                speed_of[q],
                root,
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
    max_root_obstacles, when there are more pairs than that; _root_pairs), deeper the first hit. Returns the
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


@compiled
def _via_legs(nf, branch, via_radii, envelope, horizon_s, obstacles):
    """The via points of each pair (_via_children): both sides, both roots. The pairs' options as via_options
    gives them, its arithmetic (_via_pair) on the nodes and obstacles themselves: no copies of them per pair.
    Returns, per leg (the first ``count``): its pair, its option, its duration, its start and start time, its
    velocity and its via point; and ``count``. ``branch``: :func:`_branch_pairs`' pairs."""
    pair_nodes, pair_obstacles, pairs = branch
    obstacle_positions, obstacle_velocities, _, growth, growth_until_s = obstacles
    half_accel = 0.5 * envelope[0]
    pair = np.empty(4 * pairs, np.int64)
    option = np.empty(4 * pairs, np.int64)
    t_k = np.empty(4 * pairs)
    starts_k = np.empty((4 * pairs, 2))
    times_k = np.empty(4 * pairs)
    leg_velocity = np.empty((4 * pairs, 2))
    via = np.empty((4 * pairs, 2))
    t_via = np.empty(4)
    w_via = np.empty((2, 2))
    max_time_s = 3 * horizon_s
    count = 0
    for p in range(pairs):
        node = pair_nodes[p]
        j = pair_obstacles[p]
        sx = nf[node, _X]
        sy = nf[node, _Y]
        t0 = nf[node, _T]
        speed = nf[node, _V]
        if envelope[0] > 0:
            stop_s = envelope[1] + speed / envelope[2]
            margin = half_accel * (stop_s * stop_s)
        else:
            margin = 0.0
        ovx = obstacle_velocities[j, 0]
        ovy = obstacle_velocities[j, 1]
        if not _via_pair(
            sx,
            sy,
            t0,
            speed,
            obstacle_positions[j, 0],
            obstacle_positions[j, 1],
            ovx,
            ovy,
            via_radii[j],
            growth[j],
            growth_until_s[j],
            margin,
            t_via,
            w_via,
        ):
            continue
        for o in range(4):
            t = t_via[o]
            if t <= max_time_s:
                pair[count] = p
                option[count] = o
                t_k[count] = t
                starts_k[count, 0] = sx
                starts_k[count, 1] = sy
                times_k[count] = t0
                leg_velocity[count, 0] = (w_via[o % 2, 0] + ovx * t) / t
                leg_velocity[count, 1] = (w_via[o % 2, 1] + ovy * t) / t
                via[count, 0] = sx + leg_velocity[count, 0] * t
                via[count, 1] = sy + leg_velocity[count, 1] * t
                count += 1
    return pair, option, t_k, starts_k, times_k, leg_velocity, via, count


@compiled
def _via_children(nf, ni, m, depth, branch, via, horizon_s, goal, obstacles, corridor):
    """The pairs' children (_via_children): the legs to their via points (:func:`_via_legs`) free of the people
    and inside the corridor, added below their nodes (a root's child starts the way round: obstacle id, side,
    root; deeper ones keep their parent's). ``branch``: :func:`_branch_pairs`' pairs."""
    pair_nodes, pair_obstacles, _ = branch
    via_radii, ids = via
    _, _, _, envelope, _, spacing_m, tolerance_m = goal
    legs = _via_legs(nf, branch, via_radii, envelope, horizon_s, obstacles)
    pair, option, t_k, starts_k, times_k, leg_velocity, via, count = legs
    if not count:
        return nf, ni, m
    good = _legs_free(starts_k[:count], times_k[:count], leg_velocity[:count], t_k[:count], horizon_s, obstacles)
    kept = 0
    for q in range(count):
        if good[q]:
            kept += 1
    if not kept:
        return nf, ni, m
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
    inside = _legs_inside_of(corridor, good_starts, good_vias, spacing_m, tolerance_m)
    g = 0
    for q in range(count):
        if not good[q]:
            continue
        ok = inside[g]
        g += 1
        if not ok:
            continue
        p = pair[q]
        parent = pair_nodes[p]
        speed = nf[parent, _V]
        if depth == 0:
            fx = leg_velocity[q, 0] / speed
            fy = leg_velocity[q, 1] / speed
            way0 = ids[pair_obstacles[p]]
            way1 = _SIDES[option[q]]
            way2 = _ROOTS[option[q]]
        else:
            fx = nf[parent, _FX]
            fy = nf[parent, _FY]
            way0 = ni[parent, _WAY0]
            way1 = ni[parent, _WAY1]
            way2 = ni[parent, _WAY2]
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


@compiled
def grow(position, speeds, nominal_index, roots, via, slow, horizon_s, goal, obstacles, corridor, tree):
    """The numba twin of :func:`viapath.planning.viapath.candidates.grow`: the same nodes in the same order
    (roots, slow/wait, corners, then the via-point children depth by depth), so the candidates, their
    order and so every tie are the same. Returns the node store, floats (M, 10) and integers (M, 5), in
    the columns named above; a node is a leaf (a complete candidate) when its goal leg is free.

    Takes records (tuples): ``roots`` (directions, lengths, free, contact of the root legs: :func:`goal_legs`'),
    ``via`` (via radii, ids), ``slow`` (slow radii, growth, growth until, slow times, creep speed), ``goal``, ``obstacles``
    and ``corridor`` (the kernels' records, named above :func:`_goal_legs_of`), ``tree`` (the waypoints, the robot's segment, whether slow/wait
    candidates are grown, the depth, the most obstacles a root branches on)."""
    waypoints, robot_segment, slow_enabled, max_depth, max_root_obstacles = tree
    subgoal_index = goal[4]
    root_directions, root_lengths, root_free, root_contact = roots
    obstacle_positions, obstacle_velocities, _, _, _ = obstacles
    slow_radii, slow_growth, slow_growth_until_s, slow_times, creep = slow
    s_count = speeds.shape[0]
    n_count = obstacle_positions.shape[0]
    nf, ni, m = _root_nodes(position, speeds, root_directions, root_lengths, root_free)
    here = np.empty((1, 2))
    here[0, 0] = position[0]
    here[0, 1] = position[1]
    straight_inside = _goal_legs_inside_all(corridor, here, goal)[0]
    if slow_enabled and n_count > 0 and straight_inside:
        slow_obstacles = (obstacle_positions, obstacle_velocities, slow_radii, slow_growth, slow_growth_until_s)
        nf, ni, m = _slow_nodes(
            nf,
            ni,
            m,
            position,
            speeds,
            nominal_index,
            slow_times,
            creep,
            horizon_s,
            slow_obstacles,
            obstacles,
            goal,
            corridor,
        )
    frontier_start = 0
    frontier_end = s_count
    free_now = root_free.copy()
    contact_now = root_contact
    for depth in range(max_depth):
        batch = m
        if depth == 0 and robot_segment + 1 < subgoal_index and not straight_inside:
            path = (waypoints, robot_segment)
            nf, ni, m = _corner_nodes(nf, ni, m, position, speeds, path, horizon_s, goal, obstacles, corridor)
        if n_count > 0:
            branch = _branch_pairs(
                free_now, contact_now, frontier_start, frontier_end, n_count, depth, max_root_obstacles
            )
            if branch[2]:
                nf, ni, m = _via_children(nf, ni, m, depth, branch, via, horizon_s, goal, obstacles, corridor)
        if m == batch:
            break
        # The goal legs of the new frontier: the free ones complete candidates.
        frontier_start = batch
        frontier_end = m
        starts = np.ascontiguousarray(nf[batch:m, _X : _Y + 1])
        _, lengths, free_now, contact_now = _goal_legs_of(
            starts, nf[batch:m, _T].copy(), nf[batch:m, _V].copy(), horizon_s, goal, obstacles, corridor
        )
        for r in range(m - batch):
            if free_now[r]:
                ni[batch + r, _LEAF] = 1
                nf[batch + r, _GOAL] = lengths[r]
    return nf[:m].copy(), ni[:m].copy()


# -- the choice (planner._choose) in one call, :func:`choose`, of two halves: roots, step 1 and the tree
# (:func:`choose_tree`); then Eq. 1's critics, the order and the motion-limit checks (:func:`choose_candidate`).
# Between them the candidates' angles, by libm's atan2 as the reference takes them (geometry.angles_of).

# The slots of the settings arrays: viapath.compiled.slots (C_* integers, F_* floats), imported at the top.


@compiled
def _wrap(angle):
    """:func:`viapath.geometry.wrap_angle` of a scalar (np.mod's sign convention is Python's %)."""
    turned = math.pi - angle
    if 0.0 <= turned < 2.0 * math.pi:  # % leaves it as it is (fmod exact; ±0.0 gives pi either way): skip it
        return math.pi - turned
    return math.pi - (turned % (2.0 * math.pi))


@compiled
def _clear(
    positions, count, dt, robot_x, robot_y, obstacle_positions, obstacle_velocities, radii, growth, growth_until_s
):
    """LegChecks.clear of the first ``count`` positions (one per ``dt`` from now)."""
    for j in range(obstacle_positions.shape[0]):
        now = math.hypot(robot_x - obstacle_positions[j, 0], robot_y - obstacle_positions[j, 1]) - 1e-3
        for s in range(count):
            t = dt * (s + 1)
            cx = obstacle_positions[j, 0] + obstacle_velocities[j, 0] * t
            cy = obstacle_positions[j, 1] + obstacle_velocities[j, 1] * t
            until = growth_until_s[j]
            capped = until if until != until else (t if t < until else until)  # np.minimum keeps a NaN
            reach = radii[j] + growth[j] * capped
            limit = reach if (reach != reach or reach < now) else now  # np.minimum, NaN first
            if now != now:
                limit = now
            dx = positions[s, 0] - cx
            dy = positions[s, 1] - cy
            # hypot >= limit by the squared distance outside a ±1e-9 band (as _within), else by hypot itself:
            # NaN offsets or limits, and limits whose square could underflow or overflow, go to hypot.
            if 1e-140 < limit < 1e140:
                squared = dx * dx + dy * dy
                above = limit * (1.0 + 1e-9)
                if squared > above * above:
                    continue
                below = limit * (1.0 - 1e-9)
                if squared < below * below:
                    return False
            if not math.hypot(dx, dy) >= limit:
                return False
    return True


@compiled
def clear_positions(
    positions, dt, robot_x, robot_y, obstacle_positions, obstacle_velocities, radii, growth, growth_until_s
):
    """LegChecks.clear of a whole roll-out (one position per ``dt`` from now): the choice's own :func:`_clear`,
    for the planner's stepwise cycles (static geometry in view)."""
    return _clear(
        positions,
        positions.shape[0],
        dt,
        robot_x,
        robot_y,
        obstacle_positions,
        obstacle_velocities,
        radii,
        growth,
        growth_until_s,
    )


@compiled
def _follows(robot, target_x, target_y, angle, speed, settings, steps, obstacles, corridor):
    """follow.can_follow: 0 cannot, 1 can, 2 can after turning on the spot first. ``angle``: atan2 of the
    offset from the robot to the target; ``obstacles`` and ``corridor``: :func:`grow`'s records."""
    obstacle_positions, obstacle_velocities, radii, growth, growth_until_s = obstacles
    segment_starts, segment_directions, segment_lengths, half_widths = corridor
    ox = target_x - robot[0]
    oy = target_y - robot[1]
    heading_error = abs(_wrap(angle - robot[2]))
    speed_change = abs(speed - robot[3])
    dt = settings[F_DT]
    if math.hypot(ox, oy) < 1e-6 or (
        heading_error <= settings[F_ROLLOUT_HEADING] and speed_change <= settings[F_ACCEL] * dt * 2
    ):
        return 1
    positions = track(
        robot[0],
        robot[1],
        robot[2],
        robot[3],
        robot[4],
        target_x,
        target_y,
        speed,
        settings[F_SPEED],
        settings[F_TURN_RATE],
        settings[F_ACCEL],
        settings[F_TURN_ACCEL],
        dt,
        steps,
        settings[F_GAIN],
    )
    if not _clear(
        positions, steps, dt, robot[0], robot[1], obstacle_positions, obstacle_velocities, radii, growth, growth_until_s
    ):
        return 0
    inside = True
    for s in range(steps):
        if not _excess_at_most(
            positions[s, 0],
            positions[s, 1],
            segment_starts,
            segment_directions,
            segment_lengths,
            half_widths,
            settings[F_TOLERANCE],
        ):
            inside = False
            break
    if inside:
        return 1
    turn_s = heading_error / settings[F_TURN_RATE] + 1.0
    count = max(1, int(math.ceil(turn_s / dt)))
    if heading_error > settings[F_TURN_IN_PLACE]:
        standing = np.empty((count, 2))
        for s in range(count):
            standing[s, 0] = robot[0]
            standing[s, 1] = robot[1]
        if _clear(
            standing,
            count,
            dt,
            robot[0],
            robot[1],
            obstacle_positions,
            obstacle_velocities,
            radii,
            growth,
            growth_until_s,
        ):
            return 2
    return 0


@compiled
def _leaf_facts(robot, subgoal, nf, ni):
    """What :func:`choose_tree` hands back of the tree's leaves: ``found`` (status, 0, then the K leaves' nodes)
    and ``facts`` (6, K), as it says."""
    k_count = 0
    for m in range(ni.shape[0]):
        if ni[m, _LEAF]:
            k_count += 1
    found = np.empty(2 + k_count, np.int64)
    facts = np.empty((6, k_count))
    k = 0
    for m in range(ni.shape[0]):
        if not ni[m, _LEAF]:
            continue
        found[2 + k] = m
        # _plan_of's target: the subgoal for slow/wait and straight candidates, else the second point of
        # the polyline (the node below the root).
        target_x = subgoal[0]
        target_y = subgoal[1]
        if nf[m, _SLOW_S] <= 0 and ni[m, _PARENT] >= 0:
            node = m
            while ni[node, _PARENT] >= 0:
                target_x = nf[node, _X]
                target_y = nf[node, _Y]
                node = ni[node, _PARENT]
        facts[0, k] = nf[m, _FY]
        facts[1, k] = nf[m, _FX]
        facts[2, k] = target_y - robot[1]
        facts[3, k] = target_x - robot[0]
        facts[4, k] = target_x
        facts[5, k] = target_y
        k += 1
    found[0] = CANDIDATES if k_count else NO_CANDIDATE
    found[1] = 0
    return found, facts


@compiled
def choose_tree(
    robot, speeds, subgoal, obstacles, via, slow, continuation, envelope, corridor, waypoints, settings, integers
):
    """The first half of the viapath planner's ``_choose`` in one call: the root legs (:func:`goal_legs`), the
    paper's step 1 (the free straight leg at the nominal speed, if the robot can follow it: follow.can_follow),
    else the candidate tree (:func:`grow`). ``robot`` is (x, y, heading, speed, turn rate); ``obstacles``,
    ``via``, ``slow`` and ``corridor`` are :func:`grow`'s records (:func:`choose` makes them of its
    arguments); ``settings`` and ``integers`` hold the scalars (their slots: :mod:`viapath.compiled.slots`).

    Returns (found, floats, integers: grow's node store, facts). ``found`` is (NO_CANDIDATE / STEP_ONE /
    CANDIDATES, step 1 turns on the spot first, then the K leaves: the candidates' nodes); ``facts`` (6, K)
    is each candidate's first direction (y, x) and its target's offset from the robot (y, x), for atan2,
    and the target (x, y): the point it steers for first. (Few arrays: each one returned costs about a
    microsecond.)"""
    result = np.zeros(2, np.int64)
    s_count = speeds.shape[0]
    nominal_index = integers[C_NOMINAL]
    horizon_s = settings[F_HORIZON]
    goal = (
        subgoal,
        settings[F_STOP_SHORT],
        continuation,
        envelope,
        integers[C_SUBGOAL],
        settings[F_SPACING],
        settings[F_TOLERANCE],
    )
    starts = np.empty((s_count, 2))
    for i in range(s_count):
        starts[i, 0] = robot[0]
        starts[i, 1] = robot[1]
    roots = _goal_legs_of(starts, np.zeros(s_count), speeds, horizon_s, goal, obstacles, corridor)
    if roots[2][nominal_index] and integers[C_TRY_STRAIGHT] and not integers[C_ONLY]:
        straight_angle = math.atan2(subgoal[1] - robot[1], subgoal[0] - robot[0])
        follows = _follows(
            robot,
            subgoal[0],
            subgoal[1],
            straight_angle,
            speeds[nominal_index],
            settings,
            integers[C_STEPS],
            obstacles,
            corridor,
        )
        if follows:
            result[0] = STEP_ONE
            result[1] = follows == 2
            return result, np.empty((0, NODE_FLOATS)), np.empty((0, NODE_INTEGERS), np.int64), np.empty((6, 0))
    tree = (waypoints, integers[C_SEGMENT], integers[C_SLOW] != 0, integers[C_DEPTH], integers[C_ROOT_LIMIT])
    nf, ni = grow(robot[:2].copy(), speeds, nominal_index, roots, via, slow, horizon_s, goal, obstacles, corridor, tree)
    found, facts = _leaf_facts(robot, subgoal, nf, ni)
    return found, nf, ni, facts


@compiled
def _before(a, b):
    """np.argsort's order of two costs: NaN after everything (ties are kept in index order by the caller)."""
    if b != b:
        return a == a
    return a < b


@compiled
def choose_candidate(robot, nf, ni, found, facts, angles, obstacles, corridor, settings, integers):
    """The second half of ``_choose`` up to its shield check: Eq. 1's critics (:mod:`.critics`, each term as
    there, summed in :func:`.critics.critics_for`'s order), with ``only_way`` the other ways priced out, the
    cheapest-first order (np.argsort's, stable) of the first ``max_rollouts`` candidates (and at least two,
    for the runner-up), and follow.can_follow of each in that order until one passes. ``found`` and ``facts``
    are :func:`choose_tree`'s, ``angles`` (2, K) atan2 of its facts; ``obstacles`` and ``corridor``
    :func:`grow`'s records.

    Returns (ranking, costs). ``ranking`` is (the rank that follows or -1, R: the ranks in order (0: with
    only_way, no candidate goes that way), the order (R), can_follow of each rank tried (R): 0/1/2, -1 not
    tried); ``costs`` (8, K) the critics' terms, their sum and the sum with only_way applied."""
    k_count = found.shape[0] - 2
    leaves = found[2:]
    costs = np.empty((8, k_count))
    terms = costs[:6]
    raw_total = costs[6]
    total = costs[7]
    nominal = settings[F_NOMINAL]
    only = integers[C_ONLY] != 0
    any_finite = False
    for k in range(k_count):
        m = leaves[k]
        length = nf[m, _LENGTH] + nf[m, _GOAL]
        speed = nf[m, _V]
        slow_s = nf[m, _SLOW_S]
        slow_v = nf[m, _SLOW_V]
        driven_s = (length - slow_v * slow_s) / speed
        travel_s = slow_s + driven_s
        terms[0, k] = settings[F_K1] * length
        terms[1, k] = settings[F_K2] * travel_s
        error = (slow_s * abs(slow_v - nominal) + driven_s * abs(speed - nominal)) / travel_s
        terms[2, k] = settings[F_K3] * error + settings[F_STANDING] * (slow_s if slow_v <= 0.0 else 0.0)
        theta = abs(_wrap(angles[0, k] - robot[2]))
        terms[3, k] = settings[F_K4] * (theta * (180.0 / math.pi) if integers[C_DEGREES] else theta)
        side = ni[m, _WAY1]
        terms[4, k] = settings[F_SIDE] * (1.0 if (side != 0 and side != integers[C_PREFERRED]) else 0.0)
        if integers[C_PREVIOUS]:
            same_way = (
                ni[m, _WAY0] == integers[C_PREV_OBSTACLE]
                and ni[m, _WAY1] == integers[C_PREV_SIDE]
                and ni[m, _WAY2] == integers[C_PREV_ROOT]
            )
            same_speed = np.rint(speed * 1000) == integers[C_PREV_MMPS]
            bonus = (1.0 if same_way else 0.0) + 0.5 * (1.0 if (same_way and same_speed) else 0.0)
            terms[5, k] = -(settings[F_HYSTERESIS] * bonus)
        else:
            terms[5, k] = 0.0
        value = terms[0, k] + terms[1, k]
        for c in range(2, 6):
            value = value + terms[c, k]
        raw_total[k] = value
        if only and not (
            ni[m, _WAY0] == integers[C_ONLY_OBSTACLE]
            and ni[m, _WAY1] == integers[C_ONLY_SIDE]
            and ni[m, _WAY2] == integers[C_ONLY_ROOT]
        ):
            value = math.inf
        total[k] = value
        if math.isfinite(value):
            any_finite = True
    if only and not any_finite:
        ranking = np.zeros(2, np.int64)
        ranking[0] = -1
        return ranking, costs

    ranks = min(k_count, max(integers[C_ROLLOUTS], 2))
    ranking = np.empty(2 + 2 * ranks, np.int64)
    ranking[0] = -1
    ranking[1] = ranks
    order = ranking[2 : 2 + ranks]
    follow = ranking[2 + ranks :]
    taken = np.zeros(k_count, np.bool_)
    for r in range(ranks):
        best = -1
        for k in range(k_count):
            if not taken[k] and (best < 0 or _before(total[k], total[best])):
                best = k
        taken[best] = True
        order[r] = best
    follow[:] = -1
    for r in range(min(ranks, integers[C_ROLLOUTS])):
        k = order[r]
        if not math.isfinite(total[k]):
            break
        m = leaves[k]
        speed = nf[m, _SLOW_V] if nf[m, _SLOW_S] > 0 else nf[m, _V]
        follow[r] = _follows(
            robot,
            facts[4, k],
            facts[5, k],
            angles[1, k],
            speed,
            settings,
            integers[C_STEPS],
            obstacles,
            corridor,
        )
        if follow[r]:
            ranking[0] = r
            break
    return ranking, costs


@compiled
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
    integers,
):
    """``_choose`` up to its shield check in one call (each array handed back to Python costs about a
    microsecond): :func:`choose_tree`, then, when it found candidates, their angles and :func:`choose_candidate`.
    Takes :func:`choose_tree`'s arguments; returns (found, floats, integers: the node store, costs): ``found``
    is :func:`choose_tree`'s, followed by :func:`choose_candidate`'s ranking when it says CANDIDATES (one array
    fewer to hand back), ``costs`` (8, K) :func:`choose_candidate`'s, empty unless CANDIDATES."""
    obstacles = (obstacle_positions, obstacle_velocities, radii, growth, growth_until_s)
    corridor = (segment_starts, segment_directions, segment_lengths, half_widths)
    found, nf, ni, facts = choose_tree(
        robot,
        speeds,
        subgoal,
        obstacles,
        (via_radii, ids),
        (slow_radii, slow_growth, slow_growth_until_s, slow_times, settings[F_CREEP]),
        continuation,
        envelope,
        corridor,
        waypoints,
        settings,
        integers,
    )
    if found[0] != CANDIDATES:
        return found, nf, ni, np.empty((8, 0))
    k_count = facts.shape[1]
    angles = np.empty((2, k_count))
    for k in range(k_count):
        angles[0, k] = math.atan2(facts[0, k], facts[1, k])
        angles[1, k] = math.atan2(facts[2, k], facts[3, k])
    ranking, costs = choose_candidate(robot, nf, ni, found, facts, angles, obstacles, corridor, settings, integers)
    found_and_ranking = np.empty(found.shape[0] + ranking.shape[0], np.int64)
    found_and_ranking[: found.shape[0]] = found
    found_and_ranking[found.shape[0] :] = ranking
    return found_and_ranking, nf, ni, costs
