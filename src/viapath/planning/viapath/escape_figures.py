"""The escape's figures (beyond the paper, which assumes some candidate is free: :mod:`.escape`)
in two compiled calls: the standing check and the fan's headings (:func:`escape_headings`); then, with numpy's
sines and cosines of those headings, the roll-outs, their corridor excess, the people near, the contacts and the
score (:func:`escape_scores`). :mod:`.escape` makes the choice among them.

Choices:
* numpy takes the sines and cosines between the two calls (as kinematics.rollout does, np.sin and np.cos of arrays:
  numpy may dispatch its own SIMD routines for them, the compiled code calls libm), and the sums are numpy's pairwise
  summation (:func:`viapath.sums.pairwise_sum`): the figures they were first specified with, kept bit for bit.
* hypot costs about 20 ns here; where only the sign of ``hypot - limit`` matters, the squared distance decides
  outside a band of ±1e-9 around the limit (:func:`_within`, :func:`_furthest`).
"""

from __future__ import annotations

import math

import numpy as np

from viapath.jit import compiled
from viapath.planning.viapath.legs import legs_first_contact
from viapath.planning.viapath.rollout import keeps_inside
from viapath.sums import pairwise_sum


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


@compiled(inline=True)
def _longest_tick(times, s_count):
    """The longest time between two of the first ``s_count`` steps (NaN first, as np.max)."""
    tick = 0.0
    for s in range(1, s_count):
        tick = _maximum(tick, times[s] - times[s - 1])
    return tick


@compiled(inline=True)
def _overlapped_gaps(positions, times, people, overlapping, gap_min, gap_last):
    """For each roll-out and each person it overlaps now (``overlapping``, one column each, in order): the smallest
    gap over the roll-out into ``gap_min`` and the gap at its end into ``gap_last``."""
    if gap_min.shape[1] == 0:  # no one overlapped now (mostly): no pass over every roll-out and person
        return
    obstacle_positions, obstacle_velocities, check_radii, growth, growth_until_s = people
    s_count = positions.shape[1]
    for k in range(positions.shape[0]):
        column = 0
        for j in range(obstacle_positions.shape[0]):
            if not overlapping[j]:
                continue
            px = obstacle_positions[j, 0]
            py = obstacle_positions[j, 1]
            vx = obstacle_velocities[j, 0]
            vy = obstacle_velocities[j, 1]
            for s in range(s_count):
                t = times[s]
                reach = check_radii[j] + growth[j] * (t if t < growth_until_s[j] else growth_until_s[j])
                gap = math.hypot(positions[k, s, 0] - (px + vx * t), positions[k, s, 1] - (py + vy * t)) - reach
                if gap < gap_min[k, column]:
                    gap_min[k, column] = gap
                if s == s_count - 1:
                    gap_last[k, column] = gap
            column += 1


@compiled(inline=True)
def _first_contact_steps(positions, times, people, overlapping, tick, first):
    """Into ``first`` (K,), holding the roll-out's length: the first step at which each roll-out touches someone it
    does not overlap now (kept if never). Each person is looked at up to the first contact found so far, skipping
    the steps in which the gap cannot close: by at most the robot's longest step in the roll-out (``hop``) plus
    what the person walks and grows in the longest time between two steps (``tick``)."""
    obstacle_positions, obstacle_velocities, check_radii, growth, growth_until_s = people
    s_count = positions.shape[1]
    for k in range(positions.shape[0]):
        hop_squared = 0.0  # the robot's longest step in roll-out k (NaN: no skipping)
        for s in range(1, s_count):
            dx = positions[k, s, 0] - positions[k, s - 1, 0]
            dy = positions[k, s, 1] - positions[k, s - 1, 1]
            hop_squared = _maximum(hop_squared, dx * dx + dy * dy)
        hop = math.sqrt(hop_squared)
        for j in range(obstacle_positions.shape[0]):
            if overlapping[j]:
                continue
            px = obstacle_positions[j, 0]
            py = obstacle_positions[j, 1]
            vx = obstacle_velocities[j, 0]
            vy = obstacle_velocities[j, 1]
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


