"""The oracle perception models: true obstacle states, optionally with noise.

* ``oracle``: to test planning under uncertainty without lasers, Gaussian noise (σ per axis) on each
  position and velocity estimate, drawn anew every cycle from the episode's generator, and the σ handed
  to the planner with the estimates. White noise on every cycle's velocity is a stress test: no tracker
  hands a planner estimates that jump independently from cycle to cycle.
* ``tracked``: what a robot's planner really sees. Each cycle every present person is *detected* at their
  true position plus Gaussian noise (σ ``position_noise_m`` per axis; the true radius), and the detections
  go through the project's Kalman tracker (:class:`~viapath.perception.tracking.MultiTargetTracker`, the
  laser chain's defaults) as the laser's do: the planner gets what the tracker reports
  (:meth:`~viapath.perception.tracking.MultiTargetTracker.people`): the confirmed tracks and the tentative
  ones near the robot, with the tracker's settled velocities and σ. So noise is correlated from cycle to
  cycle; a person appearing near the robot is reported in the cycle they appear, standing with a 1 m/s
  velocity σ, one farther away from their third detection on (the tracker's confirmation); and a
  person's velocity is the filter's, learnt over a few cycles.

Choices where the sources are silent, for ``tracked``: the tracker never turns a standing track into
static geometry (``static_after_s`` = inf): the oracle's static layer is the map, so a person standing
still stays a person; a σ of 0 is given to the filter as 1 mm (a filter needs some measurement noise;
the detections are then exact); white velocity noise (``velocity_noise_mps``) does not apply (velocities
are the filter's) and is refused.
"""

from __future__ import annotations

import numpy as np

from viapath.observation import Obstacles
from viapath.perception.base import Perception, WorldSnapshot
from viapath.perception.tracking import MultiTargetTracker, TrackerParams

MIN_DETECTION_SIGMA_M = 1e-3  # the σ handed to the tracker for exact detections


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


class TrackedOraclePerception(Perception):
    """True positions with Gaussian noise as detections, through the Kalman tracker (see the module)."""

    name = "tracked"

    def __init__(self, position_noise_m: float = 0.0, velocity_noise_mps: float = 0.0):
        if not (np.isfinite(position_noise_m) and position_noise_m >= 0):
            raise ValueError(f"position_noise_m: expected a number >= 0, found {position_noise_m}")
        if velocity_noise_mps not in (None, 0, 0.0):
            raise ValueError(
                "velocity_noise_mps: mode 'tracked' takes its velocities from the tracker; white velocity noise "
                "is mode 'oracle' (give 0, or mode: oracle)"
            )
        self.position_noise_m = float(position_noise_m)
        self.tracker_params = TrackerParams(static_after_s=np.inf)
        self._tracker = MultiTargetTracker(self.tracker_params)
        self.rng = np.random.default_rng(0)
        self._reported: list[Obstacles] = []
        self._truth: list[WorldSnapshot] = []

    def reset(self, rng: np.random.Generator) -> None:
        super().reset(rng)
        self._tracker.reset()
        self._reported, self._truth = [], []

    @property
    def tracker(self) -> MultiTargetTracker:
        return self._tracker

    def observe(self, world: WorldSnapshot) -> Obstacles:
        present = world.present()
        positions = world.obstacle_positions[present]
        if self.position_noise_m > 0 and len(positions):
            positions = positions + self.rng.normal(0.0, self.position_noise_m, positions.shape)
        sigma = max(self.position_noise_m, MIN_DETECTION_SIGMA_M)
        self._tracker.step(world.time_s, positions, np.full(len(positions), sigma), world.obstacle_radii_m[present])
        obstacles = self._tracker.people(world.robot_pose[:2]).finite()
        self._reported.append(obstacles)
        self._truth.append(world)
        return obstacles

    def episode_metrics(self) -> dict:
        from viapath.perception.laser import tracking_errors

        return tracking_errors(self._reported, self._truth)


def _sigmas(n: int, sigma: float) -> np.ndarray:
    return np.zeros(n) if sigma == 0 else np.full(n, sigma)  # np.zeros: the same zeros, without np.full's cost


# No obstacles: one instance handed out for every empty scene (its arrays hold nothing to change; they stay
# writeable, as the compiled functions are compiled for writeable arrays).
_NOBODY = Obstacles.of_fresh_arrays(
    np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0), np.arange(0)
)
