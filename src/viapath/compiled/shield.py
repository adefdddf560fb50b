"""The compiled shield (extra ``fast``: numba): :meth:`viapath.safety.shield.Shield.evaluate` as one
scalar loop, the same arithmetic as the numpy reference in :mod:`viapath.safety.shield` (DESIGN §7).

Source: the profile of ``benchmarks/bench_shield.py`` (docs/speed.md): per cycle the
shield spends nearly all its time in ``evaluate`` (the (command, person, sub-interval) swept-disc and
"towards" tests, a few dozen array operations on (K, N, T) arrays) and in ``braking_sweep`` (the
braking roll-outs of the K commands); once those were compiled, the Python around them did (the
achieved (v, ω), ``Obstacles.finite``, the window search's candidates, order and chunk loop). All of
it is compiled here behind one entry, :func:`shield`, operation for operation as the numpy code does
it (same order of additions, same quadratic, same bounds, same candidates, order and chunks), so
that the verdicts are the same (``tests/safety/test_shield_backends.py`` checks it on random cases,
the property test on its 14 000).

Choices:
* Loaded through :func:`viapath.compiled.kernels` (the package's one policy decides whether it runs); module-level
  ``@njit(cache=True, nogil=True)`` functions with C-contiguous float64 inputs, one signature each.
* What a scalar loop can do and the array code cannot: per (command, person) the sub-intervals are
  scanned from the start and the scan stops at the first hit, or as soon as no later hit could come
  before the meeting already found for that command (the reference keeps the earliest meeting, ties
  to the lower person row, which the loop order gives too).
* ``reach_m`` (path length until rest) is summed in order, where numpy sums a row pairwise (8
  accumulators past 8 steps): the two differ in the last bits at most, and the sum only feeds the
  "near" bound, which has 1e-6 m to spare (a person that close to it cannot be met). Copying numpy's
  pairwise sum cost two seconds of compilation.
* No np.zeros / np.ones / np.full / .copy(): each costs a compilation of its own (np.empty and loops).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_STRAIGHT = 1e-9
_LIMIT = 10_000  # braking steps at most, as braking_sweep


@njit(cache=True, nogil=True)
def _clip(x, low, high):
    """np.clip for scalars: minimum(maximum(x, low), high)."""
    if x < low:
        x = low
    if x > high:
        x = high
    return x


@njit(cache=True, nogil=True)
def braking_sweep(px, py, heading, speed_now, achieved, dv, dw, dt, substeps):
    """:func:`viapath.safety.shield.braking_sweep`: positions (K, T, 2) and headings (K, T) at the
    sub-interval ends, per braking step (K, J) the speed to count for "towards" (``effective``), the
    turn rate, moving flag and sagitta, and per command the rest time, rest index and reach."""
    k_count = achieved.shape[0]
    # Steps: the drive's recurrence until every command is at rest (numpy's while loop), at most _LIMIT.
    j_count = 1
    for k in range(k_count):
        s = achieved[k, 0]
        n = 1
        while s != 0.0 and n < _LIMIT:
            s = s + _clip(-s, -dv, dv)
            n += 1
        if n > j_count:
            j_count = n
    speed = np.empty((k_count, j_count))
    turn = np.empty((k_count, j_count))
    previous = np.empty((k_count, j_count))
    for k in range(k_count):
        s = achieved[k, 0]
        w = achieved[k, 1]
        speed[k, 0] = s
        turn[k, 0] = w
        for j in range(1, j_count):
            s = s + _clip(-s, -dv, dv)
            w = w + _clip(-w, -dw, dw)
            speed[k, j] = s
            turn[k, j] = w
        previous[k, 0] = speed_now
        for j in range(1, j_count):
            previous[k, j] = speed[k, j - 1]
    if j_count > 1:
        drop = True
        for k in range(k_count):
            if previous[k, j_count - 1] != 0.0:
                drop = False
        if drop:
            j_count -= 1
    m = substeps
    h = dt / m
    t_count = j_count * m + 1
    positions = np.empty((k_count, t_count, 2))
    headings = np.empty((k_count, t_count))
    effective = np.empty((k_count, j_count))
    sagitta = np.empty((k_count, j_count))
    moving = np.empty((k_count, j_count), dtype=np.bool_)
    rest_time = np.empty(k_count)
    rest_index = np.empty(k_count, dtype=np.int64)
    reach = np.empty(k_count)
    for k in range(k_count):
        positions[k, 0, 0] = px
        positions[k, 0, 1] = py
        headings[k, 0] = heading
        cum_turn = 0.0
        cum_x = 0.0
        cum_y = 0.0
        steps_moving = 0
        path_length = 0.0
        for j in range(j_count):
            s = speed[k, j]
            w = turn[k, j]
            h0 = heading + (cum_turn if j > 0 else 0.0)
            start_x = px + (cum_x if j > 0 else 0.0)
            start_y = py + (cum_y if j > 0 else 0.0)
            straight = abs(w) < _STRAIGHT
            safe_w = 1.0 if straight else w
            dx = 0.0
            dy = 0.0
            for i in range(m):
                tau = h * (i + 1)
                h1 = h0 + w * tau
                if straight:
                    dx = s * tau * math.cos(h0)
                    dy = s * tau * math.sin(h0)
                else:
                    dx = s / safe_w * (math.sin(h1) - math.sin(h0))
                    dy = -s / safe_w * (math.cos(h1) - math.cos(h0))
                index = 1 + j * m + i
                positions[k, index, 0] = start_x + dx
                positions[k, index, 1] = start_y + dy
                headings[k, index] = h1
            cum_turn = cum_turn + w * dt if j > 0 else w * dt
            cum_x = cum_x + dx if j > 0 else dx
            cum_y = cum_y + dy if j > 0 else dy
            p = previous[k, j]
            moving[k, j] = (s != 0.0) or (p != 0.0)
            effective[k, j] = max(abs(s), abs(p))
            sagitta[k, j] = abs(s * w) * h * h / 8.0
            if moving[k, j]:
                steps_moving += 1
            path_length += abs(s)
        rest_time[k] = steps_moving * dt
        rest_index[k] = steps_moving * m
        reach[k] = path_length * dt
    return positions, headings, effective, turn, moving, sagitta, rest_time, rest_index, reach


@njit(cache=True, nogil=True)
def _all_clear(k_count):
    """Verdicts of K commands nobody can meet: admissible, friendly, meet time inf, person -1.
    (np.empty and loops: np.ones / np.full would each cost a compilation of their own.)"""
    admissible = np.empty(k_count, dtype=np.bool_)
    friendly = np.empty(k_count, dtype=np.bool_)
    meet = np.empty(k_count)
    person = np.empty(k_count, dtype=np.int64)
    for k in range(k_count):
        admissible[k] = True
        friendly[k] = True
        meet[k] = math.inf
        person[k] = -1
    return admissible, friendly, meet, person


@njit(cache=True, nogil=True)
def _people_now(px, py, robot_radius, positions_obs, velocities_obs, radii):
    """Per person now: offset from the robot (x, y), distance, touching distance (robot radius + theirs), gap
    and speed."""
    n_count = positions_obs.shape[0]
    offset_x = np.empty(n_count)
    offset_y = np.empty(n_count)
    distance = np.empty(n_count)
    touching = np.empty(n_count)
    gap = np.empty(n_count)
    speed_people = np.empty(n_count)
    for n in range(n_count):
        offset_x[n] = positions_obs[n, 0] - px
        offset_y[n] = positions_obs[n, 1] - py
        distance[n] = math.hypot(offset_x[n], offset_y[n])
        touching[n] = robot_radius + radii[n]
        gap[n] = distance[n] - touching[n]
        speed_people[n] = math.hypot(velocities_obs[n, 0], velocities_obs[n, 1])
    return offset_x, offset_y, distance, touching, gap, speed_people


@njit(cache=True, nogil=True)
def _everyone_far(achieved, max_accel, dt, now, position_sigma, velocity_sigma, margin, k_sigma, accel, friendly_mode):
    """The cheap bound: nobody within reach of the longest braking. ``now``: :func:`_people_now`'s."""
    _, _, distance, touching, gap, speed_people = now
    fastest = 0.0
    for k in range(achieved.shape[0]):
        fastest = max(fastest, abs(achieved[k, 0]))
    a_robot = max(max_accel, 1e-9)
    t_bound = fastest / a_robot + 2.0 * dt
    r_bound = fastest * t_bound
    braking_den = 2.0 * max(accel, 1e-3)
    for n in range(gap.shape[0]):
        grow = (
            touching[n]
            + margin
            + k_sigma * (position_sigma[n] + velocity_sigma[n] * t_bound)
            + 0.5 * accel * t_bound**2.0
            + speed_people[n] * t_bound
        )
        if friendly_mode:
            grow = grow + speed_people[n] * speed_people[n] / braking_den
        if not (gap[n] > 0.0 and distance[n] - grow > r_bound + 1e-6):
            return False
    return True