@compiled(inline=True)
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
    n_overlapping = 0
    for j in range(obstacle_positions.shape[0]):
        if overlapping[j]:
            n_overlapping += 1
    first = np.full(k_count, steps, np.int64)
    gap_min = np.full((k_count, n_overlapping), np.inf)
    gap_last = np.empty((k_count, n_overlapping))
    tick = _longest_tick(times, positions.shape[1])
    people = (obstacle_positions, obstacle_velocities, check_radii, growth, growth_until_s)
    _overlapped_gaps(positions, times, people, overlapping, gap_min, gap_last)
    _first_contact_steps(positions, times, people, overlapping, tick, first)
    return first, gap_min, gap_last


@compiled
def _roll_outs_within(positions, corridor, limit, known):
    """Whether each roll-out (K, S, 2) keeps every point within ``limit`` of the corridor (excess <= limit,
    :func:`.rollout.keeps_inside`); those ``known`` to are not looked at. (A function of its own: the same loop
    inside :func:`escape_scores` took several times as long.)"""
    out = np.ones(positions.shape[0], np.bool_)
    for k in range(positions.shape[0]):
        if not known[k]:
            out[k] = keeps_inside(positions[k], positions.shape[1], corridor, limit)
    return out


@compiled(inline=True)
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
def _standing_free(robot, obstacles, settings):
    """Whether standing still at the robot's position is free over the horizon (capped at the standing time): no
    contact of that leg at rest with anyone (:func:`legs_first_contact`)."""
    starts = np.empty((1, 2))
    starts[0, 0] = robot[0]
    starts[0, 1] = robot[1]
    durations = np.empty(1)
    durations[0] = _minimum(_maximum(settings.horizon_s - 0.0, 0.0), settings.standing_check_s)
    contact = legs_first_contact(starts, np.zeros(1), np.zeros((1, 2)), durations, *obstacles, np.zeros(1))
    free = True
    for j in range(contact.shape[1]):
        if not math.isinf(contact[0, j]):
            free = False
    return free


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
    dt = settings.dt_s
    obstacles = (obstacle_positions, obstacle_velocities, radii, growth, growth_until_s)
    free = _standing_free(robot, obstacles, settings) if obstacle_positions.shape[0] else True
    max_turn = settings.max_turn_rate_radps
    turn0 = robot[4]
    heading0 = robot[2]
    headings = np.empty((row_turns.shape[0], steps + 1))
    for r in range(row_turns.shape[0]):
        w_cmd = _minimum(_maximum(row_turns[r], -max_turn), max_turn)
        headings[r, 0] = heading0
        turned = 0.0
        for s in range(steps):
            dw = settings.turn_step_radps * float(s + 1)
            turn = turn0 + _minimum(_maximum(w_cmd - turn0, -dw), dw)
            # np.cumsum: the first term as it is, then each added in order
            turned = turn * dt if s == 0 else turned + turn * dt
            headings[r, s + 1] = heading0 + turned
    return free, headings


@compiled(inline=True)
def _escape_roll_outs(robot, commands, turn_rows, sines, cosines, settings, steps):
    """The positions (K, steps, 2) of :func:`escape_scores`' roll-outs (:func:`viapath.kinematics.rollout`: the
    ramps of speed and turn rate, the exact arcs, the positions as running sums)."""
    k_count = commands.shape[0]
    dt = settings.dt_s
    max_speed = settings.max_speed_mps
    x0 = robot[0]
    y0 = robot[1]
    speed0 = robot[3]
    turn0 = robot[4]
    max_turn = settings.max_turn_rate_radps
    positions = np.empty((k_count, steps, 2))
    for k in range(k_count):
        row = turn_rows[k]
        v_cmd = _minimum(_maximum(commands[k, 0], 0.0), max_speed)
        w_cmd = _minimum(_maximum(commands[k, 1], -max_turn), max_turn)
        x_sum = 0.0
        y_sum = 0.0
        for s in range(steps):
            dv = settings.speed_step_mps * float(s + 1)
            dw = settings.turn_step_radps * float(s + 1)
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


@compiled(inline=True)
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


@compiled(inline=True)
def _roll_outs_inside(positions, corridor, tolerance, bound):
    """Whether each roll-out keeps inside the corridor (every point's excess <= ``tolerance``) and within the bound
    (np.max(excess) <= bound is all(excess <= bound), NaN included: with the bound at least the tolerance, as the
    caller sets it, true of every roll-out inside, not looked at again)."""
    k_count = positions.shape[0]
    inside = _roll_outs_within(positions, corridor, tolerance, np.zeros(k_count, np.bool_))
    known = inside if bound >= tolerance else np.zeros(k_count, np.bool_)
    within_bound = _roll_outs_within(positions, corridor, bound, known)
    return inside, within_bound


