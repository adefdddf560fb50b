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

from collections.abc import Callable
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
    """Clusters of one or more scans. Points are listed cluster after cluster (beam order inside each)."""

    beam_index: np.ndarray  # (M,) beam of each clustered point (index into the concatenated beams)
    points: np.ndarray  # (M, 2) in the common frame (the scanner frame for a single scan)
    starts: np.ndarray  # (K,) first point of each cluster
    counts: np.ndarray  # (K,) points per cluster
    occluded: np.ndarray  # (K,) bool: a neighbouring beam just outside it is nearer (something in front)
    scan_index: np.ndarray  # (K,) which scan each cluster comes from
    all_points: np.ndarray  # (V, 2) every valid point, clustered or not (the fused scan)
    all_beam_index: np.ndarray  # (V,)

    def __len__(self) -> int:
        return len(self.starts)

    def cluster_points(self, k: int) -> np.ndarray:
        return self.points[self.starts[k] : self.starts[k] + self.counts[k]]

    @classmethod
    def empty(cls) -> Segments:
        i, b = np.zeros(0, dtype=int), np.zeros(0, dtype=bool)
        return cls(i, np.zeros((0, 2)), i, i, b, i, np.zeros((0, 2)), i)


def breakpoint_threshold_m(range_m: np.ndarray, beam_gap_rad: np.ndarray, params: SegmentationParams) -> np.ndarray:
    """Adaptive breakpoint distance ``D_max`` (Borges & Aldon) at ``range_m`` for beams ``beam_gap_rad`` apart."""
    angle = np.minimum(beam_gap_rad, 0.5 * params.grazing_angle_rad)  # keep sin(λ - Δφ) > 0
    return _threshold_from_sines(range_m, np.sin(angle), np.sin(params.grazing_angle_rad - angle), params)


def _threshold_from_sines(
    range_m: np.ndarray, sin_gap: np.ndarray, sin_rest: np.ndarray, params: SegmentationParams
) -> np.ndarray:
    """:func:`breakpoint_threshold_m` from ``sin(Δφ)`` and ``sin(λ - Δφ)`` (computed there, or read from
    :class:`BeamTables`)."""
    sigma = np.where(
        range_m < params.noise_switch_range_m, params.noise_sigma_near_m, params.noise_fraction_far * range_m
    )
    jump = range_m * sin_gap / sin_rest + 3.0 * sigma
    return np.maximum(jump, params.min_jump_m)


@dataclass(frozen=True)
class BeamTables:
    """What :func:`segment_beams` computes from the beam angles alone, computed once for a fixed beam
    layout (detection caches one per scanner set and parameters).

    ``cos_rad``/``sin_rad``: of each beam's angle. ``sin_gap[d - 1, i]`` and ``sin_rest[d - 1, i]``:
    ``sin(Δφ)`` and ``sin(λ - Δφ)`` of :func:`breakpoint_threshold_m` for beams ``i`` and ``i + d``
    (``Δφ = min(|φ[i + d] - φ[i]|, λ/2)``), for ``d`` up to ``max_gap_beams + 1``: the only beam pairs
    whose threshold matters (farther ones always split). The same numpy expressions on the same
    numbers, elementwise: the same values as computing them per scan.
    """

    cos_rad: np.ndarray  # (B,)
    sin_rad: np.ndarray  # (B,)
    sin_gap: np.ndarray  # (D, B); 0 where i + d is past the last beam
    sin_rest: np.ndarray  # (D, B); 1 there

    @classmethod
    def of(cls, angles_rad: np.ndarray, params: SegmentationParams) -> BeamTables:
        angles_rad = np.asarray(angles_rad, dtype=float)
        n, reach = len(angles_rad), params.max_gap_beams + 1
        sin_gap, sin_rest = np.zeros((reach, n)), np.ones((reach, n))
        for d in range(1, min(reach, n - 1) + 1):
            angle = np.minimum(np.abs(angles_rad[d:] - angles_rad[:-d]), 0.5 * params.grazing_angle_rad)
            sin_gap[d - 1, :-d] = np.sin(angle)
            sin_rest[d - 1, :-d] = np.sin(params.grazing_angle_rad - angle)
        return cls(np.cos(angles_rad), np.sin(angles_rad), sin_gap, sin_rest)


