"""A dense polyline (a Nav2 path of 100 000 poses) simplified to the fewest of its points within a tolerance, in
time linear in their number whatever their shape.

Sources: Douglas and Peucker (1973), the recursive split at the farthest point (keeps the corners where they
are); Zhao and Saalfeld (1997), the sector ("sleeve") test, one pass.

What we chose:
* Douglas-Peucker while its work stays within ``DOUGLAS_PEUCKER_WORK`` point distances per point; a zig-zag makes
  it quadratic, and then the sleeve, whose work is linear.
* Distances are to the segment, not its line: a point beyond the segment's end (the path turns back) is not near it.
* Both steps are compiled (:func:`viapath.jit.compiled`, eagerly, for float64 arrays): they run without the GIL,
  so a worker thread simplifying a long path does not hold up the control loop of the same process, and their
  first call costs no compilation.
"""

from __future__ import annotations

import math

import numpy as np

from viapath.jit import compiled

DOUGLAS_PEUCKER_WORK = 40  # point distances per point: about log2 of a million-point path's depth, twice
REPEAT_M = 1e-6  # a point closer than this to the next is a repeat of it (the later is kept)


@compiled(signature="Tuple((boolean[::1], boolean))(float64[::1], float64[::1], float64, int64)")
def _douglas_peucker_keep(xs, ys, tolerance_m, budget):
    """(which points Douglas-Peucker keeps, whether it finished within ``budget`` point distances)."""
    n = len(xs)
    keep = np.zeros(n, dtype=np.bool_)
    keep[0] = True
    keep[n - 1] = True
    starts = np.empty(2 * n + 2, dtype=np.int64)
    ends = np.empty(2 * n + 2, dtype=np.int64)
    starts[0], ends[0], top = 0, n - 1, 1
    while top > 0:
        top -= 1
        i, j = starts[top], ends[top]
        if j <= i + 1:
            continue
        budget -= j - i
        if budget < 0:
            return keep, False
        ax, ay = xs[i], ys[i]
        dx, dy = xs[j] - ax, ys[j] - ay
        length2 = dx * dx + dy * dy
        farthest, at = -1.0, i + 1
        for k in range(i + 1, j):
            rx, ry = xs[k] - ax, ys[k] - ay
            along = 0.0
            if length2 >= 1e-24:
                along = min(max((rx * dx + ry * dy) / length2, 0.0), 1.0)
            distance = math.hypot(rx - along * dx, ry - along * dy)
            if distance > farthest:
                farthest, at = distance, k
        if farthest > tolerance_m:
            keep[at] = True
            starts[top], ends[top] = i, at
            starts[top + 1], ends[top + 1] = at, j
            top += 2
    return keep, True


@compiled(signature="int64[::1](float64[::1], float64[::1], float64)")
def _sleeve_keep(xs, ys, tolerance_m):
    """The indices the sleeve keeps (see :func:`sleeve_simplify`), increasing."""
    n = len(xs)
    keep = np.empty(n, dtype=np.int64)
    keep[0], count = 0, 1
    anchor, low, high, farthest, reference = 0, -math.inf, math.inf, 0.0, 0.0
    k = 1
    while k < n:
        dx, dy = xs[k] - xs[anchor], ys[k] - ys[anchor]
        distance = math.hypot(dx, dy)
        if distance <= tolerance_m and farthest <= tolerance_m:
            k += 1
            continue
        direction = math.atan2(dy, dx)
        if low == -math.inf:  # the first point out of the kept point's own disc sets the sector
            reference = direction
        inside = True
        if low != -math.inf:
            offset = math.atan2(math.sin(direction - reference), math.cos(direction - reference))
            inside = low <= offset <= high and distance >= farthest - 1e-12
        if not inside:
            anchor = k - 1
            keep[count] = anchor
            count += 1
            low, high, farthest = -math.inf, math.inf, 0.0
            continue  # the same point again, from the new kept point
        offset = math.atan2(math.sin(direction - reference), math.cos(direction - reference))
        half = math.asin(min(1.0, tolerance_m / distance)) if distance > tolerance_m else math.pi
        low, high = max(low, offset - half), min(high, offset + half)
        farthest = max(farthest, distance)
        k += 1
    if keep[count - 1] != n - 1:
        keep[count] = n - 1
        count += 1
    return keep[:count].copy()


def simplify_polyline(points, tolerance_m: float) -> np.ndarray:
    """The fewest of ``points`` (first and last kept) within ``tolerance_m`` of all, in time linear in their
    number whatever their shape: Douglas-Peucker while its work stays within ``DOUGLAS_PEUCKER_WORK`` point
    distances per point, else :func:`sleeve_simplify`."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(points) <= 2 or tolerance_m <= 0:
        return _without_repeats(points)
    xs, ys = np.ascontiguousarray(points[:, 0]), np.ascontiguousarray(points[:, 1])
    keep, finished = _douglas_peucker_keep(xs, ys, float(tolerance_m), DOUGLAS_PEUCKER_WORK * len(points))
    if not finished:
        return sleeve_simplify(points, tolerance_m)
    return _without_repeats(points[keep])


def sleeve_simplify(points, tolerance_m: float) -> np.ndarray:
    """Points of the polyline left out where every left-out point lies within ``tolerance_m`` of the segment
    that replaces it (first and last kept), in one pass: linear in the number of points.

    A sleeve from the last kept point (the sector test): each further point narrows the sector of directions
    whose ray passes within ``tolerance_m`` of it; a point outside the sector, or nearer to the kept point than
    one before it (the path turns back), keeps the point before it. A left-out point is then within the
    tolerance of the ray and not beyond the segment's end, hence of the segment. Points within the tolerance of
    the kept point leave the sector as it is."""
    points = _without_repeats(np.asarray(points, dtype=float).reshape(-1, 2))
    if len(points) <= 2 or tolerance_m <= 0:
        return points
    xs, ys = np.ascontiguousarray(points[:, 0]), np.ascontiguousarray(points[:, 1])
    return points[_sleeve_keep(xs, ys, float(tolerance_m))]


def _without_repeats(points: np.ndarray) -> np.ndarray:
    """Drop repeated points (a path that stands still: closer than ``REPEAT_M``), keeping the last."""
    if len(points) < 2:
        return points
    step = np.hypot(*np.diff(points, axis=0).T)
    return np.vstack([points[:-1][step > REPEAT_M], points[-1:]])
