"""Was an episode feasible at all? The robot's forward reachable set over the people's recorded future.

An evaluation tool, not part of the core: like :mod:`viapath.bench.avoidable` it reads where every person
*will* walk, which only holds for people who do not react to the robot (replays, generated people blind to
it). For them, the set of places the robot's centre could be at each step of the episode is grown on an
x-y-t grid:

* the robot moves at most ``top speed × dt`` per step in any direction: no acceleration or turn-rate
  limit, no heading (a relaxation of the drive);
* at every step its centre is inside the corridor, outside every person's disc inflated by the robot's
  radius (contact is a distance under the sum of the radii, as in :mod:`viapath.sim.metrics`) and at
  least the robot's radius from every static edge standing then.

The grid over-approximates that set, so an episode whose goal is not reached by the time limit is
proven infeasible for any robot on this drive, and the set's earliest arrival is a lower bound on the
time any such robot needs (the hindsight optimum of the time ratio):

* a cell is free when some point of it may be free: it is blocked only when it lies wholly inside one
  inflated disc or one static edge's capsule (both convex: all four corners inside), and it is in the
  corridor when its centre is within half a diagonal of it (the corridor's excess is 1-Lipschitz);
* constraints are checked at the step times only (the motion in between is free: more runs admitted),
  and a person blocks a sample only where a contact there would count (present at the step before or
  after too, as :mod:`viapath.sim.metrics` needs both ends of a step);
* what the set keeps per cell is a lower bound ``φ`` of the distance from the cell (its nearest point) to
  the true reachable set: at the start the exact distance to the start point, then
  ``φ_k = max(φ_{k-1} − v·dt, gap(cell, reachable cells at k))``, the gap being the exact distance between
  cell squares (a Euclidean distance transform of the reachable cells grown by one cell). Both terms
  are lower bounds, so their maximum is one; a free cell is reachable at step k + 1 when ``φ_k ≤ v·dt``.
  The first term carries the exact distance from every earlier set, so rounding does not add up from
  step to step: in an empty straight corridor the set's front is exact to one cell.

A goal cell is one whose square comes within the goal tolerance of the goal. The sweep is one compiled
loop (:func:`viapath.jit.compiled`) over the steps; a scenario's people come from its own models
(:func:`viapath.sim.obstacles.scenario_obstacle_states`) over the whole duration, not only until the
episode ended.

Where the method is silent: the robot's start is a point (its cell counts as reachable when free); the
set is given up when it is empty (every run of this drive has a contact by then: ``emptied_s``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from viapath.jit import compiled
from viapath.path import DesignatedPath
from viapath.static import point_segment_distances

DEFAULT_CELL_M = 0.1
# The bench's columns (viapath.bench.runner), and those of them that are flags.
FEASIBILITY_FLAGS = ("feasible", "success_feasible", "reach_feasible")
FEASIBILITY_COLUMNS = (*FEASIBILITY_FLAGS, "hindsight_time_s", "time_ratio_hindsight")
_FAR = 1e20  # "no reachable cell" in the squared distance transform


@dataclass(frozen=True)
class Grid:
    """Square cells of ``cell_m``; cell (row, column) spans x in origin_x + column·cell_m + [0, cell_m]
    and y likewise with the row."""

    origin_x: float
    origin_y: float
    cell_m: float
    rows: int
    columns: int

    @classmethod
    def around(cls, path: DesignatedPath, cell_m: float) -> Grid:
        reach = float(np.max(path.half_widths_m)) + cell_m
        low = path.waypoints.min(axis=0) - reach
        high = path.waypoints.max(axis=0) + reach
        columns, rows = (int(math.ceil(span / cell_m)) for span in high - low)
        return cls(float(low[0]), float(low[1]), float(cell_m), rows, columns)

    def centres(self) -> np.ndarray:
        """(rows, columns, 2) the centre of every cell."""
        x = self.origin_x + (np.arange(self.columns) + 0.5) * self.cell_m
        y = self.origin_y + (np.arange(self.rows) + 0.5) * self.cell_m
        return np.stack(np.meshgrid(x, y), axis=-1)

    def cell_of(self, points) -> tuple[np.ndarray, np.ndarray]:
        """(rows, columns) of the cells holding ``points`` (..., 2); -1 outside the grid."""
        points = np.asarray(points, dtype=float)
        column = np.floor((points[..., 0] - self.origin_x) / self.cell_m).astype(int)
        row = np.floor((points[..., 1] - self.origin_y) / self.cell_m).astype(int)
        inside = (row >= 0) & (row < self.rows) & (column >= 0) & (column < self.columns)
        return np.where(inside, row, -1), np.where(inside, column, -1)

    def distance_to_cells(self, point) -> np.ndarray:
        """(rows, columns) exact distance from ``point`` to each cell's square (0 inside it)."""
        gap = np.maximum(np.abs(self.centres() - np.asarray(point, dtype=float)) - 0.5 * self.cell_m, 0.0)
        return np.hypot(gap[..., 0], gap[..., 1])