@njit(cache=True, nogil=True)
def _near_people(
    reach, horizon, velocities_obs, now, position_sigma, velocity_sigma, margin, k_sigma, accel, friendly_mode
):
    """Per person: the base radius and its growth rate of the forecast disc, and whether the person could come
    near any braking path (``reach``: each command's path length until rest) within the horizon."""
    offset_x, offset_y, _, touching, gap, speed_people = now
    n_count = gap.shape[0]
    braking_den = 2.0 * max(accel, 1e-3)
    base = np.empty(n_count)
    growth = np.empty(n_count)
    near = np.empty(n_count, dtype=np.bool_)
    max_reach = 0.0
    for k in range(reach.shape[0]):
        max_reach = max(max_reach, reach[k])
    for n in range(n_count):
        base[n] = touching[n] + min(margin + k_sigma * position_sigma[n], gap[n])
        growth[n] = k_sigma * velocity_sigma[n]
        reach_person = base[n] + growth[n] * horizon + 0.5 * accel * horizon**2.0 + speed_people[n] * horizon
        if friendly_mode:
            reach_person = reach_person + speed_people[n] * speed_people[n] / braking_den
        path_x = velocities_obs[n, 0] * horizon
        path_y = velocities_obs[n, 1] * horizon
        pp = path_x * path_x + path_y * path_y
        along = _clip((-offset_x[n] * path_x + -offset_y[n] * path_y) / (pp if pp > 0 else 1.0), 0.0, 1.0)
        closest_x = offset_x[n] + path_x * along
        closest_y = offset_y[n] + path_y * along
        near[n] = math.hypot(closest_x, closest_y) - (reach_person - speed_people[n] * horizon) <= max_reach + 1e-6
    return base, growth, near


