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
* The sines of the threshold depend on the beam angles only: :class:`BeamTables` holds them for a
  fixed beam layout. The clustering is one compiled pass over neighbouring valid beams
  (:func:`viapath.jit.compiled`; plain Python when compilation is off).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from viapath.jit import compiled


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

    @classmethod
    def empty(cls) -> Segments:
        i, b = np.zeros(0, dtype=int), np.zeros(0, dtype=bool)
        return cls(i, np.zeros((0, 2)), i, i, b, i, np.zeros((0, 2)), i)


@dataclass(frozen=True)
class BeamTables:
    """What :func:`segment_beams` computes from the beam angles alone, computed once for a fixed beam
    layout (detection caches one per scanner set and parameters).

    ``cos_rad``/``sin_rad``: of each beam's angle. ``sin_gap[d - 1, i]`` and ``sin_rest[d - 1, i]``:
    ``sin(Δφ)`` and ``sin(λ - Δφ)`` of the threshold ``D_max`` for beams ``i`` and ``i + d``
    (``Δφ = min(|φ[i + d] - φ[i]|, λ/2)``), for ``d`` up to ``max_gap_beams + 1``: the only beam pairs
    whose threshold matters (farther ones always split).
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


def segment_beams(
    ranges_m,
    angles_rad,
    origin_x_m,
    origin_y_m,
    scan_index,
    params: SegmentationParams = SegmentationParams(),
    tables: BeamTables | None = None,
) -> Segments:
    """Cluster the beams of several scans at once (concatenated, each in beam order).

    ``angles_rad`` and the beam origins (``origin_x_m``, ``origin_y_m``: scalars or per beam) are in
    a common frame (the robot frame); a cluster never spans two scans (``scan_index`` per beam).
    Clusters with fewer than ``min_points`` points are dropped; ``all_points`` keeps every valid point.
    ``tables``: :class:`BeamTables` of ``angles_rad`` and ``params`` when the caller keeps them (same result).
    """
    ranges_m = np.asarray(ranges_m, dtype=float)
    valid = np.flatnonzero(np.isfinite(ranges_m))
    if len(valid) == 0:
        return Segments.empty()
    if tables is None:
        tables = BeamTables.of(angles_rad, params)
    r = ranges_m[valid]
    ox = origin_x_m[valid] if np.ndim(origin_x_m) else origin_x_m
    oy = origin_y_m[valid] if np.ndim(origin_y_m) else origin_y_m
    points = np.empty((len(valid), 2))
    points[:, 0] = ox + r * tables.cos_rad[valid]
    points[:, 1] = oy + r * tables.sin_rad[valid]
    scans = np.asarray(scan_index)[valid]
    n = len(valid)
    starts, counts, cluster_scan = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, scans.dtype)
    occluded, kept_points = np.empty(n, dtype=bool), np.empty(n, np.int64)
    kept, kept_total = split_clusters(
        points,
        r,
        valid,
        scans,
        tables.sin_gap,
        tables.sin_rest,
        (params.max_gap_beams, params.min_points),
        (params.noise_switch_range_m, params.noise_sigma_near_m, params.noise_fraction_far, params.min_jump_m),
        (starts, counts, occluded, cluster_scan, kept_points),
    )
    starts, counts, occluded, cluster_scan = starts[:kept], counts[:kept], occluded[:kept], cluster_scan[:kept]
    if kept_total == n:  # every cluster kept: the points as they are
        return Segments(valid, points, starts, counts, occluded, cluster_scan, points, valid)
    index = kept_points[:kept_total]
    return Segments(
        valid[index], points[index], np.cumsum(counts) - counts, counts, occluded, cluster_scan, points, valid
    )


@compiled
def split_clusters(points, r, valid, scans, sin_gap, sin_rest, beams, noise, out):
    """The clusters of :func:`segment_beams`: the valid beams ``valid`` (their ranges ``r`` and ``points``,
    their scans ``scans``) split where the threshold ``D_max`` says (its sines from :class:`BeamTables`),
    where more than ``max_gap_beams`` beams are invalid, and between scans.

    ``beams`` = (max_gap_beams, min_points); ``noise`` = (switch range, σ near, fraction far, min jump).
    Fills ``out`` = (starts (into the valid points), counts, occluded, scan, kept points' indices) for the
    clusters of at least ``min_points`` points; returns (clusters kept, points kept).
    """
    max_gap_beams, min_points = beams
    starts, counts, occluded, cluster_scan, kept_points = out
    n = r.shape[0]
    adjacent, split = _breaks(points, r, valid, scans, sin_gap, sin_rest, max_gap_beams, noise)
    kept = 0
    kept_total = 0
    first = 0
    for k in range(n):
        if k < n - 1 and not split[k]:
            continue
        last = k  # the cluster is first..last
        count = last - first + 1
        if count >= min_points:
            # Occluded: the valid beam just before (after) it, if adjacent, is nearer than its first (last) point.
            hidden = first > 0 and adjacent[first - 1] and r[first - 1] < r[first]
            hidden = hidden or (last < n - 1 and adjacent[last] and r[last + 1] < r[last])
            starts[kept] = first
            counts[kept] = count
            occluded[kept] = hidden
            cluster_scan[kept] = scans[first]
            for i in range(first, last + 1):
                kept_points[kept_total] = i
                kept_total += 1
            kept += 1
        first = k + 1
    return kept, kept_total


@compiled
def _breaks(points, r, valid, scans, sin_gap, sin_rest, max_gap_beams, noise):
    """Per pair of neighbouring valid beams: whether they are adjacent (at most ``max_gap_beams`` invalid beams
    between them, one scan) and whether the clusters split there (not adjacent, or a gap over the threshold)."""
    noise_switch_range, noise_sigma_near, noise_fraction_far, min_jump = noise
    n = r.shape[0]
    reach = max_gap_beams + 1
    adjacent = np.empty(max(n - 1, 0), dtype=np.bool_)
    split = np.empty(max(n - 1, 0), dtype=np.bool_)
    for k in range(n - 1):
        beam_step = valid[k + 1] - valid[k]
        adjacent[k] = beam_step <= reach and scans[k + 1] == scans[k]
        dx = points[k + 1, 0] - points[k, 0]
        dy = points[k + 1, 1] - points[k, 1]
        gap = np.sqrt(dx * dx + dy * dy)
        near = min(r[k], r[k + 1])
        row = min(beam_step, reach) - 1  # the sines of a wider gap are wrong, but it splits anyway
        sigma = noise_sigma_near if near < noise_switch_range else noise_fraction_far * near
        jump = near * sin_gap[row, valid[k]] / sin_rest[row, valid[k]] + 3.0 * sigma
        threshold = max(jump, min_jump)
        split[k] = gap > threshold or not adjacent[k]
    return adjacent, split