@dataclass
class Reach:
    """The sweep's answer."""

    feasible: bool  # the goal is in the set by the last step
    arrival_s: float | None  # the set's earliest arrival (time from the sweep's first step)
    emptied_s: float | None  # the set became empty then: every run has a contact by that time
    steps: int  # steps swept (the first one included)
    grid: Grid
    dt_s: float
    history: np.ndarray | None = None  # (steps, rows, columns) reachable cells per step, when kept

    def contains(self, step: int, points) -> np.ndarray:
        """Whether each point (..., 2) lies in a reachable cell at ``step`` (needs ``keep``)."""
        if self.history is None:
            raise ValueError("the sweep kept no history: run it with keep=True")
        row, column = self.grid.cell_of(points)
        inside = row >= 0
        out = np.zeros(row.shape, dtype=bool)
        out[inside] = self.history[step][row[inside], column[inside]]
        return out


def forward_reachable(
    people: np.ndarray,
    people_radii_m: np.ndarray,
    robot_radius_m: float,
    path: DesignatedPath,
    start,
    top_speed_mps: float,
    dt_s: float,
    goal=None,
    goal_tolerance_m: float = 0.0,
    walls: np.ndarray | None = None,
    wall_until_s: np.ndarray | None = None,
    start_time_s: float = 0.0,
    cell_m: float = DEFAULT_CELL_M,
    keep: bool = False,
) -> Reach:
    """The reachable set from ``start`` (a point, at the first row of ``people``) over the rows of
    ``people`` (K, N, 2; NaN while absent), one every ``dt_s``. ``goal`` None: no arrival test, the set is
    swept to the last row (to see whether it empties). Static edges (W, 2, 2) stand while
    ``start_time_s + k·dt_s < wall_until_s``."""
    if not (top_speed_mps > 0 and dt_s > 0 and cell_m > 0):
        raise ValueError("top_speed_mps, dt_s and cell_m must be > 0")
    people = _contact_samples(np.asarray(people, dtype=float).reshape(len(people), -1, 2))
    reach = np.ascontiguousarray(np.asarray(people_radii_m, dtype=float).reshape(-1) + robot_radius_m)
    grid = Grid.around(path, cell_m)
    centres = grid.centres()
    corridor = path.corridor_excess(centres.reshape(-1, 2)).reshape(grid.rows, grid.columns) <= cell_m / math.sqrt(2)
    times = start_time_s + np.arange(len(people)) * dt_s
    blocked, index = _static_blocked(grid, centres, walls, wall_until_s, times, robot_radius_m)
    if goal is None:
        goal_cells = np.zeros((grid.rows, grid.columns), dtype=bool)
    else:
        goal_cells = grid.distance_to_cells(goal) <= goal_tolerance_m
    phi = grid.distance_to_cells(start)
    history = np.zeros((len(people) if keep else 1, grid.rows, grid.columns), dtype=bool)
    arrival, emptied, steps = _sweep(
        people,
        reach,
        blocked,
        index,
        corridor,
        goal_cells,
        phi,
        grid.origin_x,
        grid.origin_y,
        grid.cell_m,
        top_speed_mps * dt_s,
        keep,
        history,
    )
    return Reach(
        feasible=arrival >= 0,
        arrival_s=float(arrival * dt_s) if arrival >= 0 else None,
        emptied_s=float(emptied * dt_s) if emptied >= 0 else None,
        steps=int(steps),
        grid=grid,
        dt_s=dt_s,
        history=history[:steps] if keep else None,
    )


