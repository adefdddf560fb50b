"""The corridor's free space on a grid, flooded: where the static world lets the robot's centre go.

Source: docs/design.md §10 (a closed way: drive to the farthest point along the path that the static world
lets the robot reach and wait there; the same flood tells whether a subgoal is reachable at all). The paper
draws its path boundary round static things and has no such step; what follows is ours.

* **Cells.** Square cells of ``CELL_M`` (5 cm) on a lattice fixed in the world (cell centres at integer
  multiples of the cell size), over the corridor's bounding box clipped to a window of ``WINDOW_M`` round
  the robot (its edges on multiples of ``TILE_M``, so the window stays put while the robot moves inside a
  tile). Static geometry reaches the planner within the guard's static range (12 m at least), so the window
  holds no space the planner knows nothing of except past that range.
* **Free.** A cell is free when its centre lies inside the corridor and farther than its check radius from
  the centre of every static disc (the discs the guard samples along the static segments, radius robot +
  disc + safety margin: the leg checks' own numbers). The discs cover the segments' capsules with ρ to
  spare (:mod:`viapath.static`), so a free cell's centre is farther than robot + margin from every static
  segment, and a centre farther than robot + margin + ρ from all of them is free: the grid
  under-approximates the free space by at most ρ (about 1 cm) at the cell centres.
* **Moves.** Eight neighbours; a diagonal step only when both cells it passes beside are free too (no
  cutting a blocked corner). Between two free centres 5 cm apart a disc of radius r can reach in by at most
  h²/(8r), under a millimetre here: the robot itself only ever drives legs the planner has checked exactly.
* **Rest.** A cell is a resting place when it is free with ``rest_gap_m`` more clearance (``blocked_gap_m``:
  where the robot waits before a closed door).
* **Cached.** The corridor's cells are kept per path and window; the free cells and their connected
  components (one flood of all cells, compiled) per window and static content (the static discs' centres and radii, compared
  as bytes: the guard hands the planner discs sampled from the static layer, the same ones while the layer is
  the same); the distances to a
  target (Dijkstra, steps of one cell or √2 cells) per target cell. While the static world and the window
  stay the same, asking again costs a comparison of the discs' bytes and a few look-ups.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from viapath.jit import compiled
from viapath.path import DesignatedPath

CELL_M = 0.05  # the grid's cell size
WINDOW_M = 10.0  # the grid reaches at least this far from the robot (within the corridor's bounding box)
TILE_M = 2.0  # the window's edges lie on multiples of this (it moves in steps of a tile)
SEED_M = 0.15  # a robot whose own cell is not free starts from the nearest free cell this close
_KEPT_DISTANCES = 8  # distance fields kept per free space (targets)


@compiled
def mark_blocked(
    x0: float, y0: float, cell_m: float, centres: np.ndarray, radii: np.ndarray, blocked: np.ndarray
) -> None:
    """Set ``blocked[j, i]`` for every cell whose centre ``(x0 + i·cell_m, y0 + j·cell_m)`` lies within
    ``radii[k]`` (inclusive) of ``centres[k]``, for every k."""
    ny, nx = blocked.shape
    for k in range(centres.shape[0]):
        cx, cy, r = centres[k, 0], centres[k, 1], radii[k]
        if not (r >= 0.0):
            continue
        # One cell beyond the bounds on each side: the distance test below decides, not the rounding here.
        i0 = max(0, int(math.floor((cx - r - x0) / cell_m)) - 1)
        i1 = min(nx - 1, int(math.ceil((cx + r - x0) / cell_m)) + 1)
        j0 = max(0, int(math.floor((cy - r - y0) / cell_m)) - 1)
        j1 = min(ny - 1, int(math.ceil((cy + r - y0) / cell_m)) + 1)
        r2 = r * r
        for j in range(j0, j1 + 1):
            dy = (y0 + j * cell_m) - cy
            for i in range(i0, i1 + 1):
                dx = (x0 + i * cell_m) - cx
                if dx * dx + dy * dy <= r2:
                    blocked[j, i] = True


@compiled
def label_components(free: np.ndarray, labels: np.ndarray) -> int:
    """Number the connected components of the free cells (eight neighbours, no diagonal step past a blocked
    cell) into ``labels`` (-1: not free); returns how many there are."""
    ny, nx = free.shape
    labels[:, :] = -1
    queue = np.empty(ny * nx, dtype=np.int64)
    count = 0
    for start in range(ny * nx):
        sj, si = start // nx, start % nx
        if not free[sj, si] or labels[sj, si] >= 0:
            continue
        labels[sj, si] = count
        head, tail = 0, 1
        queue[0] = start
        while head < tail:
            c = queue[head]
            head += 1
            cj, ci = c // nx, c % nx
            for dj in range(-1, 2):
                for di in range(-1, 2):
                    nj, ni = cj + dj, ci + di
                    if (dj == 0 and di == 0) or nj < 0 or nj >= ny or ni < 0 or ni >= nx:
                        continue
                    if not free[nj, ni] or labels[nj, ni] >= 0:
                        continue
                    if dj != 0 and di != 0 and not (free[cj, ni] and free[nj, ci]):
                        continue
                    labels[nj, ni] = count
                    queue[tail] = nj * nx + ni
                    tail += 1
        count += 1
    return count


@compiled
def distances_to(free: np.ndarray, target_j: int, target_i: int, cell_m: float, out: np.ndarray) -> None:
    """Shortest distances (m) from every free cell to the target cell over the moves of
    :func:`label_components` (a step costs its length: one cell or √2 cells); inf where it cannot be reached."""
    ny, nx = free.shape
    out[:, :] = np.inf
    out[target_j, target_i] = 0.0
    diagonal = cell_m * math.sqrt(2.0)
    heap = [(0.0, target_j * nx + target_i)]
    while len(heap) > 0:
        d, c = heapq.heappop(heap)
        cj, ci = c // nx, c % nx
        if d > out[cj, ci]:
            continue
        for dj in range(-1, 2):
            for di in range(-1, 2):
                nj, ni = cj + dj, ci + di
                if (dj == 0 and di == 0) or nj < 0 or nj >= ny or ni < 0 or ni >= nx or not free[nj, ni]:
                    continue
                if dj != 0 and di != 0:
                    if not (free[cj, ni] and free[nj, ci]):
                        continue
                    step = diagonal
                else:
                    step = cell_m
                nd = d + step
                if nd < out[nj, ni]:
                    out[nj, ni] = nd
                    heapq.heappush(heap, (nd, nj * nx + ni))


@compiled
def descend(free: np.ndarray, distance: np.ndarray, start_j: int, start_i: int, route: np.ndarray) -> int:
    """The cells (j, i) from the start cell down the distance field to its zero, into ``route``; returns
    how many (0 when the start cannot reach the target)."""
    ny, nx = free.shape
    if not np.isfinite(distance[start_j, start_i]):
        return 0
    cj, ci = start_j, start_i
    count = 0
    route[0, 0], route[0, 1] = cj, ci
    count = 1
    while distance[cj, ci] > 0.0 and count < route.shape[0]:
        best_j, best_i, best = cj, ci, distance[cj, ci]
        for dj in range(-1, 2):
            for di in range(-1, 2):
                nj, ni = cj + dj, ci + di
                if (dj == 0 and di == 0) or nj < 0 or nj >= ny or ni < 0 or ni >= nx or not free[nj, ni]:
                    continue
                if dj != 0 and di != 0 and not (free[cj, ni] and free[nj, ci]):
                    continue
                if distance[nj, ni] < best:
                    best_j, best_i, best = nj, ni, distance[nj, ni]
        if best_j == cj and best_i == ci:
            break
        cj, ci = best_j, best_i
        route[count, 0], route[count, 1] = cj, ci
        count += 1
    return count


@dataclass
class Corridor:
    """The cells of a window over a path's corridor: which centres lie inside, and where each projects on
    the path (arc length, distance from the path line)."""

    x0: float
    y0: float
    inside: np.ndarray  # (ny, nx) bool
    arc_m: np.ndarray  # (ny, nx)
    offset_m: np.ndarray  # (ny, nx) |lateral|

    @classmethod
    def of(cls, path: DesignatedPath, low: tuple[int, int], high: tuple[int, int], cell_m: float) -> Corridor:
        """Cells ``low`` to ``high`` (lattice indices, inclusive) of the lattice of ``cell_m``."""
        xs = np.arange(low[0], high[0] + 1) * cell_m
        ys = np.arange(low[1], high[1] + 1) * cell_m
        points = np.stack(np.meshgrid(xs, ys), axis=-1)  # (ny, nx, 2)
        part, offset_m = _near_part(path, np.array([xs[0], ys[0]]), np.array([xs[-1], ys[-1]]))
        if part is None:
            empty = np.zeros(points.shape[:2])
            return cls(float(xs[0]), float(ys[0]), np.zeros(points.shape[:2], dtype=bool), empty, empty)
        _, arc, lateral = part.project(points)
        inside = part.corridor_excess(points) <= 0.0
        return cls(float(xs[0]), float(ys[0]), inside, arc + offset_m, np.abs(lateral))


def _near_part(path: DesignatedPath, low: np.ndarray, high: np.ndarray) -> tuple[DesignatedPath | None, float]:
    """The run of ``path``'s segments from the first to the last whose corridor capsule meets the box
    [low, high], as a path of its own, and the arc length where it starts (None: no segment meets it). A
    cell outside every such capsule is outside the corridor; so a window over a long path costs the
    segments near it only."""
    starts, ends = path.segment_starts, path.segment_starts + path.segment_vectors
    grow = path.half_widths_m[:, None]
    meets = ((np.minimum(starts, ends) - grow <= high) & (np.maximum(starts, ends) + grow >= low)).all(axis=1)
    near = np.flatnonzero(meets)
    if len(near) == 0:
        return None, 0.0
    first, last = int(near[0]), int(near[-1])
    if first == 0 and last == len(path.half_widths_m) - 1:
        return path, 0.0
    part = DesignatedPath(path.waypoints[first : last + 2], half_widths_m=path.half_widths_m[first : last + 1])
    return part, float(path.cumulative_length_m[first])


@dataclass
class FreeSpace:
    """One flood of the corridor's free space (see the module docstring)."""

    corridor: Corridor
    cell_m: float
    free: np.ndarray  # (ny, nx) bool
    rest: np.ndarray  # (ny, nx) bool: free with the rest gap to spare
    labels: np.ndarray  # (ny, nx) int64: connected component, -1 not free
    _distances: dict[tuple[int, int], np.ndarray] = field(default_factory=dict)
    _farthest: dict[int, tuple[int, int] | None] = field(default_factory=dict)

    @classmethod
    def of(
        cls, corridor: Corridor, cell_m: float, centres: np.ndarray, radii: np.ndarray, rest_radii: np.ndarray
    ) -> FreeSpace:
        shape = corridor.inside.shape
        blocked = np.zeros(shape, dtype=bool)
        mark_blocked(corridor.x0, corridor.y0, cell_m, _c2(centres), _c1(radii), blocked)
        free = corridor.inside & ~blocked
        mark_blocked(corridor.x0, corridor.y0, cell_m, _c2(centres), _c1(rest_radii), blocked)
        rest = corridor.inside & ~blocked
        labels = np.empty(shape, dtype=np.int64)
        label_components(free, labels)
        return cls(corridor, cell_m, free, rest, labels)

    @property
    def shape(self) -> tuple[int, int]:
        return self.free.shape

    def centre(self, cell: tuple[int, int]) -> np.ndarray:
        """The world position of cell (j, i)'s centre."""
        return np.array([self.corridor.x0 + cell[1] * self.cell_m, self.corridor.y0 + cell[0] * self.cell_m])

    def cell_of(self, point: np.ndarray) -> tuple[int, int] | None:
        """The cell (j, i) whose centre is nearest to ``point``; None outside the grid."""
        i = int(round((float(point[0]) - self.corridor.x0) / self.cell_m))
        j = int(round((float(point[1]) - self.corridor.y0) / self.cell_m))
        ny, nx = self.shape
        if not (0 <= i < nx and 0 <= j < ny):
            return None
        return j, i

    def seed(self, point: np.ndarray, within_m: float = SEED_M) -> tuple[int, int] | None:
        """The free cell the flood starts from for a robot at ``point``: its own cell if free, else the free
        cell nearest to it within ``within_m``; None when there is none."""
        return self._nearest(point, within_m, component=None)

    def reaches(self, start: tuple[int, int], point: np.ndarray, within_m: float) -> tuple[int, int] | None:
        """The cell of ``start``'s component nearest to ``point`` within ``within_m`` (None: no such cell):
        whether the robot can get there through the static world."""
        return self._nearest(point, within_m, component=int(self.labels[start]))

    def _nearest(self, point: np.ndarray, within_m: float, component: int | None) -> tuple[int, int] | None:
        """The cell of ``component`` whose centre is nearest to ``point`` within ``within_m``; None: none. With no
        component: the nearest free cell, the point's own cell first when free (its centre is within half a
        cell's diagonal of the point)."""
        x = (float(point[0]) - self.corridor.x0) / self.cell_m
        y = (float(point[1]) - self.corridor.y0) / self.cell_m
        if not (math.isfinite(x) and math.isfinite(y)):
            return None
        ny, nx = self.shape
        if component is None:
            own_i, own_j = int(round(x)), int(round(y))
            if 0 <= own_i < nx and 0 <= own_j < ny and self.free[own_j, own_i]:
                return own_j, own_i
        reach = int(math.ceil(within_m / self.cell_m))
        i0, i1 = max(0, int(math.floor(x)) - reach), min(nx - 1, int(math.ceil(x)) + reach)
        j0, j1 = max(0, int(math.floor(y)) - reach), min(ny - 1, int(math.ceil(y)) + reach)
        if i0 > i1 or j0 > j1:
            return None
        jj, ii = np.mgrid[j0 : j1 + 1, i0 : i1 + 1]
        gap = np.hypot(ii - x, jj - y) * self.cell_m
        if component is None:
            allowed = self.free[j0 : j1 + 1, i0 : i1 + 1]
        else:
            allowed = self.labels[j0 : j1 + 1, i0 : i1 + 1] == component
        ok = allowed & (gap <= within_m + 1e-9)
        if not ok.any():
            return None
        k = int(np.argmin(np.where(ok, gap, np.inf)))
        return int(jj.flat[k]), int(ii.flat[k])

    def farthest(self, start: tuple[int, int]) -> tuple[int, int] | None:
        """The resting cell of ``start``'s component farthest along the path (the largest arc length, to the
        cell; among those the nearest to the path line); None when the component has no resting cell."""
        component = int(self.labels[start])
        if component in self._farthest:
            return self._farthest[component]
        mine = (self.labels == component) & self.rest
        found: tuple[int, int] | None = None
        if mine.any():
            arc = np.where(mine, np.floor(self.corridor.arc_m / self.cell_m + 1e-9), -np.inf)
            best = arc == arc.max()
            k = int(np.argmin(np.where(best, self.corridor.offset_m, np.inf)))
            found = divmod(k, self.shape[1])
        self._farthest[component] = found
        return found

    def route(self, start: tuple[int, int], target: tuple[int, int]) -> np.ndarray:
        """The cell centres (K, 2) of a shortest way from ``start`` to ``target`` over free cells (empty when
        there is none)."""
        distance = self._distances.get(target)
        if distance is None:
            if len(self._distances) >= _KEPT_DISTANCES:
                self._distances.pop(next(iter(self._distances)))
            distance = np.empty(self.shape)
            distances_to(self.free, target[0], target[1], self.cell_m, distance)
            self._distances[target] = distance
        cells = np.empty((self.free.size, 2), dtype=np.int64)
        count = descend(self.free, distance, start[0], start[1], cells)
        cells = cells[:count]
        return np.stack(
            [self.corridor.x0 + cells[:, 1] * self.cell_m, self.corridor.y0 + cells[:, 0] * self.cell_m], axis=1
        )


