"""The corridor's free space on a grid (planning/viapath/flood.py) against brute force: which cells are free,
which are reachable, how far, and the cache."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests._sizes import cases
from viapath.path import DesignatedPath
from viapath.planning.viapath.flood import Corridor, FloodCache, FreeSpace
from viapath.static import point_segment_distances, sample_discs

CELL = 0.05


def _space(path, centres, radii, rest_radii=None, low=None, high=None) -> FreeSpace:
    waypoints = path.waypoints
    widest = float(np.max(path.half_widths_m))
    low = low or tuple(int(v) for v in np.ceil((waypoints.min(axis=0) - widest) / CELL - 1e-9))
    high = high or tuple(int(v) for v in np.floor((waypoints.max(axis=0) + widest) / CELL + 1e-9))
    corridor = Corridor.of(path, low, high, CELL)
    return FreeSpace.of(corridor, CELL, centres, radii, radii if rest_radii is None else rest_radii)


def _cell_centres(space: FreeSpace) -> np.ndarray:
    ny, nx = space.shape
    jj, ii = np.mgrid[0:ny, 0:nx]
    return np.stack([space.corridor.x0 + ii * CELL, space.corridor.y0 + jj * CELL], axis=-1)


def _random_discs(rng, count, low=(0.0, -1.0), high=(4.0, 1.0)):
    centres = rng.uniform(low, high, size=(count, 2))
    radii = rng.uniform(0.05, 0.45, size=count)
    return centres, radii


def _moves(free: np.ndarray, j: int, i: int):
    """The brute force's moves: the eight neighbours, a diagonal only past two free cells."""
    ny, nx = free.shape
    for dj in (-1, 0, 1):
        for di in (-1, 0, 1):
            nj, ni = j + dj, i + di
            if (dj, di) == (0, 0) or not (0 <= nj < ny and 0 <= ni < nx) or not free[nj, ni]:
                continue
            if dj and di and not (free[j, ni] and free[nj, i]):
                continue
            yield nj, ni, math.hypot(dj, di) * CELL


def _reachable_brute_force(free: np.ndarray, start) -> np.ndarray:
    """Every cell some sequence of moves reaches from ``start``: relax until nothing changes."""
    reached = np.zeros_like(free)
    reached[start] = True
    changed = True
    while changed:
        changed = False
        for j, i in zip(*np.nonzero(reached), strict=True):
            for nj, ni, _ in _moves(free, j, i):
                if not reached[nj, ni]:
                    reached[nj, ni] = changed = True
    return reached


def _distances_brute_force(free: np.ndarray, target) -> np.ndarray:
    """Bellman-Ford over the moves (a step costs its length)."""
    distance = np.full(free.shape, np.inf)
    distance[target] = 0.0
    for _ in range(free.size):
        changed = False
        for j, i in zip(*np.nonzero(np.isfinite(distance)), strict=True):
            for nj, ni, step in _moves(free, j, i):
                if distance[j, i] + step < distance[nj, ni] - 1e-12:
                    distance[nj, ni] = distance[j, i] + step
                    changed = True
        if not changed:
            break
    return distance


@pytest.mark.parametrize("seed", range(cases(6, 30)))
def test_a_cell_is_free_iff_its_centre_is_in_the_corridor_and_clear_of_every_disc(seed):
    rng = np.random.default_rng(seed)
    path = DesignatedPath([[0.0, 0.0], [2.5, 0.0], [2.5, 2.0]], half_width_m=rng.uniform(0.5, 1.0))
    centres, radii = _random_discs(rng, 12, (-0.5, -1.0), (3.5, 2.5))
    space = _space(path, centres, radii, radii + 0.3)
    points = _cell_centres(space)
    gap = np.hypot(*(points[:, :, None, :] - centres).transpose(3, 0, 1, 2)) - radii  # (ny, nx, discs)
    inside = path.corridor_excess(points) <= 0.0
    assert np.array_equal(space.free, inside & (gap > 0).all(axis=-1))
    assert np.array_equal(space.rest, inside & (gap > 0.3).all(axis=-1))
    assert space.free.any() and (~space.free & inside).any()  # both verdicts drawn