def _contact_samples(people: np.ndarray) -> np.ndarray:
    """The samples at which a person can be touched, the others NaN: the metrics count a contact in a step
    with the person present at both of its ends, so a sample with the person absent just before and just
    after blocks nothing."""
    present = np.isfinite(people).all(-1)
    neighbour = np.zeros_like(present)
    neighbour[1:] |= present[:-1]
    neighbour[:-1] |= present[1:]
    return np.ascontiguousarray(np.where((present & neighbour)[..., None], people, np.nan))


def _static_blocked(grid: Grid, centres, walls, until_s, times, robot_radius_m: float):
    """The cells wholly within the robot's radius of a standing static edge, one layer per set of standing
    edges (M, rows, columns), and the layer of each step (K,)."""
    walls = np.zeros((0, 2, 2)) if walls is None else np.asarray(walls, dtype=float).reshape(-1, 2, 2)
    until = np.full(len(walls), np.inf) if until_s is None else np.asarray(until_s, dtype=float).reshape(-1)
    standing = until[None, :] > times[:, None]  # (K, W)
    keys, index = np.unique(standing, axis=0, return_inverse=True)
    layers = np.zeros((max(len(keys), 1), grid.rows, grid.columns), dtype=bool)
    if len(walls):
        half = 0.5 * grid.cell_m
        flat = centres.reshape(-1, 2)
        farthest = np.zeros((len(flat), len(walls)))
        for corner in ((-half, -half), (-half, half), (half, -half), (half, half)):
            farthest = np.maximum(farthest, point_segment_distances(flat + np.asarray(corner), walls))
        inside = farthest < robot_radius_m  # (cells, W): the whole cell within the edge's capsule
        for k, key in enumerate(keys):
            layers[k] = inside[:, key].any(axis=1).reshape(grid.rows, grid.columns)
    return layers, np.ascontiguousarray(np.asarray(index, dtype=np.int64).reshape(-1))


@compiled
def _sweep(people, reach, static_blocked, static_index, corridor, goal, phi, x0, y0, h, d, keep, history):
    """The reachable cells step by step (see the module): (arrival step or -1, emptied step or -1, steps
    swept). ``phi`` holds the start's distance lower bound and is updated in place."""
    steps = people.shape[0]
    rows, columns = corridor.shape
    current = np.zeros((rows, columns), dtype=np.bool_)
    free = np.empty((rows, columns), dtype=np.bool_)
    squared = np.empty((rows, columns))
    for k in range(steps):
        _free_cells(people[k], reach, static_blocked[static_index[k]], corridor, x0, y0, h, free)
        threshold = (0.0 if k == 0 else d) + 1e-9  # rounding never drops a cell (k = 0: the start's cells)
        alive = False
        arrived = False
        for i in range(rows):
            for j in range(columns):
                cell = free[i, j] and phi[i, j] <= threshold
                current[i, j] = cell
                if cell:
                    alive = True
                    if goal[i, j]:
                        arrived = True
        if keep:
            history[k] = current
        if not alive:
            return -1, k, k + 1
        if arrived:
            return k, -1, k + 1
        _gap_transform(current, squared)
        for i in range(rows):
            for j in range(columns):
                gap = h * math.sqrt(squared[i, j])
                phi[i, j] = max(phi[i, j] - d, gap)
    return -1, -1, steps


@compiled
def _free_cells(people, reach, blocked, corridor, x0, y0, h, free):
    """``free``: in the corridor, not wholly inside a static capsule or an inflated person's disc."""
    rows, columns = corridor.shape
    for i in range(rows):
        for j in range(columns):
            free[i, j] = corridor[i, j] and not blocked[i, j]
    half = 0.5 * h
    for n in range(people.shape[0]):
        px, py, radius = people[n, 0], people[n, 1], reach[n]
        if not (math.isfinite(px) and math.isfinite(py)):
            continue
        j0 = max(int(math.floor((px - radius - x0) / h)), 0)
        j1 = min(int(math.floor((px + radius - x0) / h)), columns - 1)
        i0 = max(int(math.floor((py - radius - y0) / h)), 0)
        i1 = min(int(math.floor((py + radius - y0) / h)), rows - 1)
        for i in range(i0, i1 + 1):
            fy = abs(y0 + (i + 0.5) * h - py) + half
            for j in range(j0, j1 + 1):
                fx = abs(x0 + (j + 0.5) * h - px) + half
                if fx * fx + fy * fy < radius * radius:  # the farthest corner inside: the whole cell
                    free[i, j] = False