@njit(cache=True, nogil=True)
def _unfriendly_at_rest(friendly, sweep, positions_obs, velocities_obs, base, growth, near, accel):
    """Clears ``friendly`` of each command whose rest point lies in a near person's way while that person
    brakes (the disc at the rest time swept along their braking path)."""
    positions, _, _, _, _, _, rest_time, rest_index, _ = sweep
    braking_den = 2.0 * max(accel, 1e-3)
    for k in range(friendly.shape[0]):
        t_rest = rest_time[k]
        rest_x = positions[k, rest_index[k], 0]
        rest_y = positions[k, rest_index[k], 1]
        for n in range(near.shape[0]):
            if not near[n]:
                continue
            vx = velocities_obs[n, 0]
            vy = velocities_obs[n, 1]
            speed = math.hypot(vx, vy)
            start_x = positions_obs[n, 0] + vx * t_rest
            start_y = positions_obs[n, 1] + vy * t_rest
            stretch = speed / braking_den
            travel_x = vx * stretch
            travel_y = vy * stretch
            radius = base[n] + growth[n] * t_rest + 0.5 * accel * (t_rest * t_rest)
            rel_x = rest_x - start_x
            rel_y = rest_y - start_y
            tt = travel_x * travel_x + travel_y * travel_y
            f = _clip((rel_x * travel_x + rel_y * travel_y) / (tt if tt > 0 else 1.0), 0.0, 1.0)
            if math.hypot(rel_x - travel_x * f, rel_y - travel_y * f) < radius:
                friendly[k] = False
                break


