"""From the scans of one cycle to round obstacles (centre, radius, centre uncertainty) in the robot frame.

Source: the usual 2-D laser people-detection chain (e.g. Arras, Martínez Mozos, Burgard, ICRA 2007;
Leigh et al., ICRA 2015; docs/design.md §3): segment each scan on range jumps
(:mod:`~viapath.perception.segmentation`), fit a circle to each segment
(:mod:`~viapath.perception.circle_fit`), keep the round, person- or leg-sized ones.

What we chose where the sources leave it open:
* **Walls and long segments** are rejected when a segment is longer than ``max_extent_m`` (a
  person seen from any side spans < 0.6 m), when it is straight (longer than ``line_min_extent_m``
  with a sagitta — largest distance from its chord — under ``line_max_sagitta_ratio`` of its
  length; a half circle has 0.5, a 90° arc 0.21), when its fitted radius is outside
  [``radius_min_m``, ``radius_max_m``], or when the fit residual RMS exceeds ``max_rms_m``. A
  segment partly hidden behind something nearer (a wall piece between two people) is rejected if
  it is flat: sagitta under ``occluded_max_sagitta_ratio`` (0.15) of its length, whatever its
  length (a round object keeps ≥ 0.2 even when half hidden) — from ``occluded_min_extent_m`` on. Finally a segment longer than
  ``flat_test_min_extent_m`` must bulge towards the sensor: a parabola fitted across its chord
  must curve towards the sensor with a t-statistic ≥ ``min_convexity_t`` (2) given the range
  noise; short wall pieces (between shadows, at the edge of the field of view) fail it.
* **Two scanners, one object**: the forward and backward scans overlap beside the robot; a front
  and a rear detection whose centres are closer than ``duplicate_distance_m`` are one object
  (centre: inverse-variance average).
* **Legs**: a walking person is often two leg segments (r ≈ 0.05–0.1 m) 0.1–0.45 m apart. Two
  leg-sized detections (fitted radius ≤ ``leg_max_radius_m``) whose centres are closer than
  ``leg_pair_distance_m`` (default 0.5 m) are one person, paired greedily, closest pair first, each
  leg used once; the person's centre is the midpoint, its radius half the leg distance plus the leg
  radius. A single leg is kept as a person too (the other leg is often hidden behind it). Leg-level
  centres are a poor estimate of the body centre (the legs swing ±0.2 m around it), so leg-derived
  detections get ``leg_position_sigma_m`` as measurement noise. Objects larger than a leg (the
  simulator's 0.25 m discs, a person in a long coat) are never paired, so two people walking side
  by side (≥ 0.5 m apart) stay two.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from viapath.jit import compiled
from viapath.options import Retired, RetiredNames
from viapath.perception.circle_fit import fit_circles, solve_sym3
from viapath.perception.fusion import FusedScan
from viapath.perception.scanner import ScannerModel
from viapath.perception.segmentation import BeamTables, SegmentationParams, segment_beams
from viapath.sums import pairwise_sum

_ONE_ARITHMETIC = "the laser chain has one implementation, compiled; plain Python when compilation is off"
#: The options the laser chain had to choose between its numpy and its compiled code (``ray_compute`` of the laser
#: perception, ``fit_compute`` of the detector and the ROS 2 node, and their earlier names): a scenario or
#: parameter file that still gives one is read with a FutureWarning (:meth:`~viapath.options.RetiredNames.drop`).
RETIRED_LASER_OPTIONS = RetiredNames(
    [Retired(name, _ONE_ARITHMETIC) for name in ("ray_compute", "fit_compute", "ray_backend", "fit_backend")],
    owner="laser chain",
)


@dataclass(frozen=True)
class DetectorParams:
    segmentation: SegmentationParams = field(default_factory=SegmentationParams)
    radius_prior_m: float | None = 0.25
    radius_prior_sigma_m: float = 0.1
    fixed_radius_m: float | None = None
    radius_min_m: float = 0.02
    radius_max_m: float = 0.6
    max_extent_m: float = 0.9
    line_min_extent_m: float = 0.25
    line_max_sagitta_ratio: float = 0.08
    max_rms_m: float = 0.06
    occluded_max_sagitta_ratio: float = 0.15
    occluded_min_extent_m: float = 0.0
    flat_test_min_extent_m: float | None = 0.1
    min_convexity_t: float = 2.0
    duplicate_distance_m: float = 0.25
    leg_max_radius_m: float = 0.15
    leg_pair_distance_m: float = 0.5
    leg_position_sigma_m: float = 0.1
    measurement_sigma_floor_m: float = 0.02
    iterations: int = 4
    keep_segments: bool = True  # per-segment points and fits, for plots and evaluation

    @classmethod
    def for_legs(cls, **overrides) -> DetectorParams:
        """Real scans of walking people: legs (r ≈ 0.06 m) are the round things the laser sees."""
        # A leg (≤ 0.15 m wide, often half hidden by the other leg, 5–10 points at 3–5 m) is too short
        # a curve for the flatness tests; two legs in one segment (0.2–0.35 m) are not convex.
        values: dict[str, Any] = dict(
            radius_prior_m=0.07,
            radius_prior_sigma_m=0.04,
            radius_max_m=0.3,
            max_extent_m=0.6,
            flat_test_min_extent_m=0.35,
            occluded_min_extent_m=0.15,
        )
        values.update(overrides)
        return cls(**values)


@dataclass
class Detections:
    """Obstacles found in one cycle, in the frame of the scanners' mounting poses (the robot frame)."""

    centres: np.ndarray  # (K, 2)
    radii_m: np.ndarray  # (K,)
    position_sigma_m: np.ndarray  # (K,) measurement noise for the tracker
    leg_count: np.ndarray  # (K,) 0 for a round object, 1 or 2 for a person seen by the legs
    segments: list = field(default_factory=list)  # per-segment info for plots and evaluation
    legs: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # leg-sized centres before pairing
    fused: FusedScan | None = None  # every valid point of the cycle, robot frame

    def __len__(self) -> int:
        return len(self.radii_m)

    @classmethod
    def empty(cls) -> Detections:
        return cls(np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0, dtype=int))

    def transformed(self, pose) -> Detections:
        """The same detections in the frame where the robot (or sensor) has ``pose`` (x, y, heading)."""
        x, y, heading = (float(v) for v in pose)
        c, s = np.cos(heading), np.sin(heading)
        rot = np.array([[c, -s], [s, c]])
        centres = self.centres @ rot.T + [x, y]
        legs = self.legs @ rot.T + [x, y] if len(self.legs) else self.legs
        return Detections(centres, self.radii_m, self.position_sigma_m, self.leg_count, self.segments, legs, self.fused)


