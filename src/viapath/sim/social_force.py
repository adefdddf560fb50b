"""A small numpy social-force crowd, to move simulated pedestrians (not the robot).

Source: D. Helbing and P. Molnár, "Social force model for pedestrian dynamics", Phys. Rev. E 51(5),
4282-4286, 1995. Each pedestrian a obeys

    dv_a/dt = (v0_a e_a - v_a) / tau                                  (Eq. 2, driving term)
              + sum_b w(e_a, -f_ab) f_ab                                (Eq. 3-4, other pedestrians)
              + sum_B f_aB                                              (Eq. 5, walls)

* f_ab = -grad_{r_ab} V0 exp(-b/sigma), with the elliptic semi-minor axis
  2b = sqrt((|r_ab| + |r_ab - v_b dt_s e_b|)^2 - (v_b dt_s)^2)   (Eq. 4; r_ab = r_a - r_b),
  V0 = 2.1 m^2/s^2, sigma = 0.3 m, dt_s = 2 s (paper values).
* f_aB = -grad U0 exp(-|r_aB|/R), U0 = 10 m^2/s^2, R = 0.2 m, r_aB to the nearest wall point.
* w = 1 inside the field of view (2 phi = 200 deg), c = 0.5 outside (Eq. 8).
* |v_a| is capped at 1.3 v0_a (Eq. 11).

What the paper leaves open and we chose:
* Integration: semi-implicit Euler (velocity first, then position) at ``step_s`` = 0.05 s.
* The gradient of the elliptic potential is analytic:
  grad_r b = (|r| + |r - s|) / (4 b) * (r/|r| + (r - s)/|r - s|), with s = v_b dt_s e_b.
* Pedestrians head for a list of waypoints each; they switch to the next within ``reach_m`` and stop
  (v0 = 0, so they come to rest) at the last one. No attraction terms (Eq. 6-7) and no fluctuations.
* The paper's pedestrians are points: we pass radii only to keep the potential's distance
  surface-to-surface (b is computed from centre distance minus the sum of radii plus ``2 sigma``)
  so larger people keep further apart; with zero radii this is the paper's model.
* The robot is not an agent here: the crowd is precomputed and does not react to it (as the
  replayed ETH/UCY people do not).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from viapath.forecast import elliptic_repulsion


@dataclass(frozen=True)
class SocialForceParams:
    relaxation_time_s: float = 0.5  # tau
    agent_strength_m2ps2: float = 2.1  # V0
    agent_range_m: float = 0.3  # sigma
    step_time_s: float = 2.0  # dt in Eq. 4
    wall_strength_m2ps2: float = 10.0  # U0
    wall_range_m: float = 0.2  # R
    field_of_view_rad: float = np.radians(100.0)  # phi (half-angle)
    outside_view_weight: float = 0.5  # c
    max_speed_factor: float = 1.3
    step_s: float = 0.05
    reach_m: float = 0.3


@dataclass
class CrowdTrajectory:
    times_s: np.ndarray  # (T,)
    positions: np.ndarray  # (T, N, 2)
    velocities: np.ndarray  # (T, N, 2)


def _wall_forces(positions: np.ndarray, walls: np.ndarray, params: SocialForceParams) -> np.ndarray:
    if len(walls) == 0:
        return np.zeros_like(positions)
    a, b = walls[:, 0], walls[:, 1]  # (W, 2)
    ab = b - a
    length_sq = np.maximum(np.sum(ab * ab, axis=1), 1e-12)
    rel = positions[:, None, :] - a[None]  # (N, W, 2)
    t = np.clip(np.sum(rel * ab[None], axis=2) / length_sq, 0.0, 1.0)
    away = rel - t[..., None] * ab[None]
    distance = np.maximum(np.hypot(away[..., 0], away[..., 1]), 1e-6)
    magnitude = params.wall_strength_m2ps2 / params.wall_range_m * np.exp(-distance / params.wall_range_m)
    return np.sum(magnitude[..., None] * away / distance[..., None], axis=1)


def simulate_crowd(
    starts,
    routes: list,
    desired_speeds_mps,
    duration_s: float,
    sample_dt_s: float = 0.1,
    radii_m=0.25,
    walls=None,
    start_times_s=None,
    params: SocialForceParams | None = None,
) -> CrowdTrajectory:
    """Simulate N pedestrians, each from ``starts[i]`` through the points of ``routes[i]``.

    ``start_times_s[i]``: the pedestrian stands still at its start until then. Returns the states
    sampled every ``sample_dt_s`` from 0 to ``duration_s``.
    """
    params = params or SocialForceParams()
    positions = np.asarray(starts, dtype=float).reshape(-1, 2).copy()
    n = len(positions)
    routes = [np.asarray(route, dtype=float).reshape(-1, 2) for route in routes]
    if len(routes) != n:
        raise ValueError("one route per pedestrian")
    desired = np.broadcast_to(np.asarray(desired_speeds_mps, dtype=float), (n,)).copy()
    radii = np.broadcast_to(np.asarray(radii_m, dtype=float), (n,)).copy()
    start_times = np.zeros(n) if start_times_s is None else np.broadcast_to(np.asarray(start_times_s, float), (n,))
    walls = np.zeros((0, 2, 2)) if walls is None else np.asarray(walls, dtype=float).reshape(-1, 2, 2)
    velocities = np.zeros((n, 2))
    next_point = np.zeros(n, dtype=int)

    n_samples = int(round(duration_s / sample_dt_s)) + 1
    substeps = max(1, int(round(sample_dt_s / params.step_s)))
    h = sample_dt_s / substeps
    out_p = np.zeros((n_samples, n, 2))
    out_v = np.zeros((n_samples, n, 2))
    time_s = 0.0
    for k in range(n_samples):
        out_p[k], out_v[k] = positions, velocities
        if k == n_samples - 1:
            break
        for _ in range(substeps):
            goals = np.array([routes[i][min(next_point[i], len(routes[i]) - 1)] for i in range(n)])
            to_goal = goals - positions
            distance = np.hypot(to_goal[:, 0], to_goal[:, 1])
            last = next_point >= np.array([len(r) - 1 for r in routes])
            advance = (distance < params.reach_m) & ~last
            next_point[advance] += 1
            done = (distance < params.reach_m) & last
            active = (time_s >= start_times) & ~done
            direction = to_goal / np.maximum(distance, 1e-9)[:, None]
            target_velocity = np.where(active[:, None], desired[:, None] * direction, 0.0)
            accel = (target_velocity - velocities) / params.relaxation_time_s
            accel += (
                elliptic_repulsion(
                    positions,
                    velocities,
                    radii[:, None] + radii[None, :],
                    (params.agent_strength_m2ps2, params.agent_range_m, params.step_time_s),
                    (params.field_of_view_rad, params.outside_view_weight),
                )
                * active[:, None]
            )
            accel += _wall_forces(positions, walls, params) * active[:, None]
            velocities = velocities + h * accel
            speed = np.hypot(velocities[:, 0], velocities[:, 1])
            cap = params.max_speed_factor * desired
            velocities *= np.where(speed > cap, cap / np.maximum(speed, 1e-12), 1.0)[:, None]
            velocities[~active & (time_s < start_times)] = 0.0
            positions = positions + h * velocities
            time_s += h
    return CrowdTrajectory(np.arange(n_samples) * sample_dt_s, out_p, out_v)
