"""The oracle perception model: true obstacle states, optionally with noise on every estimate.

To test planning under uncertainty without lasers: Gaussian noise (σ per axis) on each position and
velocity estimate, drawn anew every cycle from the episode's generator, and the σ handed to the
planner with the estimates (as a tracker would).
"""

from __future__ import annotations

import numpy as np

from viapath.observation import Obstacles
from viapath.perception.base import Perception, WorldSnapshot


class OraclePerception(Perception):
    """True obstacle states, with optional per-cycle Gaussian noise (σ per axis)."""

    name = "oracle"

    def __init__(self, position_noise_m: float = 0.0, velocity_noise_mps: float = 0.0):
        self.position_noise_m = float(position_noise_m)
        self.velocity_noise_mps = float(velocity_noise_mps)
        self.rng = np.random.default_rng(0)

    def observe(self, world: WorldSnapshot) -> Obstacles:
        if len(world.obstacle_positions) == 0:
            return _NOBODY  # an empty scene (the benchmark's free runs): nothing to copy or check
        present = world.present()
        if present.all():  # everyone in the scene: plain copies, the same arrays as the masked ones below
            positions, velocities = world.obstacle_positions.copy(), world.obstacle_velocities.copy()
            radii, ids = world.obstacle_radii_m.copy(), np.arange(len(present))
        else:
            positions, velocities = world.obstacle_positions[present], world.obstacle_velocities[present]
            radii, ids = world.obstacle_radii_m[present], np.flatnonzero(present)
        if self.position_noise_m > 0:
            positions = positions + self.rng.normal(0.0, self.position_noise_m, positions.shape)
        if self.velocity_noise_mps > 0:
            velocities = velocities + self.rng.normal(0.0, self.velocity_noise_mps, velocities.shape)
        n = len(positions)
        # Every array here is new (copies, or indexing with a mask), so the estimates are handed over as they are.
        return Obstacles.of_fresh_arrays(
            positions, velocities, radii, _sigmas(n, self.position_noise_m), _sigmas(n, self.velocity_noise_mps), ids
        )


def _sigmas(n: int, sigma: float) -> np.ndarray:
    return np.zeros(n) if sigma == 0 else np.full(n, sigma)  # np.zeros: the same zeros, without np.full's cost


# No obstacles: one instance handed out for every empty scene (its arrays hold nothing to change; they stay
# writeable, as the compiled functions are compiled for writeable arrays).
_NOBODY = Obstacles.of_fresh_arrays(
    np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0), np.arange(0)
)