@compiled
def _gap_transform(cells, out):
    """``out``: the squared exact distance, in cells, between each cell's square and the nearest square of
    ``cells``: the centre-to-centre Euclidean distance transform of ``cells`` grown by one cell (8
    neighbours), by the lower envelope of parabolas (Felzenszwalb and Huttenlocher 2012), rows then
    columns."""
    rows, columns = cells.shape
    for i in range(rows):
        for j in range(columns):
            seed = False
            for a in range(max(i - 1, 0), min(i + 2, rows)):
                for b in range(max(j - 1, 0), min(j + 2, columns)):
                    if cells[a, b]:
                        seed = True
            out[i, j] = 0.0 if seed else _FAR
    n = max(rows, columns)
    f = np.empty(n)
    result = np.empty(n)
    v = np.empty(n, dtype=np.int64)
    z = np.empty(n + 1)
    for i in range(rows):
        for j in range(columns):
            f[j] = out[i, j]
        _envelope(f, columns, result, v, z)
        for j in range(columns):
            out[i, j] = result[j]
    for j in range(columns):
        for i in range(rows):
            f[i] = out[i, j]
        _envelope(f, rows, result, v, z)
        for i in range(rows):
            out[i, j] = result[i]


@compiled
def _envelope(f, n, result, v, z):
    """One-dimensional squared distance transform of the sampled function ``f[:n]``."""
    k = 0
    v[0] = 0
    z[0] = -np.inf
    z[1] = np.inf
    for q in range(1, n):
        s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k])
        while s <= z[k]:
            k -= 1
            s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k])
        k += 1
        v[k] = q
        z[k] = s
        z[k + 1] = np.inf
    k = 0
    for q in range(n):
        while z[k + 1] < q:
            k += 1
        result[q] = (q - v[k]) * (q - v[k]) + f[v[k]]


def reacts_to_robot(scenario) -> bool:
    """Whether some person of the scenario reacts to the robot (their future depends on it: no recorded
    future to sweep over)."""
    return any(getattr(getattr(item, "replay", None), "react", False) for item in scenario.obstacles)


def scenario_reach(
    scenario,
    cell_m: float = DEFAULT_CELL_M,
    keep: bool = False,
    top_speed_mps: float | None = None,
    clearance_m: float = 0.0,
) -> Reach:
    """The sweep over a scenario's whole duration, from the robot's start to the goal, with the drive's
    top speed (or ``top_speed_mps``) and the people's radii grown by ``clearance_m``. Raises ValueError for people
    who react to the robot."""
    from viapath.scenarios.build import scenario_limits, scenario_path, scenario_subgoal_policy
    from viapath.sim.obstacles import scenario_obstacle_states
    from viapath.sim.static_world import StaticWorld

    if reacts_to_robot(scenario):
        raise ValueError(f"{scenario.name}: people react to the robot; their future is not recorded")
    dt = scenario.dt_s
    times = np.arange(int(round(scenario.duration_s / dt)) + 1) * dt
    positions, _, radii = scenario_obstacle_states(scenario, times)
    static = StaticWorld.of_scenario(scenario)
    path = scenario_path(scenario)
    return forward_reachable(
        positions,
        radii + clearance_m,
        scenario.robot.radius,
        path,
        scenario.robot.start,
        scenario_limits(scenario).max_speed_mps if top_speed_mps is None else top_speed_mps,
        dt,
        goal=path.goal,
        goal_tolerance_m=scenario_subgoal_policy(scenario).goal_tolerance_m,
        walls=static.segments,
        wall_until_s=static.until_s,
        cell_m=cell_m,
        keep=keep,
    )


def episode_columns(scenario, reached_goal: bool, collision: bool, time_to_goal_s: float | None) -> dict:
    """The bench's columns of one episode: ``feasible``, success and reach among feasible episodes (empty
    when infeasible), the set's earliest arrival and the time ratio against it; all empty for people who
    react to the robot (not applicable)."""
    row: dict = dict.fromkeys(FEASIBILITY_COLUMNS)
    if reacts_to_robot(scenario):
        return row
    reach = scenario_reach(scenario)
    row["feasible"] = reach.feasible
    if reach.feasible:
        row["success_feasible"] = bool(reached_goal and not collision)
        row["reach_feasible"] = bool(reached_goal)
        row["hindsight_time_s"] = reach.arrival_s
        if time_to_goal_s is not None and reach.arrival_s:
            row["time_ratio_hindsight"] = time_to_goal_s / reach.arrival_s
    return row