class FloodCache:
    """The last corridor window and the last free space made from it (see the module docstring)."""

    def __init__(self, cell_m: float = CELL_M, window_m: float = WINDOW_M, tile_m: float = TILE_M) -> None:
        self.cell_m, self.window_m, self.tile_m = cell_m, window_m, tile_m
        self._corridor: tuple[Any, ...] | None = None
        self._box: tuple[Any, ...] | None = None
        self._free: tuple[Any, ...] | None = None

    def window(self, path: DesignatedPath, position: np.ndarray) -> tuple[tuple[int, int], tuple[int, int]] | None:
        """The lattice indices (low, high) of the cells round ``position``: the corridor's bounding box within
        ``window_m`` of it, the window's edges on multiples of ``tile_m``; None when they do not meet."""
        box = self._box
        if box is None or box[0] is not path:
            widest = float(np.max(path.half_widths_m))
            box = self._box = (path, path.waypoints.min(axis=0) - widest, path.waypoints.max(axis=0) + widest)
        box_low, box_high = box[1], box[2]
        tile = self.tile_m
        near_low = np.floor((position - self.window_m) / tile) * tile
        near_high = np.ceil((position + self.window_m) / tile) * tile
        low = np.ceil(np.maximum(box_low, near_low) / self.cell_m - 1e-9).astype(np.int64)
        high = np.floor(np.minimum(box_high, near_high) / self.cell_m + 1e-9).astype(np.int64)
        if (high < low).any():
            return None
        return (int(low[0]), int(low[1])), (int(high[0]), int(high[1]))

    def free_space(
        self,
        path: DesignatedPath,
        position: np.ndarray,
        centres: np.ndarray,
        radii: np.ndarray,
        rest_radii: np.ndarray,
    ) -> FreeSpace | None:
        """The free space of ``path``'s corridor round ``position`` outside the discs (``radii``; resting cells
        outside ``rest_radii`` too); None when ``position`` is not finite or no cell lies near it."""
        if not np.isfinite(position).all():
            return None
        window = self.window(path, np.asarray(position, dtype=float))
        if window is None:
            return None
        corridor = self._corridor
        if corridor is None or corridor[0] is not path or corridor[1] != window:
            corridor = self._corridor = (path, window, Corridor.of(path, *window, self.cell_m))
            self._free = None
        # The static content itself is the key (a comparison of bytes, no chance of two contents meeting).
        content = (_c2(centres).tobytes(), _c1(radii).tobytes(), _c1(rest_radii).tobytes())
        free = self._free
        if free is None or free[0] != content:
            free = self._free = (content, FreeSpace.of(corridor[2], self.cell_m, centres, radii, rest_radii))
        return free[1]


def _c2(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(values, dtype=np.float64).reshape(-1, 2))


def _c1(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(values, dtype=np.float64).reshape(-1))