def checked_scans(scanners, scans) -> list[np.ndarray]:
    """One float array per scanner, checked: one scan per scanner, in order (``None`` for a scanner
    with no reading this cycle, e.g. a dropped message: all its beams count as invalid), each with
    the scanner's beam count. Anything else raises :class:`~viapath.observation.ObservationError`
    naming the scan and the scanner (bad input never becomes motion)."""
    from viapath.observation import ObservationError

    names = ", ".join(repr(s.name) for s in scanners)
    try:
        scans = list(scans)
    except TypeError:
        raise ObservationError(
            f"scans: expected a list of {len(scanners)} scans ({names}), found {type(scans).__name__}"
        ) from None
    if len(scans) != len(scanners):
        raise ObservationError(
            f"scans: expected {len(scanners)} scans, one per scanner ({names}) in that order, "
            f"found {len(scans)}; pass None for a scanner without a reading this cycle"
        )
    parts = []
    for i, (scanner, ranges) in enumerate(zip(scanners, scans, strict=True)):
        if ranges is None:
            parts.append(np.full(scanner.beam_count, np.nan))
            continue
        try:
            ranges = np.asarray(ranges, dtype=float)
        except (TypeError, ValueError):
            raise ObservationError(
                f"scans[{i}] (scanner {scanner.name!r}): expected {scanner.beam_count} numbers"
            ) from None
        if ranges.ndim != 1 or len(ranges) != scanner.beam_count:
            raise ObservationError(
                f"scans[{i}] (scanner {scanner.name!r}): expected {scanner.beam_count} ranges "
                f"(its beam count), found shape {ranges.shape}"
            )
        parts.append(ranges)
    return parts


