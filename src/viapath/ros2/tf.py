"""A small planar transform buffer fed from ``/tf`` and ``/tf_static`` (no rclpy, no tf2).

Source: REP 105 (``map → odom → base_link``), REP 103 (yaw counter-clockwise about z), tf2's tree
(every frame has one parent; ``/tf_static`` holds for all time, ``/tf`` is kept for a while).

What we chose:
* Planar: each edge is (x, y, yaw); roll, pitch and z are ignored (a robot on a floor).
* A dynamic edge keeps ``history_s`` of samples; a lookup at time t interpolates between the two
  samples around t (yaw along the shorter arc), takes the newest when t lies up to ``tolerance_s``
  after it (the publisher may lag), and fails otherwise. ``stamp_s=None`` takes every edge's newest.
* A lookup that fails returns None: the caller decides the fallback (parameters, or refusing a path).
* Staleness: a lookup of the newest transforms (``stamp_s=None``) given the current time ``now_s``
  fails when a dynamic edge's newest sample is older than ``max_age_s`` (a ``map → odom`` stamped an
  hour ago says nothing of where the map is now). Static edges hold for all time.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

Pose2 = tuple[float, float, float]


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


def compose(a: Pose2, b: Pose2) -> Pose2:
    """``a ∘ b``: b given in a's frame, returned in a's parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], _wrap(a[2] + b[2])


def inverse(a: Pose2) -> Pose2:
    c, s = math.cos(a[2]), math.sin(a[2])
    return -c * a[0] - s * a[1], s * a[0] - c * a[1], _wrap(-a[2])


def apply(a: Pose2, x: float, y: float) -> tuple[float, float]:
    c, s = math.cos(a[2]), math.sin(a[2])
    return a[0] + c * x - s * y, a[1] + s * x + c * y


@dataclass
class _Edge:
    parent: str
    static: bool
    stamps: list[float] = field(default_factory=list)
    poses: list[Pose2] = field(default_factory=list)


class TransformBuffer:
    def __init__(self, history_s: float = 10.0, tolerance_s: float = 0.5, max_age_s: float = math.inf):
        self.history_s = history_s
        self.tolerance_s = tolerance_s
        self.max_age_s = max_age_s
        self.edges: dict[str, _Edge] = {}

    @staticmethod
    def _frame(name: str) -> str:
        return name.lstrip("/")

    def set(
        self, parent: str, child: str, stamp_s: float, x: float, y: float, yaw: float, static: bool = False
    ) -> bool:
        """Store one transform (child's pose in parent); False when refused (not finite, a loop)."""
        parent, child = self._frame(parent), self._frame(child)
        if not parent or not child or parent == child or not all(math.isfinite(v) for v in (stamp_s, x, y, yaw)):
            return False
        p = parent  # refuse an edge that would close a loop
        while p in self.edges:
            p = self.edges[p].parent
            if p == child:
                return False
        edge = self.edges.get(child)
        if edge is None or edge.parent != parent or edge.static != static:
            edge = self.edges[child] = _Edge(parent, static)
        if static:
            edge.stamps, edge.poses = [stamp_s], [(x, y, _wrap(yaw))]
            return True
        if edge.stamps and stamp_s < edge.stamps[-1] - self.history_s:  # time went back: start anew
            edge.stamps, edge.poses = [], []
        k = bisect.bisect_right(edge.stamps, stamp_s)
        edge.stamps.insert(k, stamp_s)
        edge.poses.insert(k, (x, y, _wrap(yaw)))
        cut = bisect.bisect_left(edge.stamps, edge.stamps[-1] - self.history_s)
        if cut:
            del edge.stamps[:cut], edge.poses[:cut]
        return True

    def _edge_at(self, edge: _Edge, stamp_s: float | None, now_s: float | None = None) -> Pose2 | None:
        if edge.static:
            return edge.poses[-1]
        if stamp_s is None:
            if now_s is not None and not now_s - edge.stamps[-1] <= self.max_age_s:
                return None  # stale
            return edge.poses[-1]
        stamps = edge.stamps
        if stamp_s >= stamps[-1]:
            return edge.poses[-1] if stamp_s - stamps[-1] <= self.tolerance_s else None
        k = bisect.bisect_right(stamps, stamp_s)
        if k == 0:
            return edge.poses[0] if stamps[0] - stamp_s <= 1e-9 else None
        t0, t1 = stamps[k - 1], stamps[k]
        a, b = edge.poses[k - 1], edge.poses[k]
        u = 0.0 if t1 <= t0 else (stamp_s - t0) / (t1 - t0)
        return a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1]), _wrap(a[2] + u * _wrap(b[2] - a[2]))

    def _to_root(
        self, frame: str, stamp_s: float | None, now_s: float | None = None
    ) -> tuple[list[str], list[Pose2]] | None:
        """Frames from ``frame`` up to its root and each frame's pose in the root... (cumulative)."""
        chain, poses = [frame], [(0.0, 0.0, 0.0)]
        while chain[-1] in self.edges:
            edge = self.edges[chain[-1]]
            pose = self._edge_at(edge, stamp_s, now_s)
            if pose is None:
                return None
            chain.append(edge.parent)
            poses.append(pose)
        # poses[i] is frame chain[i-1] in chain[i]; accumulate: frame in each ancestor
        out = [(0.0, 0.0, 0.0)]
        for pose in poses[1:]:
            out.append(compose(pose, out[-1]))
        return chain, out

    def lookup(
        self, target: str, source: str, stamp_s: float | None = None, now_s: float | None = None
    ) -> Pose2 | None:
        """Pose of frame ``source`` in frame ``target`` (maps a point in source to target), or None
        (unknown, or with ``now_s`` and no ``stamp_s``: stale)."""
        target, source = self._frame(target), self._frame(source)
        if target == source:
            return 0.0, 0.0, 0.0
        up_s = self._to_root(source, stamp_s, now_s)
        up_t = self._to_root(target, stamp_s, now_s)
        if up_s is None or up_t is None:
            return None
        index_t = {f: i for i, f in enumerate(up_t[0])}
        for i, frame in enumerate(up_s[0]):
            if frame in index_t:
                source_in_common = up_s[1][i]
                target_in_common = up_t[1][index_t[frame]]
                return compose(inverse(target_in_common), source_in_common)
        return None
