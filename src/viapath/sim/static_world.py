"""The scenario's static shapes over an episode: which walls, boxes and polygons stand at each time.

A shape with ``until_s`` is gone from that time on (a door that opens); the scanners, the oracle's map
and the contact count all read the same :meth:`StaticWorld.at`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from viapath.static import StaticLayer


@dataclass(frozen=True)
class StaticWorld:
    segments: np.ndarray  # (W, 2, 2) every edge of every shape
    shape_ids: np.ndarray  # (W,) the shape each edge belongs to
    until_s: np.ndarray  # (W,) the edge stands while t < until_s (inf: always)
    # (W,) bool: the edge bounds a closed shape (a box, a polygon), whose inside is solid too
    closed: np.ndarray | None = None

    @classmethod
    def of_scenario(cls, scenario) -> StaticWorld:
        shapes = scenario.static_shapes()
        if not shapes:
            return cls(np.zeros((0, 2, 2)), np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0, dtype=bool))
        segments = np.concatenate([edges for edges, _ in shapes])
        ids = np.concatenate([np.full(len(edges), k, dtype=np.int64) for k, (edges, _) in enumerate(shapes)])
        until = np.concatenate([np.full(len(edges), until) for edges, until in shapes])
        walls = len(scenario.walls)  # static_shapes lists walls (open) first, then boxes and polygons
        closed = np.concatenate([np.full(len(edges), k >= walls) for k, (edges, _) in enumerate(shapes)])
        return cls(segments, ids, until, closed)

    def closed_ids(self) -> np.ndarray:
        """(W,) the closed shape each edge bounds, -1 for an edge of an open wall."""
        closed = np.zeros(len(self.segments), dtype=bool) if self.closed is None else self.closed
        return np.where(closed, self.shape_ids, -1)

    def __len__(self) -> int:
        return len(self.segments)

    def standing(self, time_s: float) -> np.ndarray:
        return self.until_s > time_s

    def at(self, time_s: float) -> StaticLayer:
        """The shapes standing at ``time_s`` (the same object while the same shapes stand)."""
        standing = self.standing(time_s)
        key = standing.tobytes()
        cached = self.__dict__.get("_at")
        if cached is None or cached[0] != key:
            layer = StaticLayer(self.segments[standing], self.shape_ids[standing])
            cached = (key, layer)
            object.__setattr__(self, "_at", cached)
        return cached[1]

    @property
    def changes(self) -> bool:
        return bool(np.any(np.isfinite(self.until_s)))