def detect(scanners, scans, params: DetectorParams = DetectorParams()) -> Detections:
    """Detect round obstacles in the scans of ``scanners`` (readings may encode invalid as 0/NaN/inf)."""
    scanners = tuple(scanners)
    layout = _beam_layout(scanners)
    ranges = np.concatenate(checked_scans(scanners, scans))
    # sanitize_ranges and each scanner's own range limits, in one pass: NaN for every invalid reading
    # (comparisons with NaN are quiet: no errstate needed).
    ranges[~np.isfinite(ranges) | (ranges <= 0.0) | (ranges < layout.range_min_m) | (ranges > layout.range_max_m)] = (
        np.nan
    )
    segments = segment_beams(
        ranges,
        layout.angles_rad,
        layout.origin_x_m,
        layout.origin_y_m,
        layout.scan_index,
        params.segmentation,
        _beam_tables(scanners, params.segmentation),
    )
    point_scan = layout.scan_index[segments.all_beam_index]
    fused = FusedScan(segments.all_points, point_scan, segments.all_beam_index - layout.first_beam[point_scan])
    if len(segments) == 0:
        empty = Detections.empty()
        empty.fused = fused
        return empty
    points, starts, counts = segments.points, segments.starts, segments.counts
    source, occluded = segments.scan_index, segments.occluded
    origins = layout.mount_xy_m[source]

    # Cheap tests first, on every segment; the circle fit only on what is left (walls are long and
    # would widen the padded fitting arrays to hundreds of points).
    first = points[starts]
    last = points[starts + counts - 1]
    chord = last - first
    extent = np.hypot(chord[:, 0], chord[:, 1])
    keep = extent <= params.max_extent_m
    candidates = np.flatnonzero(keep)
    if len(candidates):
        straight = _straight(points, starts, counts, first, chord, extent, origins, occluded, candidates, params)
        keep[candidates[straight]] = False
        candidates = candidates[~straight]
    centres_all, radii_all, sigma_all = _fit_candidates(points, starts, counts, origins, candidates, keep, params)
    keep[:] = keep & np.isfinite(radii_all)
    segment_info = (
        _segment_info(points, starts, counts, source, centres_all, radii_all, keep) if params.keep_segments else []
    )
    centres = centres_all[keep]
    radii = radii_all[keep]
    sigma = np.maximum(sigma_all[keep], params.measurement_sigma_floor_m)
    source = source[keep]
    centres, radii, sigma, source = _merge_duplicates(centres, radii, sigma, source, params.duplicate_distance_m)
    legs_mask = radii <= params.leg_max_radius_m
    legs = centres[legs_mask]
    centres, radii, sigma, leg_count = _pair_legs(centres, radii, sigma, legs_mask, params)
    return Detections(centres, radii, sigma, leg_count, segment_info, legs, fused)


def _fit_candidates(points, starts, counts, origins, candidates, keep, params) -> tuple[np.ndarray, ...]:
    """Circle fits of the ``candidates`` segments: centres, radii and centre sigmas of every segment (NaN where not
    fitted); a fit with an implausible radius or residual, or not finite, drops its segment from ``keep``."""
    centres_all = np.full((len(starts), 2), np.nan)
    radii_all = np.full(len(starts), np.nan)
    sigma_all = np.full(len(starts), np.nan)
    if len(candidates):
        fits = fit_circles(
            points,
            starts[candidates],
            counts[candidates],
            origins[candidates],
            radius_prior_m=params.radius_prior_m,
            radius_prior_sigma_m=params.radius_prior_sigma_m,
            fixed_radius_m=params.fixed_radius_m,
            range_sigma_m=params.segmentation.noise_sigma_near_m,
            iterations=params.iterations,
        )
        good = (
            (fits.radii_m >= params.radius_min_m)
            & (fits.radii_m <= params.radius_max_m)
            & (fits.rms_m <= params.max_rms_m)
            & np.isfinite(fits.centres).all(1)
        )
        centres_all[candidates], radii_all[candidates], sigma_all[candidates] = (
            fits.centres,
            fits.radii_m,
            fits.centre_sigma_m,
        )
        keep[candidates[~good]] = False
    return centres_all, radii_all, sigma_all


def _straight(points, starts, counts, first, chord, extent, origins, occluded, candidates, params) -> np.ndarray:
    """Which of the ``candidates`` segments are straight (walls, flat pieces), by the sagitta and the convexity
    t-statistic of each (:func:`segment_shapes`), or flat with something nearer beside them."""
    c_first, c_chord, c_extent, c_origins = (
        first[candidates],
        chord[candidates],
        extent[candidates],
        origins[candidates],
    )
    seg = params.segmentation
    sagitta, t_convex = np.empty(len(candidates)), np.empty(len(candidates))
    distance = np.hypot(*(c_first + 0.5 * c_chord - c_origins).T)  # from the sensor to the chord's middle
    segment_shapes(
        points,
        starts[candidates],
        counts[candidates],
        int(counts[candidates].max()),
        c_first,
        c_chord,
        c_extent,
        c_origins,
        distance,
        seg.noise_switch_range_m,
        seg.noise_sigma_near_m,
        seg.noise_fraction_far,
        sagitta,
        t_convex,
    )
    straight = (c_extent > params.line_min_extent_m) & (sagitta < params.line_max_sagitta_ratio * c_extent)
    if params.flat_test_min_extent_m is not None:
        straight |= (c_extent >= params.flat_test_min_extent_m) & (t_convex < params.min_convexity_t)
    # A flat piece with something nearer beside it: background seen between foreground objects.
    straight |= (
        occluded[candidates]
        & (c_extent >= params.occluded_min_extent_m)
        & (sagitta < params.occluded_max_sagitta_ratio * c_extent)
    )
    return straight


