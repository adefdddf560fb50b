"""The perception interface: what the closed loop (simulator, ROS 2 node) asks of a perception model.

A model takes the true world at one instant (:class:`WorldSnapshot`, in simulation) and returns the
:class:`~viapath.observation.Obstacles` the planner is told about, in the world frame. Every hook the
loop calls is declared here with its default, so no caller probes a model with ``getattr``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from viapath.observation import Obstacles
from viapath.static import StaticLayer


@dataclass(frozen=True)
class WorldSnapshot:
    """The true world at one instant. Absent obstacles (e.g. replayed people not yet in the scene) are NaN rows."""

    time_s: float
    robot_pose: np.ndarray  # (3,) x, y, heading
    robot_radius_m: float
    obstacle_positions: np.ndarray  # (N, 2)
    obstacle_velocities: np.ndarray  # (N, 2)
    obstacle_radii_m: np.ndarray  # (N,)
    walls: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 2)))  # (W, 2, 2) static segments
    static: StaticLayer | None = None  # the same segments with their shapes (None: ``walls``, one shape each)

    def static_layer(self) -> StaticLayer:
        if self.static is not None:
            return self.static
        return StaticLayer(self.walls) if len(self.walls) else StaticLayer.empty()

    def present(self) -> np.ndarray:
        return np.isfinite(self.obstacle_positions).all(axis=1)


class Perception:
    """Base class. ``observe`` is called once per cycle, in time order, after ``reset``."""

    name = "base"
    #: Scan points of the last cycle in the world frame (laser models; empty for the others).
    last_points_world: np.ndarray = np.zeros((0, 2))
    #: The last cycle's scans, one per scanner, in their own frames (laser models; empty for the others).
    last_scans: list = []  # noqa: RUF012 -- an empty default each instance replaces, never mutates

    def reset(self, rng: np.random.Generator) -> None:
        self.rng = rng

    def observe(self, world: WorldSnapshot) -> Obstacles:  # pragma: no cover - interface
        raise NotImplementedError

    def static_layer(self, world: WorldSnapshot) -> StaticLayer:
        """The static geometry the planner is told about this cycle (docs/design.md §10), after :meth:`observe`:
        by default the known map (the world's static shapes); laser models tell what their scans show."""
        return world.static_layer()

    def episode_metrics(self) -> dict[str, Any]:
        """Metrics of the model over the episode (e.g. tracking errors), merged into the episode's."""
        return {}
