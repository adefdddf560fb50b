"""The via points of the paper's §3: where a person's avoiding line, left or right,
meets the robot's reachable cone in x-y-t, for one (node, person) pair; the candidate tree (:mod:`.tree`) takes
them pair by pair, with the legs to them. A compiled step, the one implementation. The formula itself (stable
form) is :func:`viapath.geometry.via_times`'s, written here as one scalar loop.
"""

from __future__ import annotations

import math

from viapath.jit import compiled


@compiled(inline=True)
def via_pair(sx, sy, t0, speed, ox, oy, vx, vy, via_radius, growth, until, envelope_m, t_via, w_via):
    """The via options of one pair (a leg from (sx, sy) at t0 at ``speed``, the obstacle at (ox, oy) now
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