def _segment_info(points, starts, counts, source, centres, radii, accepted) -> list[dict]:
    """Per segment: the scanner, its points, the fitted circle and whether it was accepted (for plots)."""
    return [
        dict(
            scanner=int(source[k]),
            points=points[starts[k] : starts[k] + counts[k]],
            centre=centres[k],
            radius_m=float(radii[k]),
            accepted=bool(accepted[k]),
        )
        for k in range(len(starts))
    ]


def _merge_duplicates(centres, radii, sigma, source, distance_m):
    if len(centres) < 2 or distance_m <= 0 or source.min() == source.max():
        return centres, radii, sigma, source
    d = np.hypot(*(centres[:, None, :] - centres[None, :, :]).transpose(2, 0, 1))
    d[source[:, None] == source[None, :]] = np.inf
    if not (d < distance_m).any():  # nothing to merge: the loop below would stop at once
        return centres, radii, sigma, source
    alive = np.ones(len(centres), dtype=bool)
    centres, radii, sigma = centres.copy(), radii.copy(), sigma.copy()
    for flat in np.argsort(d, axis=None):
        i, j = divmod(int(flat), len(centres))
        if d[i, j] >= distance_m:
            break
        if i >= j or not (alive[i] and alive[j]):
            continue
        wi, wj = 1.0 / sigma[i] ** 2, 1.0 / sigma[j] ** 2
        centres[i] = (wi * centres[i] + wj * centres[j]) / (wi + wj)
        radii[i] = max(radii[i], radii[j])
        sigma[i] = np.sqrt(1.0 / (wi + wj))
        alive[j] = False
    return centres[alive], radii[alive], sigma[alive], source[alive]


