"""Perception models: what the planner is told about the obstacles each cycle.

Every model takes the true world at one instant and returns :class:`~viapath.observation.Obstacles`
in the world frame. ``oracle`` reports true positions and velocities, optionally with Gaussian noise
on each estimate every cycle (to test planning under uncertainty without lasers); the laser chain
lives in :mod:`viapath.perception`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from viapath.observation import Obstacles


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

    def present(self) -> np.ndarray:
        return np.isfinite(self.obstacle_positions).all(axis=1)


class Perception:
    """Base class. ``observe`` is called once per cycle, in time order."""

    name = "base"

    def reset(self, rng: np.random.Generator) -> None:
        self.rng = rng

    def observe(self, world: WorldSnapshot) -> Obstacles:  # pragma: no cover - interface
        raise NotImplementedError


class OraclePerception(Perception):
    """True obstacle states, with optional per-cycle Gaussian noise (σ per axis)."""

    name = "oracle"

    def __init__(self, position_noise_m: float = 0.0, velocity_noise_mps: float = 0.0):
        self.position_noise_m = float(position_noise_m)
        self.velocity_noise_mps = float(velocity_noise_mps)
        self.rng = np.random.default_rng(0)

    def observe(self, world: WorldSnapshot) -> Obstacles:
        present = world.present()
        positions = world.obstacle_positions[present]
        velocities = world.obstacle_velocities[present]
        if self.position_noise_m > 0:
            positions = positions + self.rng.normal(0.0, self.position_noise_m, positions.shape)
        if self.velocity_noise_mps > 0:
            velocities = velocities + self.rng.normal(0.0, self.velocity_noise_mps, velocities.shape)
        n = len(positions)
        return Obstacles(
            positions,
            velocities,
            world.obstacle_radii_m[present],
            position_sigma_m=np.full(n, self.position_noise_m),
            velocity_sigma_mps=np.full(n, self.velocity_noise_mps),
            ids=np.flatnonzero(present),
        )