@pytest.mark.parametrize("seed", range(cases(4, 20)))
def test_free_cells_against_the_static_segments_the_discs_were_sampled_from(seed):
    """The discs the planner gets cover the segments' capsules with ρ to spare: a free centre is farther than
    the clearance from every segment, and a centre farther than clearance + ρ is free (the grid
    under-approximates the free space by at most ρ)."""
    rng = np.random.default_rng(seed)
    path = DesignatedPath([[0.0, 0.0], [4.0, 0.0]], half_width_m=1.0)
    starts = rng.uniform((0.0, -1.2), (4.0, 1.2), size=(5, 2))
    segments = np.stack([starts, starts + rng.uniform(-1.0, 1.0, size=(5, 2))], axis=1)
    robot, margin, spacing = 0.25, 0.05, 0.15
    centres, pad, _ = sample_discs(segments, np.arange(5), robot, spacing)
    clearance = robot + margin
    space = _space(path, centres, clearance + pad)
    points = _cell_centres(space).reshape(-1, 2)
    to_segments = point_segment_distances(points, segments).min(axis=1).reshape(space.shape)
    inside = space.corridor.inside
    assert (to_segments[space.free] > clearance).all()
    assert space.free[inside & (to_segments > clearance + pad.max())].all()
    assert space.free.any() and (inside & ~space.free).any()


@pytest.mark.parametrize("seed", range(cases(6, 30)))
def test_a_free_cell_is_reachable_iff_a_brute_force_path_reaches_it(seed):
    rng = np.random.default_rng(100 + seed)
    path = DesignatedPath([[0.0, 0.0], [1.5, 0.0]], half_width_m=0.6)
    centres, radii = _random_discs(rng, 6, (0.0, -0.6), (1.5, 0.6))
    radii = radii * 0.6
    space = _space(path, centres, radii)
    free_cells = np.argwhere(space.free)
    start = tuple(free_cells[rng.integers(len(free_cells))])
    reached = _reachable_brute_force(space.free, start)
    assert np.array_equal(space.labels == space.labels[start], reached)
    assert np.array_equal(space.labels >= 0, space.free)


def test_a_wall_across_the_corridor_parts_the_free_space_and_a_gap_joins_it():
    path = DesignatedPath([[0.0, 0.0], [3.0, 0.0]], half_width_m=0.5)
    wall = np.stack([np.full(21, 1.5), np.linspace(-0.5, 0.5, 21)], axis=1)
    closed = _space(path, wall, np.full(21, 0.1))
    before, after = closed.cell_of(np.array([0.5, 0.0])), closed.cell_of(np.array([2.5, 0.0]))
    assert closed.labels[before] >= 0 and closed.labels[after] >= 0
    assert closed.labels[before] != closed.labels[after]
    assert closed.reaches(before, np.array([2.5, 0.0]), 0.1) is None
    assert len(closed.route(before, after)) == 0
    # a 0.3 m gap in it: the free cells through it are those farther than 0.1 m from every disc
    gap = np.abs(wall[:, 1]) > 0.25
    opened = _space(path, wall[gap], np.full(int(gap.sum()), 0.1))
    assert opened.labels[before] == opened.labels[after]
    assert opened.reaches(before, np.array([2.5, 0.0]), 0.1) is not None


