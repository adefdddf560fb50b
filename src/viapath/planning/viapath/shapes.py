"""Static shapes in the candidate tree (docs/design.md §10): a static disc a leg meets stands for its whole shape.
Compiled steps of :mod:`.tree`, the one implementation of each.

Source: beyond the paper, which draws its path boundary round static things and plans for moving ones only. A
static obstacle is a vertical prism in x-y-t, sampled as discs of velocity 0 that share their shape's id
(:mod:`viapath.static`); the tree checks legs against them as against people, and what is ours is:

* the root branches once per shape a leg meets (:func:`one_per_shape`: each shape's earliest disc), not on
  the many discs of one wall;
* the via points of a (node, static disc) pair are those of the two discs of that disc's shape that reach
  furthest left and right as seen from the node (:func:`extremes`: the tangents to the shape's inflated
  outline are the tangents to its extreme discs), so a chain goes round the whole shape
  (:func:`round_static_shapes`);
* a node that hugs a static disc (closer than ``hug_factor`` via radii) also slides (:func:`slide`): a leg of
  one via radius at right angles to the way to the disc, on each side. From so close the tangents lie a few
  centimetres away and the nearest disc is both extremes of its shape; the slide moves the node along the
  surface to where the extremes mean something again.

Static legs are checked to their end, past the horizon, and without the braking envelope (:mod:`.legs`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from viapath.jit import compiled
from viapath.planning.viapath.records import N_X, N_Y

# A node closer to a static disc than this many times its via radius hugs it (:func:`slide`).
HUG_FACTOR = 1.25


class StaticShapes(NamedTuple):
    """The cycle's static shapes as the compiled steps take them. Empty arrays: no static geometry."""

    shape_of: np.ndarray  # (N,) int64: each obstacle's shape (0..S-1), -1 for a person
    members: np.ndarray  # (D,) int64: the static discs, shape by shape, in obstacle order within a shape
    offsets: np.ndarray  # (S + 1,) int64: shape s's discs are members[offsets[s]:offsets[s + 1]]
    hug_factor: float  # :data:`HUG_FACTOR`


def static_shapes(is_static: np.ndarray, ids: np.ndarray) -> StaticShapes:
    """The shapes of a cycle's obstacles: the static rows grouped by their id (a shape's discs share it)."""
    rows = np.flatnonzero(is_static)
    if len(rows) == 0:
        return NO_SHAPES
    labels, inverse = np.unique(np.asarray(ids)[rows], return_inverse=True)
    shape_of = np.full(len(is_static), -1, dtype=np.int64)
    shape_of[rows] = inverse
    order = np.argsort(inverse, kind="stable")
    offsets = np.zeros(len(labels) + 1, dtype=np.int64)
    np.cumsum(np.bincount(inverse, minlength=len(labels)), out=offsets[1:])
    return StaticShapes(shape_of, rows[order].astype(np.int64), offsets, float(HUG_FACTOR))


NO_SHAPES = StaticShapes(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(1, np.int64), HUG_FACTOR)


@compiled
def one_per_shape(free_now, contact_now, shapes):
    """The root's contacts (K, N) with only the earliest discs of each static shape kept per blocked leg (the
    others inf): the root branches on the shapes a leg meets. A shape's earliest is the minimum over its discs
    that any blocked leg meets (NaN if one of those is NaN for this leg); discs equal to it are kept (ties)."""
    k_count, n_count = contact_now.shape
    shape_of = shapes.shape_of
    kept = contact_now.copy()
    hit = np.zeros(n_count, np.bool_)
    for k in range(k_count):
        if free_now[k]:
            continue
        blocked = False
        for j in range(n_count):
            blocked = blocked or math.isfinite(contact_now[k, j])
        if not blocked:
            continue
        for j in range(n_count):
            if shape_of[j] >= 0 and math.isfinite(contact_now[k, j]):
                hit[j] = True
    earliest = np.empty(shapes.offsets.shape[0] - 1)
    for k in range(k_count):
        for j in range(n_count):
            if hit[j]:
                earliest[shape_of[j]] = math.inf
        for j in range(n_count):
            if hit[j]:
                value, low = contact_now[k, j], earliest[shape_of[j]]
                earliest[shape_of[j]] = math.nan if (value != value or low != low) else min(value, low)
        for j in range(n_count):
            if hit[j] and contact_now[k, j] != earliest[shape_of[j]]:  # (NaN differs from everything)
                kept[k, j] = math.inf
    return kept


