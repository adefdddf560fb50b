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