@njit(cache=True, nogil=True)
def _first_meetings(meet, person, sweep, substeps, h, positions_obs, velocities_obs, people, near, accel, towards_only):
    """The swept-disc (and "towards") tests per (command, near person, sub-interval), scanned from the start:
    sets each command's first meeting time in ``meet`` and the person in ``person`` (the earliest meeting, ties
    to the lower person row). ``people``: per person the speed, the forecast disc's base radius and growth, the
    position σ, and k."""
    positions, headings, effective, turn, moving, sagitta, _, _, _ = sweep
    speed_people, base, growth, position_sigma, k_sigma = people
    k_count = meet.shape[0]
    n_count = near.shape[0]
    t_count = positions.shape[1]
    m = substeps
    times = np.empty(t_count)
    for t in range(t_count):
        times[t] = h * t
    h_int = times[1] - times[0]
    # Per person: forecast centres and radii at the sub-interval ends (as the reference's (n, T) arrays).
    centre_x = np.empty(t_count)
    centre_y = np.empty(t_count)
    radii_t = np.empty(t_count)
    ux = np.empty((k_count, t_count))  # heading unit vectors, filled per command when first needed
    uy = np.empty((k_count, t_count))
    have_u = np.empty(k_count, dtype=np.bool_)
    for k in range(k_count):
        have_u[k] = False
    for n in range(n_count):
        if not near[n]:
            continue
        cx = positions_obs[n, 0]
        cy = positions_obs[n, 1]
        vx = velocities_obs[n, 0]
        vy = velocities_obs[n, 1]
        for t in range(t_count):
            tt = times[t]
            centre_x[t] = cx + vx * tt
            centre_y[t] = cy + vy * tt
            radii_t[t] = base[n] + growth[n] * tt + 0.5 * accel * (tt * tt)
        sp = speed_people[n]
        for k in range(k_count):
            best = meet[k]
            for t in range(t_count - 1):
                when = times[t + 1]  # the meeting time a hit here gives (the reference: times[first + 1])
                if not when < best:
                    break  # no later hit can come before the meeting already found
                j = t // m
                if not moving[k, j]:
                    continue
                r_ax = positions[k, t, 0] - centre_x[t]
                r_ay = positions[k, t, 1] - centre_y[t]
                w_x = (positions[k, t + 1, 0] - centre_x[t + 1]) - r_ax
                w_y = (positions[k, t + 1, 1] - centre_y[t + 1]) - r_ay
                r_start = radii_t[t]
                d_r = (radii_t[t + 1] - radii_t[t]) + 4.0 * sagitta[k, j]
                qa = (w_x * w_x + w_y * w_y) - d_r * d_r
                qb = 2.0 * ((r_ax * w_x + r_ay * w_y) - r_start * d_r)
                qc = (r_ax * r_ax + r_ay * r_ay) - r_start * r_start
                low = min(qc, qa + qb + qc)
                vertex = -qb / (2.0 * qa if qa > 0 else 1.0)
                if qa > 0 and vertex > 0.0 and vertex < 1.0:
                    low = min(low, qc - qb * qb / (4.0 * qa if qa > 0 else 1.0))
                if not low < -1e-12:
                    continue
                if towards_only:
                    if not have_u[k]:
                        for u in range(t_count):
                            ux[k, u] = math.cos(headings[k, u]) * 1.0
                            uy[k, u] = math.sin(headings[k, u]) * 1.0
                        have_u[k] = True
                    # Towards in this sub-interval or earlier in the same period (the reference's accumulate).
                    s_int = effective[k, j]
                    towards = False
                    spread_sigma = k_sigma * position_sigma[n]
                    for u in range(j * m, t + 1):
                        tb = times[u + 1]
                        spread = spread_sigma + growth[n] * tb + 0.5 * accel * (tb * tb)
                        q_ax = positions[k, u, 0] - centre_x[u]
                        q_ay = positions[k, u, 1] - centre_y[u]
                        q_bx = q_ax + ((positions[k, u + 1, 0] - centre_x[u + 1]) - q_ax)
                        q_by = q_ay + ((positions[k, u + 1, 1] - centre_y[u + 1]) - q_ay)
                        t_a = -s_int * (ux[k, u] * q_ax + uy[k, u] * q_ay)
                        t_b = -s_int * (ux[k, u + 1] * q_bx + uy[k, u + 1] * q_by)
                        r_max = max(math.hypot(q_ax, q_ay), math.hypot(q_bx, q_by)) + 0.01
                        lipschitz = abs(s_int) * (abs(turn[k, j]) * r_max + sp + abs(s_int))
                        if (t_a + t_b + lipschitz * h_int + 2.0 * abs(s_int) * spread) > 0.0:
                            towards = True
                            break
                    if not towards:
                        continue
                meet[k] = when
                person[k] = n
                break