@compiled
def extremes(sx, sy, obstacle, positions, via_radii, shapes):
    """The discs of ``obstacle``'s shape whose via discs reach furthest to the left and to the right as seen from
    (sx, sy); the obstacle itself twice when (sx, sy) is within some disc's via radius of the shape."""
    shape = shapes.shape_of[obstacle]
    first, last = shapes.offsets[shape], shapes.offsets[shape + 1]
    reference = math.atan2(positions[obstacle, 1] - sy, positions[obstacle, 0] - sx)
    left, right = obstacle, obstacle
    best_left, best_right = 0.0, 0.0
    for q in range(first, last):
        j = shapes.members[q]
        ox, oy = positions[j, 0] - sx, positions[j, 1] - sy
        distance = math.hypot(ox, oy)
        if distance <= via_radii[j]:
            return obstacle, obstacle
        relative = (math.atan2(oy, ox) - reference + math.pi) % (2 * math.pi) - math.pi
        half = math.asin(via_radii[j] / distance)
        if q == first or relative + half > best_left:  # the first of equals, as np.argmax
            best_left, left = relative + half, j
        if q == first or relative - half < best_right:
            best_right, right = relative - half, j
    return left, right


@compiled
def round_static_shapes(nf, branch, positions, via_radii, shapes):
    """The (node, obstacle) pairs of :func:`.tree._branch_pairs` with each static disc replaced by its shape's
    two :func:`extremes` as seen from the node; pairs of people stay as they are; a pair made twice is kept
    once, where first made (a node's pairs are together). Returns the new pairs as ``branch`` holds them."""
    pair_nodes, pair_obstacles, pairs = branch
    nodes = np.empty(2 * pairs, np.int64)
    obstacles = np.empty(2 * pairs, np.int64)
    made = 0
    for p in range(pairs):
        node, j = pair_nodes[p], pair_obstacles[p]
        if shapes.shape_of[j] < 0:
            left, right = j, j
        else:
            left, right = extremes(nf[node, N_X], nf[node, N_Y], j, positions, via_radii, shapes)
        for obstacle in (left, right):
            seen = False
            q = made - 1
            while q >= 0 and nodes[q] == node and not seen:
                seen = obstacles[q] == obstacle
                q -= 1
            if not seen:
                nodes[made], obstacles[made] = node, obstacle
                made += 1
    return nodes, obstacles, made


@compiled(inline=True)
def hugs(sx, sy, cx, cy, via_radius, hug_factor):
    """Whether a node at (sx, sy) hugs the static disc at (cx, cy): closer than ``hug_factor`` via radii, not on
    its centre."""
    distance = math.hypot(cx - sx, cy - sy)
    return distance < hug_factor * via_radius and distance > 0


@compiled(inline=True)
def slide(sx, sy, cx, cy, via_radius, speed, side):
    """The slide of a node at (sx, sy) that :func:`hugs` the static disc at (cx, cy), to one side (+1 left, -1
    right of the way to the disc): its duration, velocity (x, y) and end (x, y)."""
    ox, oy = cx - sx, cy - sy
    distance = math.hypot(ox, oy)
    step_x = (-(oy / distance) * side) * via_radius
    step_y = ((ox / distance) * side) * via_radius
    duration = via_radius / speed
    return duration, step_x / duration, step_y / duration, sx + step_x, sy + step_y