@pytest.mark.parametrize("seed", range(cases(3, 12)))
def test_distances_and_routes_are_the_shortest_over_the_moves(seed):
    rng = np.random.default_rng(200 + seed)
    path = DesignatedPath([[0.0, 0.0], [1.2, 0.0]], half_width_m=0.5)
    centres, radii = _random_discs(rng, 4, (0.2, -0.5), (1.0, 0.5))
    space = _space(path, centres, radii * 0.5)
    free_cells = np.argwhere(space.free)
    target = tuple(int(v) for v in free_cells[rng.integers(len(free_cells))])
    expected = _distances_brute_force(space.free, target)
    start = tuple(int(v) for v in free_cells[rng.integers(len(free_cells))])
    route = space.route(start, target)
    distance = space._distances[target]
    assert np.allclose(np.where(np.isfinite(expected), distance, 0), np.where(np.isfinite(expected), expected, 0))
    assert np.array_equal(np.isfinite(distance), np.isfinite(expected))
    if not np.isfinite(expected[start]):
        assert len(route) == 0
        return
    assert np.allclose(route[0], space.centre(start)) and np.allclose(route[-1], space.centre(target))
    cells = [space.cell_of(p) for p in route]
    for a, b in zip(cells[:-1], cells[1:], strict=True):  # every step a move, and the steps add up
        assert b in [(nj, ni) for nj, ni, _ in _moves(space.free, *a)]
    assert np.hypot(*np.diff(route, axis=0).T).sum() == pytest.approx(expected[start])


def test_the_farthest_resting_cell_is_the_one_farthest_along_the_path():
    path = DesignatedPath([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]], half_width_m=0.6)
    door = np.stack([np.linspace(1.4, 2.6, 25), np.full(25, 1.0)], axis=1)  # across the second segment
    space = _space(path, door, np.full(25, 0.05), np.full(25, 0.35))
    start = space.cell_of(np.array([0.2, 0.0]))
    found = space.farthest(start)
    mine = (space.labels == space.labels[start]) & space.rest
    arc = np.floor(space.corridor.arc_m / CELL + 1e-9)
    assert arc[found] == arc[mine].max()
    assert space.corridor.offset_m[found] == space.corridor.offset_m[mine & (arc == arc[found])].min()
    point = space.centre(found)
    assert 1.0 - 0.35 - CELL <= point[1] < 1.0 - 0.35  # just short of the door, its rest gap kept
    assert abs(point[0] - 2.0) <= CELL


def test_the_cache_keeps_the_flood_while_the_discs_and_the_window_stay():
    path = DesignatedPath([[0.0, 0.0], [30.0, 0.0]], half_width_m=1.0)
    cache = FloodCache()
    centres, radii = np.array([[3.0, 0.0]]), np.array([0.3])
    first = cache.free_space(path, np.array([0.1, 0.0]), centres, radii, radii + 0.3)
    assert cache.free_space(path, np.array([0.3, 0.1]), centres.copy(), radii.copy(), radii + 0.3) is first
    moved = cache.free_space(path, np.array([0.1, 0.0]), centres + [0.01, 0.0], radii, radii + 0.3)
    assert moved is not first and moved.free.sum() != 0
    # far along a long corridor the window moves with the robot: cells near it, none 14 m behind
    far = cache.free_space(path, np.array([20.0, 0.0]), centres, radii, radii + 0.3)
    assert far.cell_of(np.array([20.0, 0.0])) is not None and far.cell_of(np.array([6.0, 0.0])) is None
    assert cache.free_space(path, np.array([np.nan, 0.0]), centres, radii, radii) is None


def test_a_window_over_a_long_path_takes_the_segments_near_it_with_their_arc_length():
    """A zig-zag of 400 segments: the cells of a window near its middle are those of the whole path (inside
    the corridor, the same arc length and distance from the path line)."""
    x = np.arange(401) * 1.0
    path = DesignatedPath(np.stack([x, np.where(np.arange(401) % 2, 0.5, 0.0)], axis=1), half_width_m=0.8)
    low, high = (int(200.0 / CELL), int(-1.0 / CELL)), (int(203.0 / CELL), int(1.5 / CELL))
    corridor = Corridor.of(path, low, high, CELL)
    xs, ys = np.arange(low[0], high[0] + 1) * CELL, np.arange(low[1], high[1] + 1) * CELL
    points = np.stack(np.meshgrid(xs, ys), axis=-1)
    _, arc, lateral = path.project(points)
    assert np.array_equal(corridor.inside, path.corridor_excess(points) <= 0.0)
    inside = corridor.inside
    assert inside.any() and (~inside).any()
    assert np.allclose(corridor.arc_m[inside], arc[inside]) and np.allclose(
        corridor.offset_m[inside], np.abs(lateral)[inside]
    )
