"""The shield's test of K commands: which are admissible (and friendly), and when each would first meet a person,
touch static geometry or leave the corridor. The definitions are in :mod:`viapath.safety.shield`; the braking
sweep in :mod:`viapath.safety.sweep`.

Compiled (:func:`viapath.jit.compiled`), and plain Python with ``NUMBA_DISABLE_JIT=1``. Choices:

* People: per (command, near person) the sub-intervals are scanned from the start, and the scan stops at the
  first hit, or as soon as no later hit could come before the meeting already found for that command; the
  earliest meeting counts, ties to the lower person row.
* The swept-disc test per sub-interval is the quadratic inequality of :mod:`viapath.safety.shield` solved on
  [0, 1]; a value above -1e-12 (rounding at the disc's edge) is no meeting. "Towards" is bounded per
  sub-interval by its end values' mean plus half the interval times a bound on its rate, and a hit counts
  when the robot may move towards the person in that sub-interval or earlier in the same control period.
* Static discs and the corridor are tested at the sweep's chords (each padded by its sagitta); only discs
  within reach of the longest braking and inside the sweeps' bounding box (grown by the largest reach and
  sagitta) are looked at.
* Distances by ``np.hypot``: numpy's bits compiled and in plain Python (``math.hypot`` rounds differently).
* No np.zeros / np.ones / np.full: each would cost a compilation of its own (np.empty and loops).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from viapath.jit import compiled
from viapath.path import corridor_excess_at
from viapath.safety.sweep import Drive, Robot, Sweep, achieved_first_period, braking_sweep, clip

# A record's fields as a plain tuple, how the records cross from Python into the compiled test (a record passed
# into or out of compiled code costs about two microseconds at the boundary, a plain tuple about half of one).
Fields = tuple[Any, ...]

CORRIDOR_TOLERANCE_M = 1e-6  # outside the corridor by more than this counts as leaving it (the benchmark's metric)


class Forecast(NamedTuple):
    """How the shield forecasts people (the shield's options)."""

    margin_m: float
    sigma_multiplier: float
    person_accel_mps2: float
    friendly: bool  # passive-friendly mode
    towards_only: bool


class People(NamedTuple):
    """The people (rows with every field finite), as :class:`viapath.observation.Obstacles` holds them."""

    positions: np.ndarray  # (N, 2)
    velocities: np.ndarray  # (N, 2)
    radii_m: np.ndarray
    position_sigma_m: np.ndarray
    velocity_sigma_mps: np.ndarray


class Statics(NamedTuple):
    """Static geometry: discs that do not move (no σ, no growth)."""

    positions: np.ndarray  # (S, 2)
    radii_m: np.ndarray


class Corridor(NamedTuple):
    """The designated path's corridor the robot must keep to (no segments: none)."""

    starts: np.ndarray  # (P, 2) segment starts
    directions: np.ndarray  # (P, 2) unit vectors
    lengths_m: np.ndarray
    half_widths_m: np.ndarray


class Crowd(NamedTuple):
    """Per person now: offset from the robot, distance, touching distance, gap, speed; and its forecast disc's
    base radius, growth rate and whether it can come near any braking path."""

    offset_x: np.ndarray
    offset_y: np.ndarray
    distance_m: np.ndarray
    touching_m: np.ndarray
    gap_m: np.ndarray
    speed_mps: np.ndarray
    base_m: np.ndarray
    growth_mps: np.ndarray
    near: np.ndarray


class Verdicts(NamedTuple):
    """The test's answer for K commands."""

    achieved: np.ndarray  # (K, 2) (v, ω) of the first period
    admissible: np.ndarray  # (K,) bool
    friendly: np.ndarray  # (K,) bool (passive-friendly mode; else as admissible or looser)
    meet_time_s: np.ndarray  # (K,) first meeting with a person (inf: never)
    person: np.ndarray  # (K,) that person's row (-1: none)
    contact: bool  # a person touches the robot now: nothing is admissible
    static_meet_time_s: np.ndarray  # (K,) start of the first sub-interval touching static geometry (inf: never)
    corridor_exit_time_s: np.ndarray  # (K,) when the sweep first leaves the corridor (inf: never)


@compiled
def filled(count: int, value: float) -> np.ndarray:
    out = np.empty(count)
    for i in range(count):
        out[i] = value
    return out


@compiled
def flags(count: int, value: bool) -> np.ndarray:
    out = np.empty(count, dtype=np.bool_)
    for i in range(count):
        out[i] = value
    return out


@compiled
def finite_people(people: People) -> People:
    """The rows :meth:`viapath.observation.Obstacles.finite` keeps (no NaN or infinite field, radius >= 0), as
    new arrays."""
    n_all = people.positions.shape[0]
    keep = np.empty(n_all, dtype=np.bool_)
    for n in range(n_all):
        keep[n] = (
            math.isfinite(people.positions[n, 0])
            and math.isfinite(people.positions[n, 1])
            and math.isfinite(people.velocities[n, 0])
            and math.isfinite(people.velocities[n, 1])
            and math.isfinite(people.radii_m[n])
            and people.radii_m[n] >= 0
            and math.isfinite(people.position_sigma_m[n])
            and math.isfinite(people.velocity_sigma_mps[n])
        )
    # Copies, even of all rows: the result is then one array type, whether the arrays handed in may be written
    # to or not (read-only arrays are a type of their own).
    if keep.all():
        return People(
            people.positions.copy(),
            people.velocities.copy(),
            people.radii_m.copy(),
            people.position_sigma_m.copy(),
            people.velocity_sigma_mps.copy(),
        )
    return People(
        people.positions[keep],
        people.velocities[keep],
        people.radii_m[keep],
        people.position_sigma_m[keep],
        people.velocity_sigma_mps[keep],
    )


@compiled
def crowd_now(robot: Robot, people: People, forecast: Forecast) -> Crowd:
    """:class:`Crowd` with ``near`` all True (:func:`mark_near` narrows it once the sweep is known)."""
    n_count = people.positions.shape[0]
    offset_x, offset_y, distance = np.empty(n_count), np.empty(n_count), np.empty(n_count)
    touching, gap, speed = np.empty(n_count), np.empty(n_count), np.empty(n_count)
    base, growth = np.empty(n_count), np.empty(n_count)
    for n in range(n_count):
        offset_x[n] = people.positions[n, 0] - robot.x_m
        offset_y[n] = people.positions[n, 1] - robot.y_m
        distance[n] = np.hypot(offset_x[n], offset_y[n])
        touching[n] = robot.radius_m + people.radii_m[n]
        gap[n] = distance[n] - touching[n]
        speed[n] = np.hypot(people.velocities[n, 0], people.velocities[n, 1])
        k_sigma = forecast.sigma_multiplier
        base[n] = touching[n] + min(forecast.margin_m + k_sigma * people.position_sigma_m[n], gap[n])
        growth[n] = k_sigma * people.velocity_sigma_mps[n]
    return Crowd(offset_x, offset_y, distance, touching, gap, speed, base, growth, flags(n_count, True))


@compiled
def everyone_far(achieved: np.ndarray, drive: Drive, crowd: Crowd, people: People, forecast: Forecast) -> bool:
    """The cheap bound: nobody touching the robot, and nobody within reach of its longest braking (from the
    fastest first period, 2 periods slack for the discrete steps): then no sweep is needed for people."""
    fastest = 0.0
    for k in range(achieved.shape[0]):
        fastest = max(fastest, abs(achieved[k, 0]))
    t_bound = fastest / max(drive.max_accel_mps2, 1e-9) + 2.0 * drive.dt_s
    r_bound = fastest * t_bound
    accel, k_sigma = forecast.person_accel_mps2, forecast.sigma_multiplier
    for n in range(crowd.gap_m.shape[0]):
        speed = crowd.speed_mps[n]
        grow = (
            crowd.touching_m[n]
            + forecast.margin_m
            + k_sigma * (people.position_sigma_m[n] + people.velocity_sigma_mps[n] * t_bound)
            + 0.5 * accel * t_bound**2.0
            + speed * t_bound
        )
        if forecast.friendly:
            grow = grow + speed * speed / (2.0 * max(accel, 1e-3))
        if not (crowd.gap_m[n] > 0.0 and crowd.distance_m[n] - grow > r_bound + 1e-6):
            return False
    return True


@compiled
def mark_near(crowd: Crowd, sweep: Sweep, people: People, forecast: Forecast) -> bool:
    """Sets ``crowd.near``: whose forecast path (centre over [0, horizon], grown to its largest radius) comes
    within the robot's longest sweep of its start; whether anyone does."""
    horizon = sweep.substep_s * (sweep.positions.shape[1] - 1)
    accel = forecast.person_accel_mps2
    max_reach = 0.0
    for k in range(sweep.reach_m.shape[0]):
        max_reach = max(max_reach, sweep.reach_m[k])
    anyone = False
    for n in range(crowd.near.shape[0]):
        speed = crowd.speed_mps[n]
        reach = crowd.base_m[n] + crowd.growth_mps[n] * horizon + 0.5 * accel * horizon**2.0 + speed * horizon
        if forecast.friendly:
            reach = reach + speed * speed / (2.0 * max(accel, 1e-3))
        path_x, path_y = people.velocities[n, 0] * horizon, people.velocities[n, 1] * horizon
        pp = path_x * path_x + path_y * path_y
        ox, oy = crowd.offset_x[n], crowd.offset_y[n]
        along = clip((-ox * path_x + -oy * path_y) / (pp if pp > 0 else 1.0), 0.0, 1.0)
        closest = np.hypot(ox + path_x * along, oy + path_y * along)
        crowd.near[n] = closest - (reach - speed * horizon) <= max_reach + 1e-6
        anyone = anyone or crowd.near[n]
    return anyone


@compiled
def clear_unfriendly(friendly: np.ndarray, sweep: Sweep, crowd: Crowd, people: People, accel: float) -> None:
    """Passive friendly: clears ``friendly`` of each command whose rest point lies in a near person's way while
    that person, braking at ``accel`` from its forecast at the robot's rest time, stops (the disc at the rest
    time swept along its braking path)."""
    for k in range(friendly.shape[0]):
        t_rest = sweep.rest_time_s[k]
        rest_x = sweep.positions[k, sweep.rest_index[k], 0]
        rest_y = sweep.positions[k, sweep.rest_index[k], 1]
        for n in range(crowd.near.shape[0]):
            if not crowd.near[n]:
                continue
            vx, vy = people.velocities[n, 0], people.velocities[n, 1]
            stretch = np.hypot(vx, vy) / (2.0 * max(accel, 1e-3))
            travel_x, travel_y = vx * stretch, vy * stretch
            radius = crowd.base_m[n] + crowd.growth_mps[n] * t_rest + 0.5 * accel * (t_rest * t_rest)
            rel_x = rest_x - (people.positions[n, 0] + vx * t_rest)
            rel_y = rest_y - (people.positions[n, 1] + vy * t_rest)
            tt = travel_x * travel_x + travel_y * travel_y
            f = clip((rel_x * travel_x + rel_y * travel_y) / (tt if tt > 0 else 1.0), 0.0, 1.0)
            if np.hypot(rel_x - travel_x * f, rel_y - travel_y * f) < radius:
                friendly[k] = False
                break


@compiled(inline=True)  # called per (command, person, sub-interval): no call, no record copied
def swept_disc_meets(sweep: Sweep, k: int, t: int, centres: np.ndarray, radii: np.ndarray) -> bool:
    """Whether the robot, along command k's chord over sub-interval t, comes inside the person's growing disc
    (``centres`` (T, 2) and ``radii`` (T,) at the sample times): relative motion r_a + w τ against the radius
    R_a + dR τ (its chord, above the convex radius, plus 4 sagittas), a quadratic in τ on [0, 1]."""
    j = t // sweep.substeps
    r_ax = sweep.positions[k, t, 0] - centres[t, 0]
    r_ay = sweep.positions[k, t, 1] - centres[t, 1]
    w_x = (sweep.positions[k, t + 1, 0] - centres[t + 1, 0]) - r_ax
    w_y = (sweep.positions[k, t + 1, 1] - centres[t + 1, 1]) - r_ay
    r_start = radii[t]
    d_r = (radii[t + 1] - radii[t]) + 4.0 * sweep.sagitta_m[k, j]
    qa = (w_x * w_x + w_y * w_y) - d_r * d_r
    qb = 2.0 * ((r_ax * w_x + r_ay * w_y) - r_start * d_r)
    qc = (r_ax * r_ax + r_ay * r_ay) - r_start * r_start
    low = min(qc, qa + qb + qc)
    vertex = -qb / (2.0 * qa if qa > 0 else 1.0)
    if qa > 0 and vertex > 0.0 and vertex < 1.0:
        low = min(low, qc - qb * qb / (4.0 * qa if qa > 0 else 1.0))
    return low < -1e-12


@compiled(inline=True)
def moves_towards(
    sweep: Sweep, k: int, t: int, centres: np.ndarray, heading: np.ndarray, person: tuple[float, float, float, float]
) -> bool:
    """With ``towards_only``: whether the robot may move towards the person's centre in sub-interval t or
    earlier in the same control period (the at-fault metric reads the heading at the start of the period in
    which a contact begins). T = u · (c − p) is at most (T_a + T_b + L h) / 2 on a sub-interval, L bounding
    |dT/dt|; the centre may lie anywhere within the forecast's own spread (k σ_p + k σ_v t + a_p t² / 2).
    ``heading``: (T, 2) the unit heading at the samples; ``person``: k σ_p, growth, a_p, speed."""
    spread_sigma, growth, accel, person_speed = person
    h, m = sweep.substep_s, sweep.substeps
    j = t // m
    s_int = sweep.effective_mps[k, j]
    for u in range(j * m, t + 1):
        tb = h * (u + 1)
        spread = spread_sigma + growth * tb + 0.5 * accel * (tb * tb)
        q_ax = sweep.positions[k, u, 0] - centres[u, 0]
        q_ay = sweep.positions[k, u, 1] - centres[u, 1]
        q_bx = q_ax + ((sweep.positions[k, u + 1, 0] - centres[u + 1, 0]) - q_ax)
        q_by = q_ay + ((sweep.positions[k, u + 1, 1] - centres[u + 1, 1]) - q_ay)
        t_a = -s_int * (heading[u, 0] * q_ax + heading[u, 1] * q_ay)
        t_b = -s_int * (heading[u + 1, 0] * q_bx + heading[u + 1, 1] * q_by)
        r_max = max(np.hypot(q_ax, q_ay), np.hypot(q_bx, q_by)) + 0.01
        lipschitz = abs(s_int) * (abs(sweep.turns_radps[k, j]) * r_max + person_speed + abs(s_int))
        if (t_a + t_b + lipschitz * h + 2.0 * abs(s_int) * spread) > 0.0:
            return True
    return False


@compiled
def unit_headings(sweep: Sweep, k: int, out: np.ndarray) -> None:
    """Command k's unit heading vectors at the samples into ``out`` (T, 2)."""
    for u in range(out.shape[0]):
        out[u, 0] = math.cos(sweep.headings[k, u]) * 1.0
        out[u, 1] = math.sin(sweep.headings[k, u]) * 1.0


@compiled
def first_meetings(
    meet: np.ndarray, person: np.ndarray, sweep: Sweep, crowd: Crowd, people: People, forecast: Forecast
) -> None:
    """The swept-disc (and "towards") tests per (command, near person, sub-interval), scanned from the start:
    each command's earliest meeting time into ``meet`` and the person's row into ``person``."""
    k_count, t_count = meet.shape[0], sweep.positions.shape[1]
    h, accel = sweep.substep_s, forecast.person_accel_mps2
    centres, radii = np.empty((t_count, 2)), np.empty(t_count)
    headings = np.empty((k_count, t_count, 2))  # filled per command when first needed
    have_headings = flags(k_count, False)
    for n in range(crowd.near.shape[0]):
        if not crowd.near[n]:
            continue
        for t in range(t_count):  # the forecast disc at the samples
            tt = h * t
            centres[t, 0] = people.positions[n, 0] + people.velocities[n, 0] * tt
            centres[t, 1] = people.positions[n, 1] + people.velocities[n, 1] * tt
            radii[t] = crowd.base_m[n] + crowd.growth_mps[n] * tt + 0.5 * accel * (tt * tt)
        spread = (
            forecast.sigma_multiplier * people.position_sigma_m[n],
            crowd.growth_mps[n],
            accel,
            crowd.speed_mps[n],
        )
        for k in range(k_count):
            for t in range(t_count - 1):
                if not h * (t + 1) < meet[k]:
                    break  # no later hit can come before the meeting already found
                if not sweep.moving[k, t // sweep.substeps] or not swept_disc_meets(sweep, k, t, centres, radii):
                    continue
                if forecast.towards_only:
                    if not have_headings[k]:
                        unit_headings(sweep, k, headings[k])
                        have_headings[k] = True
                    if not moves_towards(sweep, k, t, centres, headings[k], spread):
                        continue
                meet[k], person[k] = h * (t + 1), n
                break


@compiled
def people_meetings(
    meet: np.ndarray,
    person: np.ndarray,
    friendly: np.ndarray,
    sweep: Sweep,
    crowd: Crowd,
    people: People,
    forecast: Forecast,
) -> None:
    """The people's part of the test once a sweep is needed and nobody touches the robot: who is near, the
    friendly rest (passive-friendly mode) and the first meetings."""
    anyone = mark_near(crowd, sweep, people, forecast)
    if forecast.friendly:
        clear_unfriendly(friendly, sweep, crowd, people, forecast.person_accel_mps2)
    if anyone:
        first_meetings(meet, person, sweep, crowd, people, forecast)


@compiled
def statics_near(robot: Robot, drive: Drive, achieved: np.ndarray, statics: Statics, margin_m: float) -> np.ndarray:
    """Which static discs the longest braking could reach (none when no command moves in its first period)."""
    fastest = 0.0
    for k in range(achieved.shape[0]):
        fastest = max(fastest, abs(achieved[k, 0]))
    t_bound = fastest / max(drive.max_accel_mps2, 1e-9) + 2.0 * drive.dt_s
    near = np.empty(statics.radii_m.shape[0], dtype=np.bool_)
    for n in range(near.shape[0]):
        distance = np.hypot(statics.positions[n, 0] - robot.x_m, statics.positions[n, 1] - robot.y_m)
        reach = robot.radius_m + statics.radii_m[n] + margin_m
        near[n] = fastest != 0.0 and distance - reach <= fastest * t_bound + 1e-6
    return near


@compiled
def in_sweep_box(sweep: Sweep, statics: Statics, near: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Which near discs lie in the box of every sweep sample grown by the largest reach and sagitta."""
    largest = 0.0
    for n in range(near.shape[0]):
        largest = max(largest, reach[n]) if near[n] else largest
    sag = 0.0
    for k in range(sweep.sagitta_m.shape[0]):
        for j in range(sweep.sagitta_m.shape[1]):
            sag = max(sag, sweep.sagitta_m[k, j])
    low_x, low_y, high_x, high_y = math.inf, math.inf, -math.inf, -math.inf
    for k in range(sweep.positions.shape[0]):
        for t in range(sweep.positions.shape[1]):
            low_x, high_x = min(low_x, sweep.positions[k, t, 0]), max(high_x, sweep.positions[k, t, 0])
            low_y, high_y = min(low_y, sweep.positions[k, t, 1]), max(high_y, sweep.positions[k, t, 1])
    low_x, low_y = low_x - largest - sag, low_y - largest - sag
    high_x, high_y = high_x + largest + sag, high_y + largest + sag
    inside = np.empty(near.shape[0], dtype=np.bool_)
    for n in range(near.shape[0]):
        x, y = statics.positions[n, 0], statics.positions[n, 1]
        inside[n] = near[n] and low_x <= x <= high_x and low_y <= y <= high_y
    return inside


@compiled
def static_meetings(
    meet: np.ndarray, sweep: Sweep, robot: Robot, statics: Statics, near: np.ndarray, margin_m: float
) -> None:
    """Static geometry: command k meets a disc in a sub-interval when the distance from the disc's centre to
    its chord, less the chord's sagitta, is below robot + disc radius + margin and below the distance now (a
    robot already too close may move away). Sets the start of the first such sub-interval into ``meet``."""
    n_count = near.shape[0]
    distance, reach = np.empty(n_count), np.empty(n_count)
    for n in range(n_count):
        distance[n] = np.hypot(statics.positions[n, 0] - robot.x_m, statics.positions[n, 1] - robot.y_m)
        reach[n] = robot.radius_m + statics.radii_m[n] + margin_m
    inside = in_sweep_box(sweep, statics, near, reach)
    if not inside.any():
        return
    for k in range(meet.shape[0]):
        for t in range(sweep.positions.shape[1] - 1):
            j = t // sweep.substeps
            if not sweep.moving[k, j]:
                continue
            ax, ay = sweep.positions[k, t, 0], sweep.positions[k, t, 1]
            cx, cy = sweep.positions[k, t + 1, 0] - ax, sweep.positions[k, t + 1, 1] - ay
            length2 = cx * cx + cy * cy
            hit = False
            for n in range(n_count):
                if not inside[n]:
                    continue
                rx, ry = statics.positions[n, 0] - ax, statics.positions[n, 1] - ay
                f = clip((rx * cx + ry * cy) / (length2 if length2 > 0 else 1.0), 0.0, 1.0)
                gap = np.hypot(rx - f * cx, ry - f * cy) - sweep.sagitta_m[k, j]
                if gap < reach[n] and gap < distance[n] - 1e-9:
                    hit = True
                    break
            if hit:
                meet[k] = sweep.substep_s * t
                break


@compiled
def corridor_exits(exit_time: np.ndarray, sweep: Sweep, robot: Robot, corridor: Corridor) -> None:
    """The corridor is hard: command k leaves it at the first sample of a moving step whose centre, padded by
    the sagitta, lies further outside than the robot is now (0 for a robot inside) plus the tolerance."""
    now = corridor_excess_at(
        robot.x_m, robot.y_m, corridor.starts, corridor.directions, corridor.lengths_m, corridor.half_widths_m
    )
    allowed = max(0.0, now) + CORRIDOR_TOLERANCE_M
    for k in range(exit_time.shape[0]):
        for t in range(1, sweep.positions.shape[1]):
            j = (t - 1) // sweep.substeps
            if not sweep.moving[k, j]:
                continue
            x, y = sweep.positions[k, t, 0], sweep.positions[k, t, 1]
            excess = corridor_excess_at(
                x, y, corridor.starts, corridor.directions, corridor.lengths_m, corridor.half_widths_m
            )
            if excess + sweep.sagitta_m[k, j] > allowed:
                exit_time[k] = sweep.substep_s * t
                break


@compiled
def touching(crowd: Crowd) -> int:
    """The row of the person with the smallest gap if someone touches the robot now (gap <= 0), else -1."""
    first = -1
    for n in range(crowd.gap_m.shape[0]):
        if not crowd.gap_m[n] > 0.0 and first < 0:
            first = n
    if first < 0:
        return -1
    for n in range(crowd.gap_m.shape[0]):  # argmin: the first smallest gap
        if crowd.gap_m[n] < crowd.gap_m[first]:
            first = n
    return first


@compiled
def evaluate(
    robot: Robot,
    drive: Drive,
    forecast: Forecast,
    commands: np.ndarray,
    people: People,
    statics: Statics,
    corridor: Corridor,
) -> Verdicts:
    """The verdicts on K commands (K, 2); people with a field not finite are left out (``person`` counts the
    rows kept)."""
    achieved = achieved_first_period(commands, robot, drive)
    k_count = achieved.shape[0]
    people = finite_people(people)
    crowd = crowd_now(robot, people, forecast)
    check_people = people.radii_m.shape[0] > 0 and not everyone_far(achieved, drive, crowd, people, forecast)
    contact_row = touching(crowd) if check_people else -1
    near_static = statics_near(robot, drive, achieved, statics, forecast.margin_m)
    moves = robot.speed_mps != 0.0
    for k in range(k_count):
        moves = moves or achieved[k, 0] != 0.0
    moves = moves and corridor.lengths_m.shape[0] > 0
    need = (check_people and contact_row < 0) or near_static.any() or moves
    sweep = braking_sweep(robot, drive, achieved if need else achieved[:0])
    friendly, meet = flags(k_count, True), filled(k_count, math.inf)
    person = np.empty(k_count, dtype=np.int64)
    person[:] = -1 if contact_row < 0 else contact_row
    if contact_row >= 0:
        meet[:] = 0.0
    elif check_people:
        people_meetings(meet, person, friendly, sweep, crowd, people, forecast)
    static_meet, corridor_exit = filled(k_count, math.inf), filled(k_count, math.inf)
    if near_static.any():
        static_meetings(static_meet, sweep, robot, statics, near_static, forecast.margin_m)
    if moves:
        corridor_exits(corridor_exit, sweep, robot, corridor)
    admissible = np.empty(k_count, dtype=np.bool_)
    for k in range(k_count):
        admissible[k] = not (math.isfinite(meet[k]) or math.isfinite(static_meet[k]) or math.isfinite(corridor_exit[k]))
        friendly[k] = friendly[k] and admissible[k]
    return Verdicts(achieved, admissible, friendly, meet, person, contact_row >= 0, static_meet, corridor_exit)


@compiled
def evaluate_fields(
    robot: Fields,
    drive: Fields,
    forecast: Fields,
    commands: np.ndarray,
    people: Fields,
    statics: Fields,
    corridor: Fields,
) -> Fields:
    """:func:`evaluate` called from Python: each record as its :data:`Fields`, the verdicts as a plain tuple in
    :class:`Verdicts`' order."""
    verdicts = evaluate(
        Robot(*robot),
        Drive(*drive),
        Forecast(*forecast),
        commands,
        People(*people),
        Statics(*statics),
        Corridor(*corridor),
    )
    return (
        verdicts.achieved,
        verdicts.admissible,
        verdicts.friendly,
        verdicts.meet_time_s,
        verdicts.person,
        verdicts.contact,
        verdicts.static_meet_time_s,
        verdicts.corridor_exit_time_s,
    )
