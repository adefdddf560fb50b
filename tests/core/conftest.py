"""Shared helpers for the core tests: brute-force references written independently of viapath.

The references here use dense sampling only (no closed forms copied from the code under test), so
a test comparing against them checks the mathematics, not our own outputs.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, settings

SRC = Path(__file__).resolve().parents[2] / "src"
if str(SRC) not in sys.path:  # test the worktree's code, not another editable install
    sys.path.insert(0, str(SRC))

settings.register_profile(
    "core", max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
settings.register_profile("core-long", max_examples=1000, deadline=None)
settings.load_profile(os.environ.get("VIAPATH_HYPOTHESIS_PROFILE", "core"))


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
