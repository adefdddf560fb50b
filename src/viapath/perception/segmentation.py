"""Split one scan into clusters of neighbouring beams on range jumps that grow with range.

Source: the adaptive breakpoint detector of Borges & Aldon ("Line extraction in 2D range images
for mobile robotics", J. Intell. Robot. Syst. 40, 2004): consecutive points ``p_{n-1}``, ``p_n``
``Δφ`` apart belong to different objects when

    |p_n - p_{n-1}| > D_max = r · sin(Δφ) / sin(λ - Δφ) + 3 σ_r,

i.e. when the gap is wider than a surface seen at the grazing angle ``λ`` would produce, plus the
range noise. The threshold grows linearly with range, as it must: neighbouring beams diverge.

What the source leaves open and we chose:
* ``r`` is the *smaller* of the two ranges (symmetric in the two points; the near object decides).
* ``λ = 10°`` and ``σ_r`` from the scanner's noise model at that range (defaults: URG-04LX).
* Invalid beams (NaN after :func:`~viapath.perception.scanner.sanitize_ranges`) are skipped; a run of
  more than ``max_gap_beams`` invalid beams always splits (a dark or absorbing patch of one or two
  beams inside a leg is common; a longer hole means we do not know what is there).
* A floor on the threshold (``min_jump_m``) so that near objects are not shattered by noise.
* Each cluster records whether a neighbouring beam just outside it is *nearer* (``occluded``):
  then part of it is hidden behind something, which is how a piece of wall between two people
  looks; detection uses this to reject straight occluded pieces.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SegmentationParams:
    grazing_angle_rad: float = np.deg2rad(10.0)  # λ
    noise_sigma_near_m: float = 0.010
    noise_fraction_far: float = 0.01
    noise_switch_range_m: float = 1.0
    min_jump_m: float = 0.05
    max_gap_beams: int = 2
    min_points: int = 3


@dataclass
class Segments:
    """Clusters of one scan. Points are listed cluster after cluster (beam order inside each)."""

    beam_index: np.ndarray  # (M,) beam of each point
    points: np.ndarray  # (M, 2) in the scanner frame
    starts: np.ndarray  # (K,) first point of each cluster
    counts: np.ndarray  # (K,) points per cluster
    occluded: np.ndarray | None = None  # (K,) bool: a neighbouring beam just outside it is nearer (something in front)

    def __len__(self) -> int:
        return len(self.starts)

    def cluster_points(self, k: int) -> np.ndarray:
        return self.points[self.starts[k]:self.starts[k] + self.counts[k]]


def breakpoint_threshold_m(range_m: np.ndarray, beam_gap_rad: np.ndarray, params: SegmentationParams) -> np.ndarray:
    """Adaptive breakpoint distance ``D_max`` (Borges & Aldon) at ``range_m`` for beams ``beam_gap_rad`` apart."""
    sigma = np.where(range_m < params.noise_switch_range_m, params.noise_sigma_near_m, params.noise_fraction_far * range_m)
    angle = np.minimum(beam_gap_rad, 0.5 * params.grazing_angle_rad)  # keep sin(λ - Δφ) > 0
    jump = range_m * np.sin(angle) / np.sin(params.grazing_angle_rad - angle) + 3.0 * sigma
    return np.maximum(jump, params.min_jump_m)


def segment_scan(ranges_m: np.ndarray, angles_rad: np.ndarray, params: SegmentationParams = SegmentationParams()) -> Segments:
    """Cluster a sanitised scan (NaN = invalid). Clusters with fewer than ``min_points`` points are dropped."""
    ranges_m = np.asarray(ranges_m, dtype=float)
    valid = np.flatnonzero(np.isfinite(ranges_m))
    if len(valid) == 0:
        return Segments(np.zeros(0, dtype=int), np.zeros((0, 2)), np.zeros(0, dtype=int), np.zeros(0, dtype=int),
                        np.zeros(0, dtype=bool))
    r = ranges_m[valid]
    a = np.asarray(angles_rad, dtype=float)[valid]
    points = np.stack([r * np.cos(a), r * np.sin(a)], axis=-1)
    step = np.diff(points, axis=0)
    gap = np.hypot(step[:, 0], step[:, 1])
    threshold = breakpoint_threshold_m(np.minimum(r[:-1], r[1:]), np.abs(np.diff(a)), params)
    split = (gap > threshold) | (np.diff(valid) > params.max_gap_beams + 1)
    starts = np.concatenate([[0], np.flatnonzero(split) + 1])
    counts = np.diff(np.concatenate([starts, [len(valid)]]))
    # Occlusion: the valid beam just before (after) a cluster, if adjacent, is nearer than its first (last) point.
    ends = starts + counts - 1
    before = np.zeros(len(starts), dtype=bool)
    after = np.zeros(len(starts), dtype=bool)
    has_before = (starts > 0)
    has_before[has_before] &= (valid[starts[has_before]] - valid[starts[has_before] - 1]) <= params.max_gap_beams + 1
    before[has_before] = r[starts[has_before] - 1] < r[starts[has_before]]
    has_after = ends < len(valid) - 1
    has_after[has_after] &= (valid[ends[has_after] + 1] - valid[ends[has_after]]) <= params.max_gap_beams + 1
    after[has_after] = r[ends[has_after] + 1] < r[ends[has_after]]
    occluded = before | after
    keep = counts >= params.min_points
    if not keep.all():
        starts, counts, occluded = starts[keep], counts[keep], occluded[keep]
        index = _ranges_index(starts, counts)
        valid, points = valid[index], points[index]
        starts = (np.cumsum(counts) - counts).astype(int)
    return Segments(valid, points, starts, counts, occluded)


def _ranges_index(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Concatenation of ``arange(s, s + c)`` for each (start, count), without a Python loop."""
    if len(counts) == 0:
        return np.zeros(0, dtype=int)
    total = int(counts.sum())
    offsets = np.repeat(starts - (np.cumsum(counts) - counts), counts)
    return np.arange(total) + offsets