@compiled(inline=True)
def _toward(subgoal, x0, y0):
    """The unit direction from (x0, y0) to the subgoal (of length at least 1e-9 before scaling)."""
    toward_x = subgoal[0] - x0
    toward_y = subgoal[1] - y0
    norm = math.hypot(toward_x, toward_y)
    norm = 1e-9 if norm < 1e-9 else norm  # Python's max(norm, 1e-9)
    return toward_x / norm, toward_y / norm


@compiled(inline=True)
def _separations(gap_min, gap_last, gap_overlapped):
    """Each roll-out's separation (K,) from the M people overlapped now: per person, how much deeper it goes than now
    and how deep it ends (each counted when negative), summed as np.sum does (:func:`viapath.sums.pairwise_sum`)."""
    k_count = gap_min.shape[0]
    m_count = gap_overlapped.shape[0]
    separations = np.zeros(k_count)
    if m_count:
        terms = np.empty(m_count)
        for k in range(k_count):
            for column in range(m_count):
                deeper = gap_min[k, column] - gap_overlapped[column]
                terms[column] = _minimum(deeper, 0.0) + _minimum(gap_last[k, column], 0.0)
            separations[k] = 0.0 + pairwise_sum(terms, 0, m_count)
    return separations


@compiled(inline=True)
def _score(separation, free, inside, time_to_contact, speed, progress, progress_s):
    """One escape command's score before the continuity term: separation, free of contact over the roll-out, inside
    the corridor, time to contact, speed (less of it when not free), progress towards the subgoal (``progress_s``
    per m/s when free, a tie-break otherwise)."""
    return (
        1e2 * separation
        + 20.0 * (1.0 if free else 0.0)
        + 2.0 * (1.0 if inside else 0.0)
        + time_to_contact
        - (0.005 if free else 0.5) * speed
        + (progress_s if free else 0.01) * progress
    )


@compiled(inline=True)
def _change(speed, turn, settings):
    """How far a command is from last cycle's, speed and turn rate each relative to its top (the continuity term)."""
    return (
        abs(speed - settings.previous_speed_mps) / settings.top_speed_mps
        + abs(turn - settings.previous_turn_radps) / settings.max_turn_rate_radps
    )


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
    positions as running sums), whether they keep inside the corridor, the people who could come within reach
    (the triangle-inequality bound), the contacts (:func:`escape_contacts`), the separation from the people
    overlapped now, the progress towards the subgoal and the score. Returns the ends (K, 2) and the scores (K,).

    ``sines`` and ``cosines`` are numpy's, of :func:`escape_headings`' rows (command k's row is
    ``turn_rows[k]``). ``calm``: a calm escape with last cycle's command (the continuity term)."""
    k_count = commands.shape[0]
    dt = settings.dt_s
    positions = _escape_roll_outs(robot, commands, turn_rows, sines, cosines, settings, steps)
    corridor = (segment_starts, segment_directions, segment_lengths, half_widths)
    inside, within_bound = _roll_outs_inside(positions, corridor, settings.corridor_tolerance_m, settings.max_excess_m)
    travel = _furthest(positions, robot[0], robot[1])
    first_step, gap_min, gap_last, gap_overlapped = _escape_contacts_near(
        positions, robot, obstacle_positions, obstacle_velocities, radii, growth, growth_until_s, dt, steps, travel
    )
    toward_x, toward_y = _toward(subgoal, robot[0], robot[1])
    separations = _separations(gap_min, gap_last, gap_overlapped)
    ends = positions[:, steps - 1, :].copy()
    score = np.empty(k_count)
    for k in range(k_count):
        speed = commands[k, 0]
        time_to_contact = first_step[k] * dt
        free = time_to_contact >= steps * dt
        progress = ((ends[k, 0] - robot[0]) * toward_x + (ends[k, 1] - robot[1]) * toward_y) / settings.escape_s
        value = _score(separations[k], free, inside[k], time_to_contact, speed, progress, settings.progress_s)
        if calm:
            value = value - settings.continuity_s * _minimum(_change(speed, commands[k, 1], settings), 1.0)
        score[k] = value if (within_bound[k] or speed == 0.0) else -math.inf
    return ends, score
