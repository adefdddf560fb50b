"""Brute-force references for the planner tests, written independently of viapath's geometry.

Motion is sampled densely in time (no closed-form segment/disc checks copied from the code under
test): a robot leg and a constant-velocity obstacle are compared at every sample instant.
"""

from __future__ import annotations

import os

import numpy as np
from hypothesis import HealthCheck, settings

# Per-test settings (no global profile). VIAPATH_PLANNER_EXAMPLES=2000 for a long, randomised hunt.
_LONG = "VIAPATH_PLANNER_EXAMPLES" in os.environ
planner_settings = settings(
    max_examples=int(os.environ.get("VIAPATH_PLANNER_EXAMPLES", 100)),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
    derandomize=not _LONG,
)

SAMPLE_DT_S = 0.005


def robot_track(start, velocity, t0: float, t1: float, dt: float = SAMPLE_DT_S):
    """Sample instants in [t0, t1] (both ends included) and the robot's positions on a straight leg
    that starts at ``start`` at time ``t0`` with constant ``velocity``."""
    if t1 < t0:
        return np.zeros(0), np.zeros((0, 2))
    n = max(2, int(np.ceil((t1 - t0) / dt)) + 1)
    times = np.linspace(t0, t1, n)
    points = np.asarray(start, float) + (times - t0)[:, None] * np.asarray(velocity, float)
    return times, points


def obstacle_gaps(times, points, positions, velocities, radii):
    """(T, N) centre distance minus combined radius, obstacle j at ``positions[j] + velocities[j] t``."""
    centres = positions[None, :, :] + times[:, None, None] * velocities[None, :, :]
    distance = np.hypot(*(points[:, None, :] - centres).transpose(2, 0, 1))
    return distance - radii[None, :]


def piecewise_track(pieces, horizon_s: float):
    """Concatenate straight pieces ``(start, velocity, t0, t1)``, each cut at the horizon."""
    all_t, all_p = [np.zeros(0)], [np.zeros((0, 2))]
    for start, velocity, t0, t1 in pieces:
        times, points = robot_track(start, velocity, t0, min(t1, horizon_s))
        all_t.append(times)
        all_p.append(points)
    return np.concatenate(all_t), np.concatenate(all_p)
