"""Helpers for the core tests: brute-force references written independently of viapath.

The references here use dense sampling only (no closed forms copied from the code under test), so
a test comparing against them checks the mathematics, not our own outputs.
"""

from __future__ import annotations

import os

import numpy as np
from hypothesis import HealthCheck, settings

# Applied per test (not a global profile, which would change other folders' hypothesis tests).
# VIAPATH_CORE_EXAMPLES=1000 for a long, randomised hunt; the default is quick and reproducible.
_LONG = "VIAPATH_CORE_EXAMPLES" in os.environ
core_settings = settings(
    max_examples=int(os.environ.get("VIAPATH_CORE_EXAMPLES", 60)),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
    derandomize=not _LONG,
)


def sample_polyline(waypoints: np.ndarray, per_segment: int = 4000):
    """Dense points along each segment: (S, per_segment, 2) points and their arc lengths (S, per_segment)."""
    waypoints = np.asarray(waypoints, dtype=float)
    f = np.linspace(0.0, 1.0, per_segment)
    a, b = waypoints[:-1], waypoints[1:]
    points = a[:, None, :] + f[None, :, None] * (b - a)[:, None, :]
    lengths = np.hypot(*(b - a).T)
    start_arc = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    arcs = start_arc[:, None] + f[None, :] * lengths[:, None]
    return points, arcs


def brute_segment_distances(points: np.ndarray, samples: np.ndarray) -> np.ndarray:
    """Distance of each point (P, 2) to each densely sampled segment (S, M, 2): (P, S), error <= half the spacing."""
    diff = points[:, None, None, :] - samples[None]
    return np.sqrt(np.min(np.sum(diff * diff, axis=-1), axis=-1))


def sampling_error(waypoints: np.ndarray, per_segment: int) -> float:
    """Largest possible error of :func:`brute_segment_distances`: half the sample spacing."""
    lengths = np.hypot(*np.diff(np.asarray(waypoints, dtype=float), axis=0).T)
    return float(np.max(lengths) / (per_segment - 1) / 2)


def rollout(state, commands, limits, dt_s, steps):
    """Positions (K, steps, 2) after each step of holding each of K commands (v, ω) from ``state``: the limited
    arcs of :func:`viapath.kinematics.step` in closed form (a held command ramps speed and turn rate to it at the
    acceleration limits; the positions are running sums of the arcs). The escape's roll-outs as the tests
    specify them (tests/test_kinematics.py holds them to stepping the robot)."""
    commands = np.asarray(commands, dtype=float).reshape(-1, 2)
    v_cmd = np.clip(commands[:, 0], 0.0, limits.max_speed_mps)
    w_cmd = np.clip(commands[:, 1], -limits.max_turn_rate_radps, limits.max_turn_rate_radps)
    ramp = np.arange(1, steps + 1)
    speed0, turn0 = float(state.speed_mps), float(state.turn_rate_radps)
    dv, dw = limits.max_accel_mps2 * dt_s * ramp, limits.max_turn_accel_radps2 * dt_s * ramp
    speed = speed0 + np.clip((v_cmd - speed0)[:, None], -dv, dv)
    turn = turn0 + np.clip((w_cmd - turn0)[:, None], -dw, dw)
    heading_after = float(state.heading_rad) + np.cumsum(turn * dt_s, axis=1)
    heading_before = np.concatenate(
        [np.full((len(commands), 1), float(state.heading_rad)), heading_after[:, :-1]], axis=1
    )
    straight = np.abs(turn) < 1e-9
    radius = speed / np.where(straight, 1.0, turn)
    dx = np.where(
        straight, speed * dt_s * np.cos(heading_before), radius * (np.sin(heading_after) - np.sin(heading_before))
    )
    dy = np.where(
        straight, speed * dt_s * np.sin(heading_before), -radius * (np.cos(heading_after) - np.cos(heading_before))
    )
    positions = np.empty((len(commands), steps, 2))
    positions[..., 0] = float(state.x) + np.cumsum(dx, axis=1)
    positions[..., 1] = float(state.y) + np.cumsum(dy, axis=1)
    return positions
