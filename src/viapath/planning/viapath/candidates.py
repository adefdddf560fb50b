"""Step 2, the candidates: for every speed of the set, the ways to the subgoal in x-y-t.

Source: paper §3 steps 1-3 (after Tsubouchi et al.'s iterated forecast and planning); docs/design.md §2.

Every candidate is a chain of legs at one constant speed, grown as a tree of (position, time)
nodes. **The speed loop is the roots**: one root node per speed of the set (plus the current and the
nominal speed), all at the robot, at t = 0. From each node the straight leg to the subgoal is tried:

* a free straight leg completes a candidate ("speed up to stay ahead", "slow down and let it
  pass" are straight candidates at other speeds);
* a blocked one branches to the **via points** of the obstacle it hits (avoiding line ∩ reachable
  cone, :func:`viapath.geometry.via_times`): both sides and, when the obstacle is faster, both roots
  (pass early / let it overtake). At the root we branch on every obstacle the straight leg hits
  (earliest first, at most ``max_root_obstacles``), deeper only on the first one hit. Depth is
  bounded by ``max_depth``; a via leg that meets an obstacle or leaves the corridor drops its branch.

Beyond the paper (docs/design.md §2 and §5.2 future work):
* **Slow / wait**: stand still, creep (``creep_speed_mps``, below the speed set) or drive at a speed of
  the set slower than nominal along the straight leg for each of ``slow_times_s``, then on at the
  nominal speed, or at the slowest faster speed whose leg is free when the nominal one's is not. Once
  the way is clear the robot drives the straight leg at the nominal speed (step 1), so a faster
  continuation would be a plan it never drives, and would make waiting look quicker than slowing
  down. Letting a crossing person pass is then a straight candidate, not a sharp turn behind them. The leg after waiting is checked to its end, not
  to the horizon: waiting is for letting someone pass, not for pushing a collision past the horizon.
  The slow leg itself is checked with ``slow_leg_inflation`` of the uncertainty inflation: at a tenth
  of a metre per second the robot stops within millimetres, the next cycles correct the forecast, and
  the shield (docs/design.md §7) keeps it passively safe; with the full cone a freshly tracked crossing person
  made the robot wait where the paper slows down (laser paper-side).
* **Corners**: when the straight leg to the subgoal would cut a corner of the corridor (the robot
  was pushed back, or a blocked subgoal was given up), the path's own corners between the robot and
  the subgoal become via points: the way back along the designated path.

**Static geometry** (docs/design.md §10): a static disc met by a leg stands for its whole shape. The root branches
once per shape a leg meets, and the via points are those of the shape's two extreme discs as seen from the
node (the tangents to its inflated outline); via points round static geometry keep no braking envelope.
A node that hugs a static disc (closer than ``HUG_FACTOR`` via radii) also **slides**: a leg of one via
radius at right angles to the way to the disc, on each side (:func:`_with_slides`), since from so close
the tangents lie a few centimetres away and the nearest disc is both extremes of its shape.

Each candidate records its **way round** — the first obstacle it avoids, the side and the root
(:class:`Way`) — so that the next cycle can prefer the same way (hysteresis) without comparing
positions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from viapath.geometry import VIA_ROOTS as _ROOTS
from viapath.geometry import VIA_SIDES as _SIDES
from viapath.options import Settings
from viapath.planning.viapath.checks import LegChecks

# The "obstacle" of a way that is not round an obstacle.
STRAIGHT = -1  # the straight leg to the subgoal (or a chain grown from it)
SLOW = -2  # first slows down or waits
CORNER = -3  # back along the path through a corner (the corner's index as the way's 'root')


@dataclass(frozen=True)
class Way:
    """Which way round a candidate goes: (first obstacle id or STRAIGHT/SLOW/CORNER, side, root)."""

    obstacle: int
    side: int
    root: int

    def same(self, ways: np.ndarray) -> np.ndarray:
        """Which rows of a (K, 3) way array go this way round (at any speed)."""
        return np.all(ways == (self.obstacle, self.side, self.root), axis=1)


@dataclass
class Choice:
    """What the planner chose last cycle: the way round and the speed (mm/s)."""

    way: Way
    speed_mmps: int


class _Tree:
    """Growable columns of search nodes: where and when the robot is, at which speed, how it got there."""

    # name: (shape of a row, dtype)
    COLUMNS: ClassVar[dict[str, tuple[tuple[int, ...], type]]] = {
        "position": ((2,), float),
        "time_s": ((), float),
        "speed": ((), float),
        "parent": ((), int),
        "length_m": ((), float),
        "first_direction": ((2,), float),
        "way": ((3,), int),  # (obstacle, side, root) of the first branch
        "slow_s": ((), float),  # how long the candidate first drives slower (or stands); 0 if not given
        "slow_speed": ((), float),  # and at which speed
    }

    def __init__(self, capacity: int = 128):
        # Filled in place, doubled when full: a cycle extends the tree a few times and reads it after each.
        self._columns: dict[str, np.ndarray] = {
            name: np.empty((capacity, *shape), dtype) for name, (shape, dtype) in self.COLUMNS.items()
        }
        self._size = 0

    def extend(self, **columns: np.ndarray) -> np.ndarray:
        start = self._size
        end = start + len(columns["position"])
        if end > len(self._columns["position"]):
            self._columns = {
                name: np.concatenate([array[:start], np.empty((2 * end, *array.shape[1:]), array.dtype)])
                for name, array in self._columns.items()
            }
        for name, array in self._columns.items():
            array[start:end] = columns.get(name, 0.0)
        self._size = end
        return np.arange(start, end)

    def stacked(self) -> dict[str, np.ndarray]:
        """The columns of the nodes so far (views: later nodes do not change them)."""
        return {name: array[: self._size] for name, array in self._columns.items()}


@dataclass
class Candidates:
    """The complete candidates of one cycle, as arrays (one row each)."""

    nodes: dict[str, np.ndarray]  # the whole tree, stacked
    leaves: np.ndarray  # the node each candidate ends in (before its last, straight leg)
    total_length_m: np.ndarray
    speed_mps: np.ndarray  # the speed of the candidate's driven legs
    slow_s: np.ndarray  # how long it first slows down or waits (0: never)
    slow_speed_mps: np.ndarray
    first_direction: np.ndarray  # (K, 2) unit vector of the first leg
    ways: np.ndarray  # (K, 3) obstacle, side, root
    subgoal: np.ndarray

    def __len__(self) -> int:
        return len(self.leaves)

    @property
    def driven_s(self) -> np.ndarray:
        return (self.total_length_m - self.slow_speed_mps * self.slow_s) / self.speed_mps

    @property
    def travel_time_s(self) -> np.ndarray:
        return self.slow_s + self.driven_s

    @property
    def speed_mmps(self) -> np.ndarray:
        return np.round(self.speed_mps * 1000).astype(int)

    def first_leg(self, k: int) -> tuple[np.ndarray, float]:
        """Where candidate ``k`` first heads, and at which speed (its plan's target and speed): the subgoal at
        the slow speed for a slow/wait candidate, else its first via point (the subgoal for a straight leg)."""
        if self.slow_s[k] > 0:
            return self.subgoal, float(self.slow_speed_mps[k])
        parent, node = self.nodes["parent"], int(self.leaves[k])
        if parent[node] < 0:
            return self.subgoal, float(self.speed_mps[k])
        while parent[parent[node]] >= 0:  # up to the node after the root
            node = int(parent[node])
        return self.nodes["position"][node], float(self.speed_mps[k])

    def polyline(self, k: int) -> np.ndarray:
        """Candidate ``k`` from the robot through its via points to the subgoal."""
        nodes, node = self.nodes, int(self.leaves[k])
        points = [self.subgoal]
        while node >= 0:
            points.append(nodes["position"][node])
            node = int(nodes["parent"][node])
        return np.array(points[::-1])


@dataclass
class RootLegs:
    """The straight legs from the robot at every speed: the roots of the tree (the speed loop)."""

    speeds: np.ndarray
    nominal_index: int
    directions: np.ndarray
    lengths: np.ndarray
    free: np.ndarray
    contact: np.ndarray

    @classmethod
    def of(cls, checks: LegChecks, speeds: np.ndarray, nominal_index: int) -> RootLegs:
        starts = checks.position[None].repeat(len(speeds), axis=0)  # (np.broadcast_to's Python costs more)
        directions, lengths, free, contact = checks.goal_legs(starts, np.zeros(len(speeds)), speeds)
        return cls(speeds, nominal_index, directions, lengths, free, contact)

    @property
    def nominal_is_free(self) -> bool:
        return bool(self.free[self.nominal_index])


# A node closer to a static disc than this many times its via radius hugs it (:func:`_with_slides`).
HUG_FACTOR = 1.25


def grow(
    checks: LegChecks, roots: RootLegs, config: Settings, slow_checks: LegChecks | None = None
) -> Candidates | None:
    """Every complete candidate of the cycle (straight, slow/wait, corners, via-point chains).
    ``slow_checks`` (default ``checks``) checks the first, slow leg of the slow/wait candidates."""
    speeds = roots.speeds
    n_speeds = len(speeds)
    tree = _Tree()
    frontier = tree.extend(
        position=checks.position[None].repeat(n_speeds, axis=0),
        time_s=np.zeros(n_speeds),
        speed=speeds,
        parent=np.full(n_speeds, -1),
        length_m=np.zeros(n_speeds),
        first_direction=roots.directions,
        way=_ways(n_speeds, STRAIGHT),
    )
    leaves: Any = [frontier[roots.free]]  # a list of arrays, then their concatenation
    goal_length = [roots.lengths[roots.free]]
    if config.slow_times_s and len(checks.obstacles):
        slowing = _slow_candidates(checks, slow_checks or checks, tree, speeds, roots.nominal_index, config)
        if slowing is not None:
            leaves.append(slowing[0])
            goal_length.append(slowing[1])
    free, contact = roots.free, roots.contact
    data = tree.stacked()
    for depth in range(config.max_depth):
        next_frontier = [_corner_nodes(checks, tree, speeds)] if depth == 0 else []
        pairs = _pairs(checks, data["position"], frontier, free, contact, depth, config.max_root_obstacles)
        if pairs is not None:
            children = _via_children(checks, data, *pairs, is_root=(depth == 0))
            if children is not None:
                next_frontier.append(tree.extend(**children))
        frontier = np.concatenate([np.zeros(0, int)] + next_frontier)
        if len(frontier) == 0:
            break
        data = tree.stacked()
        starts, times, node_speeds = data["position"][frontier], data["time_s"][frontier], data["speed"][frontier]
        _, lengths, free, contact = checks.goal_legs(starts, times, node_speeds)
        leaves.append(frontier[free])
        goal_length.append(lengths[free])

    leaves = np.concatenate(leaves)
    if len(leaves) == 0:
        return None
    return Candidates(
        nodes=data,
        leaves=leaves,
        total_length_m=data["length_m"][leaves] + np.concatenate(goal_length),
        speed_mps=data["speed"][leaves],
        slow_s=data["slow_s"][leaves],
        slow_speed_mps=data["slow_speed"][leaves],
        first_direction=data["first_direction"][leaves],
        ways=data["way"][leaves],
        subgoal=checks.subgoal,
    )


def _pairs(
    checks: LegChecks,
    positions: np.ndarray,
    frontier: np.ndarray,
    free: np.ndarray,
    contact: np.ndarray,
    depth: int,
    max_root_obstacles: int,
) -> tuple[np.ndarray, np.ndarray] | None:
    """The (node, obstacle) pairs to branch on from the frontier's blocked legs to the subgoal: at the root each
    shape a leg meets (earliest first, at most ``max_root_obstacles``), deeper the first obstacle hit; a static
    disc replaced by its shape's extremes as seen from the node. None when no leg is blocked by an obstacle."""
    blocked = (~free & np.isfinite(contact).any(axis=1)).nonzero()[0]
    if not (len(blocked) and len(checks.obstacles)):
        return None
    if depth == 0:
        rows, pair_obstacles = _root_pairs(_one_per_shape(checks, contact[blocked]), max_root_obstacles)
        pair_nodes = frontier[blocked][rows]
    else:
        pair_nodes = frontier[blocked]
        pair_obstacles = contact[blocked].argmin(axis=1)
    if checks.obstacles.static_mask is not None:
        pair_nodes, pair_obstacles = _round_static_shapes(checks, positions, pair_nodes, pair_obstacles)
    return pair_nodes, pair_obstacles


def _candidates_of(store: Any, subgoal: np.ndarray) -> Candidates | None:
    """Candidates from the compiled tree's node store (the planner's compiled step instead of :func:`grow`): the
    same arrays as the numpy :func:`grow` builds, leaves in node order as there."""
    data = store.columns()
    leaves = store.leaves()
    if len(leaves) == 0:
        return None
    return Candidates(
        nodes=data,
        leaves=leaves,
        total_length_m=data["length_m"][leaves] + store.to_goal_m(leaves),
        speed_mps=data["speed"][leaves],
        slow_s=data["slow_s"][leaves],
        slow_speed_mps=data["slow_speed"][leaves],
        first_direction=data["first_direction"][leaves],
        ways=data["way"][leaves],
        subgoal=subgoal,
    )


def _ways(count: int, obstacle: ArrayLike, side: ArrayLike = 0, root: ArrayLike = 0) -> np.ndarray:
    """(count, 3) ways round: the obstacle, side and root of each row (a number for all, or one per row)."""
    ways = np.empty((count, 3), dtype=int)
    ways[:, 0], ways[:, 1], ways[:, 2] = obstacle, side, root
    return ways


def _root_pairs(contact: np.ndarray, limit: int) -> tuple[np.ndarray, np.ndarray]:
    """(row, obstacle) pairs to branch on at the root: each obstacle the leg hits, earliest first."""
    rows, cols = np.isfinite(contact).nonzero()
    if limit and len(rows) > limit:
        order = np.lexsort((contact[rows, cols], rows))
        rows, cols = rows[order], cols[order]
        rank = np.arange(len(rows)) - np.searchsorted(rows, rows)
        keep = rank < limit
        rows, cols = rows[keep], cols[keep]
    return rows, cols


def _one_per_shape(checks: LegChecks, contact: np.ndarray) -> np.ndarray:
    """``contact`` with only the earliest discs of each static shape kept per leg: the root branches on the
    shapes a leg meets, not on the many discs of one wall."""
    if checks.obstacles.static_mask is None:
        return contact
    hit = np.flatnonzero(checks.obstacles.static_mask & np.isfinite(contact).any(axis=0))
    if len(hit) == 0:
        return contact
    labels = checks.static_labels()
    columns = hit[np.argsort(labels[hit], kind="stable")]
    starts = np.flatnonzero(np.diff(labels[columns], prepend=-2))
    block = contact[:, columns]
    earliest = np.repeat(np.minimum.reduceat(block, starts, axis=1), np.diff(np.append(starts, len(columns))), axis=1)
    kept = contact.copy()
    kept[:, columns] = np.where(block == earliest, block, np.inf)
    return kept


def _round_static_shapes(
    checks: LegChecks, positions: np.ndarray, node_index: np.ndarray, obstacle_index: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(node, obstacle) pairs with each static disc replaced by the two extreme discs of its shape as seen
    from the node (:meth:`.checks.LegChecks.static_extremes`): via points go round the whole shape, not
    round the one disc a leg met first. Pairs of people stay as they are; repeated pairs are made once."""
    labels = checks.static_labels()
    pairs: dict[tuple[int, int], None] = {}  # (node, obstacle) in the order made, once each
    known: dict[tuple[float, float, int], Any] = {}
    for node, obstacle in zip(node_index.tolist(), obstacle_index.tolist()):
        if labels[obstacle] < 0:
            pairs[node, obstacle] = None
            continue
        start = positions[node]
        key = (float(start[0]), float(start[1]), int(labels[obstacle]))
        extremes = known.get(key)
        if extremes is None:
            extremes = known[key] = checks.static_extremes(start, obstacle)
        for extreme in extremes:
            pairs[node, extreme] = None
    made = np.array(list(pairs), dtype=np.int64).reshape(-1, 2)
    return made[:, 0], made[:, 1]


def _via_children(
    checks: LegChecks, data: dict[str, np.ndarray], node_index: np.ndarray, obstacle_index: np.ndarray, is_root: bool
) -> dict[str, np.ndarray] | None:
    """Via-point children of each (node, obstacle) pair: both sides, both roots, legs checked."""
    starts = data["position"][node_index]
    times = data["time_s"][node_index]
    speeds = data["speed"][node_index]
    obstacles = checks.obstacles
    # The radius grows with prediction uncertainty; it is evaluated near the expected passing time.
    pair, option, t_k, leg_velocity, via = checks.via_options(
        starts,
        times,
        speeds,
        obstacles.positions[obstacle_index],
        obstacles.velocities[obstacle_index],
        checks.via_radii[obstacle_index],
        checks.growth[obstacle_index],
        checks.growth_until_s[obstacle_index],
        _envelope_of_pairs(checks, speeds, obstacle_index),
        3 * checks.horizon_s,
    )
    if obstacles.static_mask is not None:
        pair, option, t_k, leg_velocity, via = _with_slides(
            checks, starts, speeds, obstacle_index, (pair, option, t_k, leg_velocity, via)
        )
    if len(pair) == 0:
        return None
    starts_k, times_k, speeds_k = starts[pair], times[pair], speeds[pair]
    good = checks.legs_free(starts_k, times_k, leg_velocity, t_k)
    good[good] = checks.legs_inside(starts_k[good], via[good])
    if not good.any():
        return None
    pair, option, t_k, speeds_k = pair[good], option[good], t_k[good], speeds_k[good]
    parent = node_index[pair]
    if is_root:
        first_direction = leg_velocity[good] / speeds_k[:, None]
        way = _ways(len(pair), obstacles.ids[obstacle_index[pair]], _SIDES[option], _ROOTS[option])
    else:
        first_direction = data["first_direction"][parent]
        way = data["way"][parent]
    return dict(
        position=via[good],
        time_s=times_k[good] + t_k,
        speed=speeds_k,
        parent=parent,
        length_m=data["length_m"][parent] + speeds_k * t_k,
        first_direction=first_direction,
        way=way,
    )


def _with_slides(
    checks: LegChecks,
    starts: np.ndarray,
    speeds: np.ndarray,
    obstacle_index: np.ndarray,
    options: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The via options of :func:`viapath.geometry.via_options` and, for each pair whose node hugs a static disc
    (closer than ``HUG_FACTOR`` times its via radius), a slide on each side: a leg of one via radius at right
    angles to the way to the disc. From so close the tangents to the via circle lie a few centimetres away, and
    a chain of them creeps round the shape's nearest disc, which from there is both its extremes; the slide
    moves the node along the surface to where the shape's extremes and their tangents mean something again."""
    pair, option, t_k, leg_velocity, via = options
    static = checks.obstacles.static_mask
    assert static is not None
    centres = checks.obstacles.positions[obstacle_index]
    radii = checks.via_radii[obstacle_index]
    offset = centres - starts
    distance = np.hypot(offset[:, 0], offset[:, 1])
    hugging = np.flatnonzero(static[obstacle_index] & (distance < HUG_FACTOR * radii) & (distance > 0))
    if len(hugging) == 0:
        return options
    toward = offset[hugging] / distance[hugging, None]
    left = np.stack([-toward[:, 1], toward[:, 0]], axis=1)  # the way to the disc turned left
    slide_pair = np.repeat(hugging, 2)
    slide_option = np.tile(np.array([0, 1]), len(hugging))  # (left, early), (right, early) of VIA_SIDES
    step = np.repeat(left, 2, axis=0) * _SIDES[slide_option][:, None] * radii[slide_pair][:, None]
    slide_t = radii[slide_pair] / speeds[slide_pair]
    return (
        np.concatenate([pair, slide_pair]),
        np.concatenate([option, slide_option]),
        np.concatenate([t_k, slide_t]),
        np.concatenate([leg_velocity, step / slide_t[:, None]]),
        np.concatenate([via, starts[slide_pair] + step]),
    )


def _envelope_of_pairs(checks: LegChecks, speeds: np.ndarray, obstacle_index: np.ndarray) -> np.ndarray:
    """The braking envelope of each pair's via point: none round static geometry (it stays put)."""
    envelope = checks.envelope_m(speeds)
    static = checks.obstacles.static_mask
    if static is None:
        return envelope
    return np.where(static[obstacle_index], 0.0, envelope)


def _corner_nodes(checks: LegChecks, tree: _Tree, speeds: np.ndarray) -> np.ndarray:
    """The path's corners between the robot and the subgoal, as via points, when the straight leg
    would cut the corridor."""
    path = checks.path
    if checks.subgoal_index < 2:
        return np.zeros(0, int)  # no corner before the first subgoal, wherever the robot is (no projection needed)
    segment = int(path.project(checks.position)[0])
    corners = np.arange(segment + 1, checks.subgoal_index)
    if len(corners) == 0 or checks.goal_legs_inside(checks.position[None])[0]:
        return np.zeros(0, int)
    corner, speed = (grid.ravel() for grid in np.meshgrid(corners, speeds))
    targets = path.waypoints[corner]
    offset = targets - checks.position
    length = np.hypot(offset[:, 0], offset[:, 1])
    direction = offset / np.maximum(length, 1e-12)[:, None]
    starts = np.broadcast_to(checks.position, targets.shape)
    duration = length / speed
    good = checks.legs_free(starts, np.zeros(len(speed)), direction * speed[:, None], duration)
    good &= checks.legs_inside(starts, targets)
    count = int(good.sum())
    if count == 0:
        return np.zeros(0, int)
    return tree.extend(
        position=targets[good],
        time_s=duration[good],
        speed=speed[good],
        parent=np.searchsorted(speeds, speed[good]),  # the root node of that speed
        length_m=length[good],
        first_direction=direction[good],
        way=_ways(count, CORNER, 0, corner[good]),
    )


def creep_speeds(creep_speed_mps: float, speeds: np.ndarray, nominal_mps: float) -> np.ndarray:
    """The creep speed as a slow speed: none when it is off, not below the nominal speed, or in the set."""
    creep = float(creep_speed_mps)
    if creep <= 0.0 or creep >= nominal_mps - 1e-9 or bool(np.any(np.abs(speeds - creep) < 1e-9)):
        return np.zeros(0)
    return np.array([creep])


def _first_in_rows(free: np.ndarray, row_length: int) -> np.ndarray:
    """``free`` with only the first True of each row of ``row_length`` kept."""
    rows = free.reshape(-1, row_length)
    return (rows & (np.cumsum(rows, axis=1) == 1)).ravel()


def _slow_candidates(
    checks: LegChecks, slow_checks: LegChecks, tree: _Tree, speeds: np.ndarray, nominal_index: int, config: Settings
) -> tuple[np.ndarray, np.ndarray] | None:
    """Stand still or drive slower than nominal towards the subgoal for each of ``slow_times_s``,
    then on at the nominal speed or faster. Returns (leaf node indices, goal leg lengths) or None."""
    if not checks.goal_legs_inside(checks.position[None])[0]:
        return None  # slowing down runs along the straight leg, which would leave the corridor
    nominal = speeds[nominal_index]
    slow_speeds = np.concatenate(
        [[0.0], creep_speeds(config.creep_speed_mps, speeds, nominal), speeds[speeds < nominal - 1e-9]]
    )
    # Every slow time with every slow speed, as np.meshgrid(times, slow_speeds) would pair them (row-major;
    # np.tile and np.repeat as the array methods: their Python costs more than these few copies).
    times = np.asarray(config.slow_times_s, float)
    duration, slow_speed = times[None].repeat(len(slow_speeds), axis=0).ravel(), slow_speeds.repeat(len(times))
    offset = checks.subgoal - checks.position
    direction = offset / max(float(np.hypot(*offset)), 1e-12)
    # Never past the subgoal while slowing down.
    ok = slow_speed * duration < np.hypot(*offset) - 1e-6
    duration, slow_speed = duration[ok], slow_speed[ok]
    starts = checks.position[None].repeat(len(duration), axis=0)
    free = slow_checks.legs_free(starts, np.zeros(len(duration)), direction * slow_speed[:, None], duration)
    if not free.any():
        return None
    duration, slow_speed = duration[free], slow_speed[free]
    # Then the nominal speed, or the slowest faster one whose leg is free: waiting only makes sense when the
    # way is clear afterwards (slowing down for good is the straight candidates' job).
    after = speeds[speeds >= nominal - 1e-9]
    d, v_slow = duration.repeat(len(after)), slow_speed.repeat(len(after))
    v_after = after[None].repeat(len(duration), axis=0).ravel()
    ends = checks.position + direction * (v_slow * d)[:, None]
    _, lengths, free, _ = checks.goal_legs(ends, d, v_after, np.inf)
    if not free.any():
        return None
    free = _first_in_rows(free, len(after))
    count = int(free.sum())
    index = tree.extend(
        position=ends[free],
        time_s=d[free],
        speed=v_after[free],
        parent=np.full(count, -1),
        length_m=(v_slow * d)[free],
        first_direction=np.broadcast_to(direction, (count, 2)).copy(),
        way=_ways(count, SLOW),
        slow_s=d[free],
        slow_speed=v_slow[free],
    )
    return index, lengths[free]