@njit(cache=True, nogil=True)
def evaluate(
    px,
    py,
    heading,
    speed_now,
    robot_radius,
    achieved,
    max_accel,
    dv,
    dw,
    dt,
    substeps,
    positions_obs,
    velocities_obs,
    radii,
    position_sigma,
    velocity_sigma,
    margin,
    k_sigma,
    accel,
    friendly_mode,
    towards_only,
):
    """The verdicts of :meth:`viapath.safety.shield.Shield.evaluate` for K achieved (v, ω) (K, 2) and
    N >= 1 finite people: admissible (K,), friendly (K,), meet time (K,) (inf: never), person row (K,)
    (-1: none) and whether a person touches the robot now."""
    k_count = achieved.shape[0]
    n_count = positions_obs.shape[0]
    admissible, friendly, meet, person = _all_clear(k_count)
    contact = False
    now = _people_now(px, py, robot_radius, positions_obs, velocities_obs, radii)
    gap = now[4]
    if _everyone_far(
        achieved, max_accel, dt, now, position_sigma, velocity_sigma, margin, k_sigma, accel, friendly_mode
    ):
        return admissible, friendly, meet, person, contact
    touched = False
    for n in range(n_count):
        if not gap[n] > 0.0:
            touched = True
    if touched:  # a person touches the robot now: nothing is admissible
        first = 0
        for n in range(n_count):  # argmin: the first smallest gap
            if gap[n] < gap[first]:
                first = n
        for k in range(k_count):
            admissible[k] = False
            friendly[k] = False
            person[k] = first
            meet[k] = 0.0
        return admissible, friendly, meet, person, True
    sweep = braking_sweep(px, py, heading, speed_now, achieved, dv, dw, dt, substeps)
    t_count = sweep[0].shape[1]
    h = dt / substeps
    horizon = h * (t_count - 1)
    base, growth, near = _near_people(
        sweep[8], horizon, velocities_obs, now, position_sigma, velocity_sigma, margin, k_sigma, accel, friendly_mode
    )
    any_near = False
    for n in range(n_count):
        any_near = any_near or near[n]
    if friendly_mode:
        _unfriendly_at_rest(friendly, sweep, positions_obs, velocities_obs, base, growth, near, accel)
    if not any_near:
        return admissible, friendly, meet, person, contact
    people = (now[5], base, growth, position_sigma, k_sigma)
    _first_meetings(meet, person, sweep, substeps, h, positions_obs, velocities_obs, people, near, accel, towards_only)
    for k in range(k_count):
        admissible[k] = not math.isfinite(meet[k])
        friendly[k] = friendly[k] and admissible[k]
    return admissible, friendly, meet, person, contact


@njit(cache=True, nogil=True)
def achieved_first_period(commands, speed, turn_rate, max_speed, max_turn_rate, dv, dw):
    """:func:`viapath.safety.shield.achieved_first_period` (dv, dw: the speed and turn-rate steps of one period)."""
    k_count = commands.shape[0]
    out = np.empty((k_count, 2))
    for k in range(k_count):
        v = commands[k, 0]
        w = commands[k, 1]
        v_cmd = _clip(v if math.isfinite(v) else 0.0, 0.0, max_speed)
        w_cmd = _clip(w if math.isfinite(w) else 0.0, -max_turn_rate, max_turn_rate)
        if not (math.isfinite(v) and math.isfinite(w)):
            v_cmd = 0.0
            w_cmd = 0.0
        out[k, 0] = speed + _clip(v_cmd - speed, -dv, dv)
        out[k, 1] = turn_rate + _clip(w_cmd - turn_rate, -dw, dw)
    return out