def segment_scan(
    ranges_m: np.ndarray, angles_rad: np.ndarray, params: SegmentationParams = SegmentationParams()
) -> Segments:
    """Cluster one sanitised scan (NaN = invalid) in its own frame."""
    ranges_m = np.asarray(ranges_m, dtype=float)
    return segment_beams(ranges_m, angles_rad, 0.0, 0.0, np.zeros(len(ranges_m), dtype=int), params)


def segment_beams(
    ranges_m,
    angles_rad,
    origin_x_m,
    origin_y_m,
    scan_index,
    params: SegmentationParams = SegmentationParams(),
    tables: BeamTables | None = None,
    splitter: Callable[..., Segments] | None = None,
) -> Segments:
    """Cluster the beams of several scans at once (concatenated, each in beam order).

    ``angles_rad`` and the beam origins (``origin_x_m``, ``origin_y_m``: scalars or per beam) are in
    a common frame (the robot frame); a cluster never spans two scans (``scan_index`` per beam).
    Clusters with fewer than ``min_points`` points are dropped; ``all_points`` keeps every valid point.
    ``tables``: :class:`BeamTables` of ``angles_rad`` and ``params`` when the caller keeps them (same result).
    ``splitter`` (with ``tables``): the clustering after the points, ``splitter(points, ranges, beams, scans, tables,
    params)``, in place of this numpy reference (the laser pipeline's compiled pass, the same result bit for bit).
    """
    ranges_m = np.asarray(ranges_m, dtype=float)
    valid = np.flatnonzero(np.isfinite(ranges_m))
    if len(valid) == 0:
        return Segments.empty()
    r = ranges_m[valid]
    a = np.asarray(angles_rad, dtype=float)[valid]
    ox = origin_x_m[valid] if np.ndim(origin_x_m) else origin_x_m
    oy = origin_y_m[valid] if np.ndim(origin_y_m) else origin_y_m
    points = np.empty((len(valid), 2))
    points[:, 0] = ox + r * (np.cos(a) if tables is None else tables.cos_rad[valid])
    points[:, 1] = oy + r * (np.sin(a) if tables is None else tables.sin_rad[valid])
    scans = np.asarray(scan_index)[valid]
    if splitter is not None and tables is not None:
        return splitter(points, r, valid, scans, tables, params)
    step = np.diff(points, axis=0)
    gap = np.sqrt(step[:, 0] ** 2 + step[:, 1] ** 2)
    beam_step = np.diff(valid)
    adjacent = (beam_step <= params.max_gap_beams + 1) & (scans[1:] == scans[:-1])
    near = np.minimum(r[:-1], r[1:])
    if tables is None:
        threshold = breakpoint_threshold_m(near, np.abs(np.diff(a)), params)
    else:  # its sines from the tables (wrong only where not adjacent, and those split anyway)
        row = np.minimum(beam_step, params.max_gap_beams + 1) - 1
        threshold = _threshold_from_sines(
            near, tables.sin_gap[row, valid[:-1]], tables.sin_rest[row, valid[:-1]], params
        )
    split = (gap > threshold) | ~adjacent
    starts = np.concatenate([[0], np.flatnonzero(split) + 1])
    counts = np.diff(np.append(starts, len(valid)))
    # Occlusion: the valid beam just before (after) a cluster, if adjacent, is nearer than its first (last) point.
    ends = starts + counts - 1
    occluded = np.zeros(len(starts), dtype=bool)
    inner = starts > 0
    s_in = starts[inner]
    occluded[inner] = adjacent[s_in - 1] & (r[s_in - 1] < r[s_in])
    inner = ends < len(valid) - 1
    e_in = ends[inner]
    occluded[inner] |= adjacent[e_in] & (r[e_in + 1] < r[e_in])
    all_points, all_beams = points, valid
    cluster_scan = scans[starts]
    keep = counts >= params.min_points
    if not keep.all():
        starts, counts, occluded, cluster_scan = starts[keep], counts[keep], occluded[keep], cluster_scan[keep]
        index = _ranges_index(starts, counts)
        valid, points = valid[index], points[index]
        starts = np.cumsum(counts) - counts
    return Segments(valid, points, starts, counts, occluded, cluster_scan, all_points, all_beams)


def _ranges_index(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Concatenation of ``arange(s, s + c)`` for each (start, count), without a Python loop."""
    if len(counts) == 0:
        return np.zeros(0, dtype=int)
    total = int(counts.sum())
    offsets = np.repeat(starts - (np.cumsum(counts) - counts), counts)
    return np.arange(total) + offsets
