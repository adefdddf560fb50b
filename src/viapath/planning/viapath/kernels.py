"""The compiled hot path of the viapath planner (extra ``fast``: numba): the same arithmetic as the
numpy reference, one scalar loop instead of a few dozen array operations.

Source: the profile of ``benchmarks/bench_planner.py`` (docs/speed.md): per cycle the planner spends
most of its time in (1) the leg-against-people checks, :func:`viapath.geometry.legs_first_contact`,
called a handful of times per cycle on K legs × N people, and (2) the roll-outs of
:func:`viapath.kinematics.track` (a Python loop of 20 steps, up to ``max_rollouts`` times a cycle).
Both are pure functions of arrays, so they are compiled here, operation for operation as the numpy
code does them (same order of additions, same roots), so that the decisions are the same
(``tests/planning/test_backends.py`` checks it on random observations).

Choices:
* Only imported when numba is importable (:mod:`viapath.planning.viapath.backend` decides);
  every kernel is a plain module-level ``@njit(cache=True)`` function, so numba's on-disk cache
  works and a process after the first pays no compilation (docs/speed.md gives the first run's cost).
* Inputs are C-contiguous float64 arrays (the caller makes them so): one compiled signature each.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _contact(px, py, vx, vy, radius, growth, duration, with_growth):
    """Scalar :func:`viapath.geometry._first_contact`: first τ in [0, duration] with
    |p + v τ| <= radius + growth τ; inf if none, 0 if already touching."""
    if with_growth:
        a = vx * vx + vy * vy - growth * growth
        b = px * vx + py * vy - radius * growth
    else:
        a = vx * vx + vy * vy
        b = px * vx + py * vy
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


@njit(cache=True, nogil=True)
def legs_first_contact(starts, start_times, velocities, durations, obstacle_positions, obstacle_velocities,
                       radii, growth, growth_until_s):
    """(K, N) first contact of K legs with N moving discs whose radius grows as a capped cone: the
    numba twin of :func:`viapath.geometry.legs_first_contact` (all arguments arrays, one value per
    obstacle for ``radii``, ``growth`` and ``growth_until_s``)."""
    k_count = starts.shape[0]
    n_count = obstacle_positions.shape[0]
    out = np.empty((k_count, n_count))
    any_growth = False
    any_finite_until = False
    for j in range(n_count):
        if growth[j] != 0.0:
            any_growth = True
        if math.isfinite(growth_until_s[j]):
            any_finite_until = True
    cylinder_only = (not any_growth) or (not any_finite_until)
    for k in range(k_count):
        t0 = start_times[k]
        duration = durations[k]
        for j in range(n_count):
            ovx = obstacle_velocities[j, 0]
            ovy = obstacle_velocities[j, 1]
            px = starts[k, 0] - (obstacle_positions[j, 0] + ovx * t0)
            py = starts[k, 1] - (obstacle_positions[j, 1] + ovy * t0)
            vx = velocities[k, 0] - ovx
            vy = velocities[k, 1] - ovy
            g = growth[j]
            if cylinder_only:
                out[k, j] = _contact(px, py, vx, vy, radii[j] + g * t0, g, duration, any_growth)
                continue
            until = growth_until_s[j]
            cone_duration = until - t0
            if cone_duration < 0.0:
                cone_duration = 0.0
            if cone_duration > duration:
                cone_duration = duration
            early = _contact(px, py, vx, vy, radii[j] + g * (t0 if t0 < until else until),
                             g if until > t0 else 0.0, cone_duration, True)
            if math.isfinite(early):
                out[k, j] = early
                continue
            if t0 + duration >= until:
                full_growth = g * (until if math.isfinite(until) else 0.0)
                late = _contact(px + vx * cone_duration, py + vy * cone_duration, vx, vy, radii[j] + full_growth,
                                0.0, duration - cone_duration, False)
                out[k, j] = late + cone_duration
            else:
                out[k, j] = math.inf
    return out


@njit(cache=True, nogil=True)
def _clip(value, low, high):
    return low if value < low else high if value > high else value


@njit(cache=True, nogil=True)
def track(x, y, heading, speed, turn, target_x, target_y, speed_mps, max_speed_mps, max_turn_rate_radps,
          max_accel_mps2, max_turn_accel_radps2, dt_s, steps, heading_gain):
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
