"""The designated path (paper §2, Fig. 2-3): subgoals joined by straight segments inside a corridor.

The corridor ("path boundary") bounds the robot *centre*: a point is inside when it lies within
``half_width`` of some segment, i.e. the corridor is the union of one capsule per segment. This
keeps corners filled on the outside of a turn and needs no special case at junctions.

What the paper leaves open and we chose:
* Subgoal switching: within ``reach_threshold_m`` of the subgoal, or once the robot's projection on
  the segment that ends at the subgoal has passed it (so the robot never turns back for a subgoal
  it has already passed, e.g. after an avoidance).
* Bypass (Fig. 3): an intermediate subgoal is given up when an obstacle's disc, grown by the robot
  radius, comes within ``blocked_clearance_m`` of it while the robot is within ``bypass_distance_m``.
  The final goal is never given up.
* Junctions: the robot heads for the corner subgoal itself and switches only when close, so it goes
  straight to the end of a segment before turning, as the paper asks.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from viapath.geometry import cross2
from viapath.jit import compiled
from viapath.limits import SUBGOAL_OPTIONS

# A path of more segments than this (a dense path from a planner, a zig-zag) is checked against the
# segments near the points asked about, which give the same numbers: its cost per cycle does not grow
# with its length. _NEAR_MARGIN_M: how far outside the corridor a point may be for that to hold.
_MANY_SEGMENTS = 64
_NEAR_MARGIN_M = 2.0


class DesignatedPath:
    """A polyline of subgoals (the last is the goal) with a corridor half-width per segment."""

    def __init__(
        self, waypoints: ArrayLike, half_width_m: float | None = None, half_widths_m: ArrayLike | None = None
    ) -> None:
        waypoints = np.asarray(waypoints, dtype=float)
        if waypoints.ndim != 2 or waypoints.shape[1] != 2 or len(waypoints) < 2:
            raise ValueError("a designated path needs at least two (x, y) waypoints")
        if not np.isfinite(waypoints).all():
            raise ValueError("waypoints must be finite")
        lengths = np.hypot(*np.diff(waypoints, axis=0).T)
        if (lengths <= 1e-9).any():
            raise ValueError("consecutive waypoints must differ")
        n_segments = len(waypoints) - 1
        if half_widths_m is None:
            if half_width_m is None:
                raise ValueError("give half_width_m or half_widths_m")
            half_widths_m = np.full(n_segments, float(half_width_m))
        half_widths_m = np.asarray(half_widths_m, dtype=float).reshape(-1)
        if len(half_widths_m) != n_segments:
            raise ValueError(f"half_widths_m needs one value per segment ({n_segments}), got {len(half_widths_m)}")
        if not (np.isfinite(half_widths_m).all() and (half_widths_m > 0).all()):
            raise ValueError("corridor half-widths must be positive and finite")
        self.waypoints = waypoints
        self.half_widths_m = half_widths_m
        self.segment_starts = waypoints[:-1]
        self.segment_vectors = np.diff(waypoints, axis=0)
        self.segment_lengths_m = lengths
        self.segment_directions = self.segment_vectors / lengths[:, None]
        self.cumulative_length_m = np.concatenate([[0.0], np.cumsum(lengths)])

    @property
    def goal(self) -> np.ndarray:
        return self.waypoints[-1]

    @property
    def length_m(self) -> float:
        return float(self.cumulative_length_m[-1])

    def _segment_geometry(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per point and segment: clamped arc position along the segment and offset from it."""
        if points.size > 128:  # x and y apart: the same values, faster on many points (the escape's roll-outs)
            return self._segment_geometry_xy(points)
        rel = points[..., None, :] - self.segment_starts  # (..., S, 2)
        along = np.add.reduce(rel * self.segment_directions, axis=-1)  # np.sum's own reduction, without its Python
        along_clamped = np.minimum(np.maximum(along, 0.0), self.segment_lengths_m)  # np.clip without its dispatch
        closest = self.segment_starts + along_clamped[..., None] * self.segment_directions
        offset = points[..., None, :] - closest
        distance = np.hypot(offset[..., 0], offset[..., 1])
        return along, along_clamped, distance

    def _segment_geometry_xy(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`_segment_geometry` with x and y apart: each product, sum and difference as there (the
        sum of the two products as np.sum adds them; only the sign of a zero ``along`` may differ, which no
        result shows), without the (..., S, 2) temporaries, whose strided passes cost more on many points."""
        starts, directions = self.segment_starts, self.segment_directions
        px, py = points[..., 0, None], points[..., 1, None]  # (..., 1)
        along = (px - starts[:, 0]) * directions[:, 0] + (py - starts[:, 1]) * directions[:, 1]  # (..., S)
        along_clamped = np.minimum(np.maximum(along, 0.0), self.segment_lengths_m)
        distance = np.hypot(
            px - (starts[:, 0] + along_clamped * directions[:, 0]),
            py - (starts[:, 1] + along_clamped * directions[:, 1]),
        )
        return along, along_clamped, distance

    def project(self, points: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Nearest point on the path: ``(segment_index, arc_length_m, signed_lateral_m)``.

        The lateral deviation is positive to the left of the direction of travel.
        """
        points = np.asarray(points, dtype=float)
        _along, along_clamped, distance = self._segment_geometry(points)
        index = distance.argmin(axis=-1)
        take: Callable[[np.ndarray], np.ndarray] = lambda a: np.take_along_axis(a, index[..., None], axis=-1)[..., 0]
        rel = points - self.segment_starts[index]
        side = np.sign(cross2(self.segment_directions[index], rel))
        side = np.where(side == 0, 1.0, side)
        arc = self.cumulative_length_m[index] + take(along_clamped)
        return index, arc, side * take(distance)

    def lateral_deviation(self, points: ArrayLike) -> np.ndarray:
        return self.project(points)[2]

    def corridor_excess(self, points: ArrayLike) -> np.ndarray:
        """How far each point is outside the corridor (m); <= 0 inside."""
        points = np.asarray(points, dtype=float)
        if points.shape == (2,):
            x, y = float(points[0]), float(points[1])
            if math.isfinite(x) and math.isfinite(y):
                return self._point_excess(x, y)  # type: ignore[return-value]  # a float64 acts as a 0-d array
        if len(self.half_widths_m) > _MANY_SEGMENTS and points.size:
            near = self._excess_near(points)
            if near is not None:
                return near
        _, _, distance = self._segment_geometry(points)
        if len(self.half_widths_m) == 1:
            return distance[..., 0] - self.half_widths_m[0]  # the one segment's (a minimum of one is that one)
        return (distance - self.half_widths_m).min(axis=-1)

    def _segments_near(self, low: np.ndarray, high: np.ndarray) -> np.ndarray:
        """Indices of the segments whose box, grown by their half-width and ``_NEAR_MARGIN_M``, meets the
        box [low, high]: any other segment's excess is above ``_NEAR_MARGIN_M`` for every point in it."""
        boxes = self.__dict__.get("_boxes")
        if boxes is None:
            ends = self.segment_starts + self.segment_vectors
            grow = (self.half_widths_m + _NEAR_MARGIN_M)[:, None]
            boxes = self._boxes = (
                np.minimum(self.segment_starts, ends) - grow,
                np.maximum(self.segment_starts, ends) + grow,
            )
        return np.flatnonzero(((boxes[0] <= high) & (boxes[1] >= low)).all(axis=1))

    def _excess_near(self, points: np.ndarray) -> np.ndarray | None:
        """:meth:`corridor_excess` of many-segment paths computed on the segments near the points only: the
        same numbers (a minimum over a set that holds the minimiser), or None when some point is farther
        than ``_NEAR_MARGIN_M`` out and the whole path must be looked at."""
        flat = points.reshape(-1, 2)
        if not np.isfinite(flat).all():
            return None
        chosen = self._segments_near(flat.min(axis=0), flat.max(axis=0))
        if len(chosen) == 0 or len(chosen) * 2 > len(self.half_widths_m):
            return None
        part = DesignatedPath.__new__(DesignatedPath)
        part.segment_starts = self.segment_starts[chosen]
        part.segment_directions = self.segment_directions[chosen]
        part.segment_lengths_m = self.segment_lengths_m[chosen]
        _, _, distance = part._segment_geometry(points)
        excess = (distance - self.half_widths_m[chosen]).min(axis=-1)
        if not (excess <= _NEAR_MARGIN_M).all():
            return None
        return excess

    def _point_excess(self, x: float, y: float) -> np.float64:
        """:meth:`corridor_excess` of one finite point (the robot's, every cycle) in scalar arithmetic: the
        same operations as :meth:`_segment_geometry` (the clamp as ``np.clip``'s max-then-min, the
        distance by ``np.hypot``; ``math.hypot`` rounds differently), without its array temporaries."""
        if len(self.half_widths_m) > _MANY_SEGMENTS:
            point = np.array([x, y])
            near = self._excess_near(point[None])
            if near is not None:
                return np.float64(near[0])
        segments = self.__dict__.get("_segments")
        if segments is None:
            segments = self._segments = [
                (float(sx), float(sy), float(dx), float(dy), float(length), float(half))
                for (sx, sy), (dx, dy), length, half in zip(
                    self.segment_starts, self.segment_directions, self.segment_lengths_m, self.half_widths_m
                )
            ]
        best = math.inf
        hypot = np.hypot
        for sx, sy, dx, dy, length, half in segments:
            along = (x - sx) * dx + (y - sy) * dy
            along = along if along > 0.0 else 0.0
            along = along if along < length else length
            excess = float(hypot(x - (sx + along * dx), y - (sy + along * dy))) - half
            if excess < best:
                best = excess
        return np.float64(best)

    def contains(self, points: ArrayLike, tolerance_m: float = 1e-9) -> np.ndarray:
        return self.corridor_excess(points) <= tolerance_m

    def legs_inside(
        self, starts: ArrayLike, ends: ArrayLike, spacing_m: float = 0.05, tolerance_m: ArrayLike = 1e-9
    ) -> np.ndarray:
        """Whether each straight leg stays in the corridor.

        Each capsule is convex, so a leg whose two ends lie in the same capsule is inside, exactly.
        Other legs (across a junction) are checked at points ``spacing_m`` apart.
        """
        starts = np.asarray(starts, dtype=float).reshape(-1, 2)
        ends = np.asarray(ends, dtype=float).reshape(-1, 2)
        if len(starts) == 0:
            return np.zeros(0, dtype=bool)
        # One tolerance for all (the planner's case) is compared as it is: the same verdicts as against
        # its copies, without making them.
        tolerance = tolerance_m if np.ndim(tolerance_m) == 0 else np.asarray(tolerance_m, dtype=float)[:, None]
        # Both ends in one pass (the same values as two; a call costs more than these few points).
        excess = self._segment_geometry(np.concatenate([starts, ends]))[2] - self.half_widths_m
        start_in = excess[: len(starts)] <= tolerance
        end_in = excess[len(starts) :] <= tolerance
        inside = (start_in & end_in).any(axis=1)
        if len(self.half_widths_m) == 1 or inside.all():
            return inside  # no leg across a junction (one capsule: both ends in it or the leg is out)
        tolerance = np.broadcast_to(np.asarray(tolerance_m, dtype=float), (len(starts),))
        unresolved = np.flatnonzero(~inside & start_in.any(axis=1) & end_in.any(axis=1))
        if len(unresolved):
            a, b = starts[unresolved], ends[unresolved]
            longest = float(np.max(np.hypot(*(b - a).T)))
            fractions = np.linspace(0.0, 1.0, max(2, int(np.ceil(longest / spacing_m)) + 1))
            samples = a[:, None, :] + fractions[None, :, None] * (b - a)[:, None, :]
            inside[unresolved] = np.all(self.corridor_excess(samples) <= tolerance[unresolved, None], axis=1)
        return inside

    def point_at(self, arc_length_m: float) -> np.ndarray:
        arc = float(np.clip(arc_length_m, 0.0, self.length_m))
        index = int(
            np.clip(
                np.searchsorted(self.cumulative_length_m, arc, side="right") - 1, 0, len(self.segment_lengths_m) - 1
            )
        )
        return self.segment_starts[index] + (arc - self.cumulative_length_m[index]) * self.segment_directions[index]


@dataclass
class SubgoalPolicy:
    """When a subgoal is reached or given up; defaults, units and bounds: :data:`viapath.limits.SUBGOAL_OPTIONS`."""

    reach_threshold_m: float = SUBGOAL_OPTIONS["reach_threshold_m"].default
    goal_tolerance_m: float = SUBGOAL_OPTIONS["goal_tolerance_m"].default
    bypass_distance_m: float = SUBGOAL_OPTIONS["bypass_distance_m"].default
    blocked_clearance_m: float = SUBGOAL_OPTIONS["blocked_clearance_m"].default


class SubgoalTracker:
    """Which subgoal the robot heads for now (paper §2). Keeps state between cycles."""

    def __init__(self, path: DesignatedPath, policy: SubgoalPolicy | None = None):
        self.path = path
        self.policy = policy or SubgoalPolicy()
        self.index = 1
        self.bypassed: list[int] = []

    @property
    def is_final(self) -> bool:
        return self.index == len(self.path.waypoints) - 1

    @property
    def subgoal(self) -> np.ndarray:
        return self.path.waypoints[self.index]

    def goal_reached(self, position: ArrayLike) -> bool:
        if not self.is_final:
            return False
        (gx, gy), (x, y) = self.path.goal.tolist(), np.asarray(position, dtype=float).tolist()
        return float(np.hypot(gx - x, gy - y)) <= self.policy.goal_tolerance_m

    def is_blocked(
        self, obstacle_positions: np.ndarray | None, obstacle_radii: ArrayLike | None, robot_radius_m: float = 0.0
    ) -> bool:
        """Whether an obstacle sits on the current intermediate subgoal (the goal is never blocked)."""
        if self.is_final or obstacle_positions is None or len(obstacle_positions) == 0:
            return False
        gaps = (
            np.hypot(*(np.asarray(obstacle_positions) - self.subgoal).T) - np.asarray(obstacle_radii) - robot_radius_m
        )
        return bool(np.min(gaps) <= self.policy.blocked_clearance_m)

    def update(
        self,
        position: ArrayLike,
        robot_radius_m: float = 0.0,
        obstacle_positions: np.ndarray | None = None,
        obstacle_radii: ArrayLike | None = None,
    ) -> int:
        position = np.asarray(position, dtype=float)
        while not self.is_final:
            subgoal = self.subgoal
            distance = float(np.hypot(*(subgoal - position)))
            segment = self.index - 1
            along = float(np.dot(position - self.path.segment_starts[segment], self.path.segment_directions[segment]))
            passed = along >= self.path.segment_lengths_m[segment]
            if distance <= self.policy.reach_threshold_m or passed:
                self.index += 1
                continue
            if distance <= self.policy.bypass_distance_m and self.is_blocked(
                obstacle_positions, obstacle_radii, robot_radius_m
            ):
                self.bypassed.append(self.index)
                self.index += 1
                continue
            break
        return self.index


@compiled
def corridor_excess_at(
    x: float, y: float, starts: np.ndarray, directions: np.ndarray, lengths_m: np.ndarray, half_widths_m: np.ndarray
) -> float:
    """How far the point (x, y) is outside the corridor of these segments (m; <= 0 inside): compiled, for
    the compiled steps that test many points (the shield's braking sweeps, the situation's robot). The
    operations of :meth:`DesignatedPath.corridor_excess` (the clamp as ``np.clip``'s max-then-min; ``np.hypot``,
    which compiled and in plain Python gives numpy's bits, where Python's ``math.hypot`` rounds differently)."""
    best = math.inf
    for i in range(lengths_m.shape[0]):
        sx, sy, dx, dy = starts[i, 0], starts[i, 1], directions[i, 0], directions[i, 1]
        along = (x - sx) * dx + (y - sy) * dy
        along = along if along > 0.0 else 0.0
        along = along if along < lengths_m[i] else lengths_m[i]
        excess = np.hypot(x - (sx + along * dx), y - (sy + along * dy)) - half_widths_m[i]
        if excess < best:
            best = excess
    return float(best)  # a float in plain Python too (np.hypot hands back a numpy float there)
