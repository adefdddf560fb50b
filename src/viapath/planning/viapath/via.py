"""The via points of the paper's §3: where a person's avoiding line, left or right,
meets the robot's reachable cone in x-y-t, for each (start, person) pair of a cycle; and the legs to them. A compiled
step, the one implementation; :mod:`.packing` packs the cycle's arrays for it. The formula itself (stable form) is
:func:`viapath.geometry.via_times`'s, written here as one scalar loop.
"""

from __future__ import annotations

import math

import numpy as np

from viapath.jit import compiled


@compiled(inline=True)
def via_pair(sx, sy, t0, speed, ox, oy, vx, vy, via_radius, growth, until, envelope_m, t_via, w_via):
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
    """The compiled form of :func:`viapath.geometry.via_options` (tangent points, via times on both
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
        if not via_pair(
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