def _pair_legs(centres, radii, sigma, legs_mask, params: DetectorParams):
    leg_count = np.where(legs_mask, 1, 0)
    sigma = np.where(legs_mask, np.maximum(sigma, params.leg_position_sigma_m), sigma)
    legs = np.flatnonzero(legs_mask)
    if len(legs) < 2 or params.leg_pair_distance_m <= 0:
        return centres, radii, sigma, leg_count
    sub = centres[legs]
    d = np.hypot(*(sub[:, None, :] - sub[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    alive = np.ones(len(centres), dtype=bool)
    used = np.zeros(len(legs), dtype=bool)
    centres, radii = centres.copy(), radii.copy()
    for flat in np.argsort(d, axis=None):
        a, b = divmod(int(flat), len(legs))
        if d[a, b] >= params.leg_pair_distance_m:
            break
        if a >= b or used[a] or used[b]:
            continue
        used[a] = used[b] = True
        i, j = legs[a], legs[b]
        centres[i] = 0.5 * (centres[i] + centres[j])
        radii[i] = 0.5 * d[a, b] + max(radii[i], radii[j])
        leg_count[i] = 2
        alive[j] = False
    return centres[alive], radii[alive], sigma[alive], leg_count[alive]


# -- the detector's shape tests ----------------------------------------------------------------
# Both come from the points' coordinates along each segment's chord and across it. The sums are numpy's
# pairwise sums of a row of ``width`` terms (the segment padded with zero terms), as the detector's numpy
# formulation summed them: the convexity test sits on a threshold, and its verdicts stay those of that
# formulation to the last bit.


@compiled(error_model="numpy")
def segment_shapes(
    points,
    starts,
    counts,
    width,
    first,
    chord,
    extent,
    origins,
    distance,
    noise_switch_range,
    noise_sigma_near,
    noise_fraction_far,
    sagitta,
    t_convex,
):
    """Per segment ``k`` (``points[starts[k] : starts[k] + counts[k]]``, chord ``chord[k]`` from ``first[k]``,
    of length ``extent[k]``, seen from ``origins[k]`` at ``distance[k]``): ``sagitta[k]``, the largest distance
    of a point from the chord, and ``t_convex[k]``, the t-statistic of the curvature towards the sensor of
    ``y = a + b x + c x²`` fitted across the chord (``x`` along it from its middle, ``y`` across it towards the
    sensor), given the range noise at ``distance[k]``. ``width``: at least the largest count."""
    terms = np.empty((8, width))
    sums = np.empty(8)
    for k in range(starts.shape[0]):
        sagitta[k] = _chord_terms(points, starts[k], counts[k], first[k], chord[k], extent[k], origins[k], terms)
        for q in range(8):
            sums[q] = 0.0 + pairwise_sum(terms[q], 0, width)
        # Least squares: (count, Σx, Σx², Σx², Σx³, Σx⁴) (a, b, c) = (Σy, Σxy, Σx²y); c and (A⁻¹)₂₂.
        _, _, curvature, _, _, _, inv22 = solve_sym3(
            sums[0], sums[1], sums[2], sums[2], sums[3], sums[4], sums[5], sums[6], sums[7]
        )
        sigma = noise_sigma_near if distance[k] < noise_switch_range else noise_fraction_far * distance[k]
        t_convex[k] = -curvature / (sigma * np.sqrt(max(inv22, 1e-30)))


@compiled(error_model="numpy")
def _chord_terms(points, start, count, first, chord, extent, origin, terms):
    """The eight terms of :func:`segment_shapes`' sums for each point of one segment (columns past ``count``:
    0), ``(1, x, x², x³, x⁴, y, xy, x²y)``; returns the sagitta, the largest ``|y|``."""
    ux = chord[0] / max(extent, 1e-12)
    uy = chord[1] / max(extent, 1e-12)
    mx = first[0] + 0.5 * chord[0]
    my = first[1] + 0.5 * chord[1]
    nx = -uy
    ny = ux
    if (0.0 + (origin[0] - mx) * nx) + (origin[1] - my) * ny < 0:  # n points towards the sensor
        nx = nx * -1.0
        ny = ny * -1.0
    largest = 0.0
    for p in range(terms.shape[1]):
        on = p < count
        mask = 1.0 if on else 0.0
        i = start + p if on else start
        rx = points[i, 0] - mx
        ry = points[i, 1] - my
        x = (rx * ux + ry * uy) * mask
        y = (rx * nx + ry * ny) * mask
        largest = max(largest, abs(y))
        x2 = x * x
        terms[0, p] = mask
        terms[1, p] = x
        terms[2, p] = x2
        terms[3, p] = x2 * x
        terms[4, p] = x2 * x2
        terms[5, p] = y
        terms[6, p] = x * y
        terms[7, p] = x2 * y
    return largest


@dataclass(frozen=True)
class _BeamLayout:
    """Every beam of a set of scanners, concatenated, in the robot frame (cached per scanner set)."""

    angles_rad: np.ndarray
    origin_x_m: np.ndarray
    origin_y_m: np.ndarray
    scan_index: np.ndarray
    first_beam: np.ndarray
    range_min_m: np.ndarray
    range_max_m: np.ndarray
    mount_x_m: np.ndarray
    mount_y_m: np.ndarray
    mount_xy_m: np.ndarray  # (S, 2): mount_x_m, mount_y_m side by side


@lru_cache(maxsize=16)
def _beam_tables(scanners: tuple[ScannerModel, ...], segmentation: SegmentationParams) -> BeamTables:
    return BeamTables.of(_beam_layout(scanners).angles_rad, segmentation)


@lru_cache(maxsize=16)
def _beam_layout(scanners: tuple[ScannerModel, ...]) -> _BeamLayout:
    counts = [s.beam_count for s in scanners]
    rep = lambda values: np.repeat(np.asarray(values, dtype=float), counts)
    return _BeamLayout(
        angles_rad=np.concatenate([s.beam_angles_rad() + s.mount_yaw_rad for s in scanners]),
        origin_x_m=rep([s.mount_x_m for s in scanners]),
        origin_y_m=rep([s.mount_y_m for s in scanners]),
        scan_index=np.repeat(np.arange(len(scanners)), counts),
        first_beam=np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(int),
        range_min_m=rep([s.range_min_m for s in scanners]),
        range_max_m=rep([s.range_max_m for s in scanners]),
        mount_x_m=np.array([s.mount_x_m for s in scanners]),
        mount_y_m=np.array([s.mount_y_m for s in scanners]),
        mount_xy_m=np.array([[s.mount_x_m, s.mount_y_m] for s in scanners], dtype=float),
    )
