"""The static world: everything the robot can touch that does not move (docs/design.md §10).

Source: docs/design.md §10 (a static obstacle is a vertical prism in the paper's x-y-t space, velocity 0);
the shapes come from a known map (walls, boxes, polygons) or from scan returns no person explains.

Representation, and why: a :class:`StaticLayer` is a set of **segments** (M, 2, 2) in the world
frame, each with a shape id (a point is a segment of length 0). Segments are what maps and scans
give (a wall, a box's edges, a run of scan returns), and the exact distance from a point or a
segment to them is closed form (:func:`segment_distances`), which the simulator's contact count uses.

The planner, the guard and the shield check the robot against **discs** sampled along the segments
(:func:`sample_discs`): a static disc is an obstacle of velocity 0, so every x-y-t check that exists
for people (legs against oblique cylinders, via points on avoiding lines, the braking sweep) is
already exact for it, on the numpy and the compiled paths alike, and no planner needs a second kind
of obstacle. The sampling is conservative by a known, small amount: along a segment cut into pieces
of length ``h`` (at most ``spacing_m``), discs of radius ``ρ = sqrt(r² + (h/2)²) − r`` at the piece
ends, inflated by any ``R ≥ r``, cover the segment's capsule of radius R (a point within R of the
segment is within ``sqrt(R² + (h/2)²) ≤ R + ρ`` of the nearest sample). With the robot radius r =
0.25 m and h = 0.1 m, ρ = 5 mm. Discs of one shape carry the shape's id, so the planner's way round
a wall keeps its name from cycle to cycle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from viapath.jit import compiled

# Static obstacles' ids in a merged obstacle set: far above any tracker's ids, so the two never meet.
STATIC_ID_BASE = 1 << 40
# m: how far geometry may lie from a segment (a map cell's half-diagonal, a scan polyline's error). A
# larger one is no measurement: a 1e300 m radius would cover the world and pin the robot.
MAX_STATIC_RADIUS_M = 10.0
# discs a layer keeps sampled between cycles at most (a map); beyond, the guard samples the window only.
MAX_CACHED_DISCS = 2_000_000


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.array(array, copy=True)
    array.setflags(write=False)
    return array


@dataclass(frozen=True)
class StaticLayer:
    """Static segments in the world frame; ``shape_ids`` groups them (a box's four edges share one)."""

    segments: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 2)))  # (M, 2, 2) m
    shape_ids: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))  # (M,)
    # (M,) m: how far the geometry may lie from each segment (a polyline simplified from scan returns); 0: exact
    radii_m: np.ndarray | None = None

    def __post_init__(self) -> None:
        try:
            segments = np.asarray(self.segments, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(
                f"static.segments: expected an (M, 2, 2) array of [[x1, y1], [x2, y2]] rows, found {self.segments!r}"[
                    :300
                ]
            ) from None
        if segments.size == 0:
            segments = np.zeros((0, 2, 2))
        if segments.ndim != 3 or segments.shape[1:] != (2, 2):
            raise ValueError(
                f"static.segments: expected an (M, 2, 2) array of [[x1, y1], [x2, y2]] rows, "
                f"found shape {segments.shape}"
            )
        try:
            ids = np.asarray(self.shape_ids).reshape(-1)
            if ids.size and not (ids.dtype.kind in "iu" or (ids.dtype.kind == "f" and np.all(ids == np.round(ids)))):
                raise TypeError("not integers")
            ids = ids.astype(np.int64)
        except (TypeError, ValueError, OverflowError):
            raise ValueError(
                f"static.shape_ids: expected integers, one per segment, found {self.shape_ids!r}"[:300]
            ) from None
        if ids.size == 0 and len(segments):
            ids = np.arange(len(segments), dtype=np.int64)
        if ids.shape != (len(segments),):
            raise ValueError(f"static.shape_ids: expected {len(segments)} ids (one per segment), found {ids.size}")
        # Copies, read-only: a layer's caches (its discs) follow its contents only if they never change.
        object.__setattr__(self, "segments", _frozen(segments))
        object.__setattr__(self, "shape_ids", _frozen(ids))
        if self.radii_m is not None:
            try:
                radii = np.broadcast_to(np.asarray(self.radii_m, dtype=float), (len(segments),))
            except (TypeError, ValueError):
                raise ValueError(
                    f"static.radii_m: expected {len(segments)} numbers (one per segment) or one number, "
                    f"found {self.radii_m!r}"[:300]
                ) from None
            if not (np.isfinite(radii).all() and (radii >= 0).all() and (radii <= MAX_STATIC_RADIUS_M).all()):
                worst = radii[~(np.isfinite(radii) & (radii >= 0) & (radii <= MAX_STATIC_RADIUS_M))][0]
                raise ValueError(
                    f"static.radii_m: expected finite numbers in [0, {MAX_STATIC_RADIUS_M:g}] m, found {worst:g}"
                )
            object.__setattr__(self, "radii_m", _frozen(radii))

    def __len__(self) -> int:
        return len(self.segments)

    @classmethod
    def empty(cls) -> StaticLayer:
        return _EMPTY

    @classmethod
    def of_shapes(cls, shapes: list[np.ndarray]) -> StaticLayer:
        """One shape per item, each an (E, 2, 2) array of its edges."""
        shapes = [np.asarray(s, dtype=float).reshape(-1, 2, 2) for s in shapes]
        if not shapes:
            return _EMPTY
        ids = np.concatenate([np.full(len(s), k, dtype=np.int64) for k, s in enumerate(shapes)])
        return cls(np.concatenate(shapes), ids)

    def near(self, centre: np.ndarray, reach_m: float) -> StaticLayer:
        """The segments that may come within ``reach_m`` of ``centre`` (a superset): the whole layer when it
        is small; for a large one (a map) the segments in the cells of a uniform grid that the square round
        ``centre`` touches, and every segment too long, too far out or too wide for one cell. The index is
        built once per layer, and the subset is kept while the square covers the same cells, so the discs
        sampled from it carry over from cycle to cycle."""
        if len(self) < NEAR_INDEX_MIN_SEGMENTS:
            return self
        index = self.__dict__.get("_near_index")
        if index is None:
            index = _grid_index(self)
            object.__setattr__(self, "_near_index", index)
        keys, order, always = index
        cx, cy = (float(c) for c in centre)
        if not (math.isfinite(cx) and math.isfinite(cy)):
            return self
        grow = reach_m + _CELL_M
        x0, x1 = math.floor((cx - grow) / _CELL_M), math.floor((cx + grow) / _CELL_M)
        y0, y1 = math.floor((cy - grow) / _CELL_M), math.floor((cy + grow) / _CELL_M)
        key = (x0, x1, y0, y1)
        cached = self.__dict__.get("_near")
        if cached is not None and cached[0] == key:
            return cached[1]
        rows = np.arange(x0, x1 + 1, dtype=np.int64) * _KEY_SPAN
        first = np.searchsorted(keys, rows + (y0 + _KEY_OFFSET), side="left")
        last = np.searchsorted(keys, rows + (y1 + _KEY_OFFSET), side="right")
        picked = [order[a:b] for a, b in zip(first.tolist(), last.tolist()) if b > a]
        chosen = np.sort(np.concatenate([always, *picked])) if picked else always
        subset = self.subset(chosen)
        object.__setattr__(self, "_near", (key, subset))
        return subset

    def finite_mask(self) -> np.ndarray:
        """(M,) bool: segments whose coordinates are all finite."""
        return np.isfinite(self.segments).all(axis=(1, 2))

    def split_wide(self, bound_m: float, longest_m: float) -> tuple[StaticLayer, StaticLayer]:
        """(plain, wide): ``wide`` are the segments longer than ``longest_m`` or with a coordinate beyond
        ``bound_m`` (and every segment when the plain ones would sample into more than
        ``MAX_CACHED_DISCS`` discs): what the guard clips to a window round the robot each cycle instead
        of sampling once. Kept for the last arguments asked."""
        key = (float(bound_m), float(longest_m))
        cached = self.__dict__.get("_split")
        if cached is None or cached[0] != key:
            with np.errstate(invalid="ignore", over="ignore"):
                lengths = np.hypot(*(self.segments[:, 1] - self.segments[:, 0]).T)  # inf past the largest float
                wide = ~((np.abs(self.segments) <= bound_m).all(axis=(1, 2)) & (lengths <= longest_m))
            parts = self.__dict__.get("_parts")
            if not wide.any():
                split = (self, _EMPTY)
            elif parts is not None:  # the parts' splits, joined: the plain part keeps its parts' discs
                (plain_a, wide_a), (plain_b, wide_b) = (part.split_wide(bound_m, longest_m) for part in parts[:2])
                split = (plain_a.concatenate(plain_b), wide_a.concatenate(wide_b))
            elif wide.all() or float(lengths[~wide].sum()) / 0.05 > MAX_CACHED_DISCS:
                split = (_EMPTY, self)
            else:
                split = (self.subset(~wide), self.subset(wide))
            cached = (key, split)
            object.__setattr__(self, "_split", cached)
        return cached[1]

    def finite(self) -> StaticLayer:
        """Without segments that have a NaN or infinite coordinate (a bad row says nothing about where
        something is; scanners report 'no return' that way). Kept (the layer is read-only): a map's layer is
        made finite beside the control loop, and asking again in the loop costs nothing (2 000 000 segments:
        about 70 ms)."""
        cached = self.__dict__.get("_finite")  # True: this layer is finite (no reference to itself: no cycle)
        if cached is not None:
            return self if cached is True else cached
        ok = np.isfinite(self.segments).all(axis=(1, 2))
        if ok.all():
            object.__setattr__(self, "_finite", True)
            return self
        finite = self.subset(ok)
        object.__setattr__(finite, "_finite", True)
        object.__setattr__(self, "_finite", finite)
        return finite

    def subset(self, mask_or_index: Any) -> StaticLayer:
        return StaticLayer(
            self.segments[mask_or_index],
            self.shape_ids[mask_or_index],
            None if self.radii_m is None else self.radii_m[mask_or_index],
        )

    @property
    def padding_m(self) -> np.ndarray:
        return np.zeros(len(self.segments)) if self.radii_m is None else self.radii_m

    def concatenate(self, other: StaticLayer) -> StaticLayer:
        if len(other) == 0:
            return self
        if len(self) == 0:
            return other
        offset = int(self.shape_ids.max()) + 1 - int(other.shape_ids.min())
        radii = (
            None
            if self.radii_m is None and other.radii_m is None
            else np.concatenate([self.padding_m, other.padding_m])
        )
        joined = StaticLayer(
            np.concatenate([self.segments, other.segments]),
            np.concatenate([self.shape_ids, other.shape_ids + offset]),
            radii,
        )
        # Its discs are its parts' (each kept by its part: a map joined with each cycle's scan returns
        # is sampled once, not every cycle).
        object.__setattr__(joined, "_parts", (self, other, offset))
        return joined

    def discs(self, robot_radius_m: float, spacing_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:func:`sample_discs` of this layer, kept for the last (radius, spacing) asked: a map is the same
        object cycle after cycle."""
        key = (float(robot_radius_m), float(spacing_m))
        cached = self.__dict__.get("_discs")
        parts = self.__dict__.get("_parts")
        if parts is not None and (cached is None or cached[0] != key):
            first, second, offset = parts
            a, b = first.discs(*key), second.discs(*key)
            joined = (np.concatenate([a[0], b[0]]), np.concatenate([a[1], b[1]]), np.concatenate([a[2], b[2] + offset]))
            cached = (key, joined)
            object.__setattr__(self, "_discs", cached)
        if cached is None or cached[0] != key:
            centres, radii, ids, owner = sample_discs(self.segments, self.shape_ids, *key, with_owner=True)
            if self.radii_m is not None:
                radii = radii + self.radii_m[owner]
            cached = (key, (centres, radii, ids))
            object.__setattr__(self, "_discs", cached)
        return cached[1]


_EMPTY = StaticLayer()

# A layer with this many segments (a map) is indexed on a grid of cells of _CELL_M for StaticLayer.near.
NEAR_INDEX_MIN_SEGMENTS = 20_000
_CELL_M = 16.0
_KEY_OFFSET = 1 << 30  # cell y index offset into the key (cells within ±2^30, i.e. ±1.7e10 m)
_KEY_SPAN = 1 << 31


def _grid_index(layer: StaticLayer) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(sorted cell keys, the segments in that order, segments always included): a segment is filed under
    the cell of its first end when it is no longer than a cell and its padding is below a cell (so the
    square grown by one cell finds it); any other is always included."""
    a, b = layer.segments[:, 0], layer.segments[:, 1]
    with np.errstate(invalid="ignore", over="ignore"):
        lengths = np.hypot(*(b - a).T)
        cells = np.floor(a / _CELL_M)
        fits = (
            (lengths <= _CELL_M)
            & (layer.padding_m <= _CELL_M / 4)
            & (np.abs(cells) < _KEY_OFFSET - 1).all(axis=1)
            & np.isfinite(a).all(axis=1)
        )
    filed = np.flatnonzero(fits)
    cells = cells[filed].astype(np.int64)
    keys = cells[:, 0] * _KEY_SPAN + (cells[:, 1] + _KEY_OFFSET)
    order = np.argsort(keys, kind="stable")
    return keys[order], filed[order], np.flatnonzero(~fits)


def sample_discs(
    segments: np.ndarray, shape_ids: np.ndarray, robot_radius_m: float, spacing_m: float, with_owner: bool = False
) -> tuple[np.ndarray, ...]:
    """Disc centres (N, 2), radii (N,) and shape ids (N,) covering ``segments`` for any robot radius of at
    least ``robot_radius_m`` (see the module docstring); a segment of length 0 is one disc of radius 0.
    With ``with_owner`` also the segment of each disc (N,)."""
    if len(segments) == 0:
        empty = (np.zeros((0, 2)), np.zeros(0), np.zeros(0, dtype=np.int64))
        return (*empty, np.zeros(0, dtype=np.int64)) if with_owner else empty
    a, b = segments[:, 0], segments[:, 1]
    lengths = np.hypot(*(b - a).T)
    pieces = np.maximum(np.ceil(lengths / spacing_m - 1e-9), 1).astype(np.int64)
    pieces[lengths == 0] = 0
    counts = pieces + 1
    counts[lengths == 0] = 1
    # A polyline's segments share their ends: the second copy of a shared end is left out.
    shared = np.zeros(len(segments), dtype=bool)
    shared[1:] = (
        (segments[1:, 0] == segments[:-1, 1]).all(axis=1) & (shape_ids[1:] == shape_ids[:-1]) & (pieces[1:] > 0)
    )
    owner = np.repeat(np.arange(len(segments)), counts)
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    k = np.arange(len(owner)) - np.repeat(start, counts)
    fraction = np.where(pieces[owner] > 0, k / np.maximum(pieces[owner], 1), 0.0)
    centres = a[owner] + fraction[:, None] * (b - a)[owner]
    unique = ~(shared[owner] & (k == 0))
    if not unique.all():
        centres, owner = centres[unique], owner[unique]
    half_piece = np.where(pieces > 0, lengths / np.maximum(pieces, 1), 0.0) / 2
    r = float(robot_radius_m)
    pad = np.sqrt(r * r + half_piece**2) - r
    if with_owner:
        return centres, pad[owner], shape_ids[owner], owner
    return centres, pad[owner], shape_ids[owner]


def point_segment_distances(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(P, M) exact distances from points (P, 2) to segments (M, 2, 2)."""
    a, b = segments[None, :, 0], segments[None, :, 1]
    d = b - a
    dd = np.einsum("pmi,pmi->pm", d, d)
    rel = points[:, None, :] - a
    t = np.clip(np.einsum("pmi,pmi->pm", rel, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    closest = rel - t[..., None] * d
    return np.hypot(closest[..., 0], closest[..., 1])


def segment_distances(starts: np.ndarray, ends: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(P, M) exact distances between the segments ``starts[p]``–``ends[p]`` (e.g. the robot centre's motion in
    one step) and the static segments (M, 2, 2). Two segments that do not cross are closest at an end of
    one of them; crossing ones are at distance 0."""
    if len(segments) == 0:
        return np.full((len(starts), 0), np.inf)
    moving = np.stack([starts, ends], axis=1)
    distance = np.minimum(point_segment_distances(starts, segments), point_segment_distances(ends, segments))
    distance = np.minimum(distance, point_segment_distances(segments[:, 0], moving).T)
    distance = np.minimum(distance, point_segment_distances(segments[:, 1], moving).T)
    p, r = starts[:, None, :], (ends - starts)[:, None, :]
    q, s = segments[None, :, 0], (segments[:, 1] - segments[:, 0])[None]
    denominator = r[..., 0] * s[..., 1] - r[..., 1] * s[..., 0]
    qp = q - p
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (qp[..., 0] * s[..., 1] - qp[..., 1] * s[..., 0]) / denominator
        u = (qp[..., 0] * r[..., 1] - qp[..., 1] * r[..., 0]) / denominator
    crossing = (denominator != 0) & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)
    return np.where(crossing, 0.0, distance)


@compiled
def _merged_shapes(
    segments: np.ndarray, shape: np.ndarray, padding: np.ndarray, gap_m: float, parent: np.ndarray
) -> None:
    """:func:`merge_close_shapes`' grouping: ``parent[k]`` = the smallest shape whose bounding box (grown by its
    largest padding and half the gap) is linked to shape ``k``'s through overlapping boxes (``shape``: each
    segment's shape, 0 to K - 1)."""
    count = parent.shape[0]
    low = np.full((count, 2), np.inf)
    high = np.full((count, 2), -np.inf)
    grow = np.zeros(count)
    for m in range(segments.shape[0]):
        k = shape[m]
        for end in range(2):
            for axis in range(2):
                low[k, axis] = min(low[k, axis], segments[m, end, axis])
                high[k, axis] = max(high[k, axis], segments[m, end, axis])
        grow[k] = max(grow[k], padding[m])
    for k in range(count):
        parent[k] = k
        for axis in range(2):
            low[k, axis] = low[k, axis] - grow[k] - gap_m / 2
            high[k, axis] = high[k, axis] + grow[k] + gap_m / 2
    for i in range(count):  # union-find over the overlapping pairs, the larger root under the smaller
        for j in range(i + 1, count):
            if (
                low[i, 0] <= high[j, 0]
                and low[j, 0] <= high[i, 0]
                and low[i, 1] <= high[j, 1]
                and low[j, 1] <= high[i, 1]
            ):
                a, b = i, j
                while parent[a] != a:
                    a = parent[a]
                while parent[b] != b:
                    b = parent[b]
                if a != b:
                    parent[max(a, b)] = min(a, b)
    for k in range(count):
        root = k
        while parent[root] != root:
            root = parent[root]
        parent[k] = root


def box_edges(center: ArrayLike, size: ArrayLike, yaw_rad: float = 0.0) -> np.ndarray:
    """The four edges (4, 2, 2) of a rectangle of ``size`` (length along ``yaw_rad``, width) at ``center``."""
    half = np.asarray(size, dtype=float) / 2
    corners = np.array([[half[0], half[1]], [-half[0], half[1]], [-half[0], -half[1]], [half[0], -half[1]]])
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    corners = corners @ np.array([[c, s], [-s, c]]) + np.asarray(center, dtype=float)
    return polygon_edges(corners)


def polygon_edges(points: ArrayLike) -> np.ndarray:
    """The closed outline (E, 2, 2) of a polygon given by its vertices (E, 2)."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    return np.stack([points, np.roll(points, -1, axis=0)], axis=1)


def polyline_edges(points: ArrayLike) -> np.ndarray:
    """The open polyline (E - 1, 2, 2) through ``points`` (E, 2)."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    return np.stack([points[:-1], points[1:]], axis=1)


def merge_close_shapes(layer: StaticLayer, gap_m: float) -> StaticLayer:
    """The layer with shapes whose bounding boxes come within ``gap_m`` of each other given one id (the
    smallest): pieces of one thing seen as several (two scanners' views of a box, a wall broken by a
    shadow) are one shape to go round. Bounding boxes overlap more often than shapes do; a merged shape
    is only ever a larger thing to go round, never a smaller one."""
    if len(layer) == 0:
        return layer
    ids, inverse = np.unique(layer.shape_ids, return_inverse=True)
    if len(ids) == 1:
        return layer
    parent = np.empty(len(ids), dtype=np.int64)
    _merged_shapes(layer.segments, inverse.reshape(-1), layer.padding_m, float(gap_m), parent)
    return StaticLayer(layer.segments, ids[parent][inverse], layer.radii_m)