@njit(cache=True, nogil=True)
def _finite_people(positions_obs, velocities_obs, radii, position_sigma, velocity_sigma):
    """The rows :meth:`viapath.observation.Obstacles.finite` keeps (no NaN or infinite field, radius >= 0)."""
    n_all = positions_obs.shape[0]
    keep = np.empty(n_all, dtype=np.bool_)
    kept = 0
    for n in range(n_all):
        keep[n] = (
            math.isfinite(positions_obs[n, 0])
            and math.isfinite(positions_obs[n, 1])
            and math.isfinite(velocities_obs[n, 0])
            and math.isfinite(velocities_obs[n, 1])
            and math.isfinite(radii[n])
            and radii[n] >= 0
            and math.isfinite(position_sigma[n])
            and math.isfinite(velocity_sigma[n])
        )
        kept += keep[n]
    if kept == n_all:
        return positions_obs, velocities_obs, radii, position_sigma, velocity_sigma
    p = np.empty((kept, 2))
    v = np.empty((kept, 2))
    r = np.empty(kept)
    sp = np.empty(kept)
    sv = np.empty(kept)
    i = 0
    for n in range(n_all):
        if keep[n]:
            p[i, 0] = positions_obs[n, 0]
            p[i, 1] = positions_obs[n, 1]
            v[i, 0] = velocities_obs[n, 0]
            v[i, 1] = velocities_obs[n, 1]
            r[i] = radii[n]
            sp[i] = position_sigma[n]
            sv[i] = velocity_sigma[n]
            i += 1
    return p, v, r, sp, sv


@njit(cache=True, nogil=True)
def _linspace(start, stop, num):
    """np.linspace(start, stop, num) for num >= 2, bit for bit (i * step + start, the last one stop)."""
    out = np.empty(num)
    div = num - 1
    delta = stop - start
    step = delta / div
    for i in range(num):
        if step == 0:
            out[i] = i / div * delta + start
        else:
            out[i] = i * step + start
    out[num - 1] = stop
    return out


@njit(cache=True, nogil=True)
def candidates(robot, limits, command, samples, dt):
    """:meth:`viapath.safety.shield.Shield.candidates` (K, 2) and their achieved (v, ω) (K, 2)."""
    dv = limits[1] * dt
    dw = limits[3] * dt
    corners_in = np.empty((2, 2))
    corners_in[0, 0] = 0.0
    corners_in[0, 1] = -limits[2]
    corners_in[1, 0] = limits[0]
    corners_in[1, 1] = limits[2]
    corners = achieved_first_period(corners_in, robot[3], robot[4], limits[0], limits[2], dv, dw)
    n = samples
    v = _linspace(corners[0, 0], corners[1, 0], n)
    w = _linspace(corners[0, 1], corners[1, 1], n)
    planner = np.empty((1, 2))
    planner[0, 0] = command[0]
    planner[0, 1] = command[1]
    planner_reached = achieved_first_period(planner, robot[3], robot[4], limits[0], limits[2], dv, dw)
    out = np.empty((2 + 2 * n + n * n, 2))
    out[0, 0] = command[0]
    out[0, 1] = command[1]
    out[1, 0] = 0.0
    out[1, 1] = 0.0
    for i in range(n):
        out[2 + i, 0] = v[i]
        out[2 + i, 1] = planner_reached[0, 1]
        out[2 + n + i, 0] = planner_reached[0, 0]
        out[2 + n + i, 1] = w[i]
        for j in range(n):
            out[2 + 2 * n + i * n + j, 0] = v[i]
            out[2 + 2 * n + i * n + j, 1] = w[j]
    reached = achieved_first_period(out, robot[3], robot[4], limits[0], limits[2], dv, dw)
    return out, reached


@njit(cache=True, nogil=True)
def shield(
    robot,
    limits,
    commands,
    search_window,
    samples,
    chunk,
    positions_obs,
    velocities_obs,
    radii,
    position_sigma,
    velocity_sigma,
    settings,
    friendly_mode,
    towards_only,
):
    """The one compiled entry of the shield (one entry links :func:`evaluate` once: two entries cost
    seconds more of compilation). ``robot``: x, y, heading, speed, turn rate, radius; ``limits``:
    max speed, max accel, max turn rate, max turn accel; ``settings``: dt, substeps, margin, k sigma,
    person accel. The people's rows with a non-finite field (or a negative radius) are dropped as
    :meth:`viapath.observation.Obstacles.finite` does (``person`` counts the rows kept).

    ``search_window`` False: :meth:`viapath.safety.shield.Shield.evaluate` of the K raw
    ``commands``: returns their achieved (v, ω), admissible, friendly, meet time, person, contact
    (then -1, -1, 0, 0).

    ``search_window`` True: the window search of :meth:`viapath.safety.shield.Shield.filter` when the
    planner's command ``commands[0]`` fails: candidates closest first (each axis over its limit,
    ties to the slower, then to the lower row, as np.lexsort), tested in the reference's chunks
    (np.array_split into ceil(L / chunk) pieces), stopping after the first chunk holding a wanted
    (friendly, or admissible) one. Returns the candidates' achieved (v, ω), the last chunk's
    verdicts, then the wanted pick's row (-1: none), the first admissible row of the first chunk
    holding one (-1: none), the candidates tested and the admissible among them."""
    dt = settings[0]
    dv = limits[1] * dt
    dw = limits[3] * dt
    positions_obs, velocities_obs, radii, position_sigma, velocity_sigma = _finite_people(
        positions_obs, velocities_obs, radii, position_sigma, velocity_sigma
    )
    if search_window:
        command = np.empty(2)
        command[0] = commands[0, 0]
        command[1] = commands[0, 1]
        candidate_commands, reached = candidates(robot, limits, command, samples, dt)
        k_count = candidate_commands.shape[0]
        scale_v = max(limits[0], 1e-9)
        scale_w = max(limits[2], 1e-9)
        distance = np.empty(k_count)
        for k in range(k_count):
            a = (reached[k, 0] - reached[0, 0]) / scale_v
            b = (reached[k, 1] - reached[0, 1]) / scale_w
            distance[k] = a * a + b * b
        # Stable insertion sort on (distance, achieved speed), the planner's own row left out.
        order = np.empty(k_count - 1, dtype=np.int64)
        count = 0
        for k in range(1, k_count):
            i = count
            while i > 0:
                o = order[i - 1]
                if distance[o] > distance[k] or (distance[o] == distance[k] and reached[o, 0] > reached[k, 0]):
                    order[i] = o
                    i -= 1
                else:
                    break
            order[i] = k
            count += 1  # noqa: SIM113 (the insertion sort's sorted length, read at the top of each step)
        total = k_count - 1
        sections = max(1, (total + chunk - 1) // chunk)
    else:
        reached = achieved_first_period(commands, robot[3], robot[4], limits[0], limits[2], dv, dw)
        total = reached.shape[0]
        order = np.empty(total, dtype=np.int64)
        for k in range(total):
            order[k] = k
        sections = 1
    size, extra = total // sections, total % sections
    start = 0
    tested = 0
    passing = 0
    passive_pick = -1
    admissible, friendly, meet, person = _all_clear(0)
    contact = False
    for section in range(sections):
        length = size + 1 if section < extra else size
        rows = order[start : start + length]
        start += length
        achieved = np.empty((length, 2))
        for i in range(length):
            achieved[i, 0] = reached[rows[i], 0]
            achieved[i, 1] = reached[rows[i], 1]
        if positions_obs.shape[0] == 0:
            admissible, friendly, meet, person = _all_clear(length)
            contact = False
        else:
            admissible, friendly, meet, person, contact = evaluate(
                robot[0],
                robot[1],
                robot[2],
                robot[3],
                robot[5],
                achieved,
                limits[1],
                dv,
                dw,
                dt,
                int(settings[1]),
                positions_obs,
                velocities_obs,
                radii,
                position_sigma,
                velocity_sigma,
                settings[2],
                settings[3],
                settings[4],
                friendly_mode,
                towards_only,
            )
        if not search_window:
            return reached, admissible, friendly, meet, person, contact, -1, -1, 0, 0
        tested += length
        for i in range(length):
            passing += admissible[i]
        for i in range(length):
            if friendly[i] if friendly_mode else admissible[i]:
                return reached, admissible, friendly, meet, person, contact, rows[i], passive_pick, tested, passing
        if passive_pick < 0:
            for i in range(length):
                if admissible[i]:
                    passive_pick = rows[i]
                    break
    return reached, admissible, friendly, meet, person, contact, -1, passive_pick, tested, passing
