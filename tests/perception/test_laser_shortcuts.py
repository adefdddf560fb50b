"""The laser chain's compiled steps and shortcuts against their specifications.

Each piece is checked on seeded random inputs against what it computes, worked out independently, or
against a plain numpy statement of it kept here as its specification, bit for bit:
* the segmentation's clustering (compiled, with its cached beam tables) against the per-scan numpy
  statement of the breakpoint rule (:func:`_segments_spec`);
* the detector's shape tests (:func:`~viapath.perception.detection.segment_shapes`: sagitta and convexity
  t-statistic of each segment) against their numpy statement (``_padded``, ``_chord_coordinates``,
  ``_convexity_t`` here; the pairwise summation, :mod:`viapath.sums`, is tested with the planner),
  and the t-statistic against a least-squares fit of each segment (np.linalg.lstsq);
* ``_merge_duplicates`` (its early return when nothing is close, the information it keeps when merging);
* ``gated_assignment`` against the cheapest pairing, every pairing tried;
* the tracker's cached motion model against the matrices it used to build every cycle.
"""

from __future__ import annotations

import numpy as np
import pytest

from viapath.perception.assignment import gated_assignment
from viapath.perception.detection import segment_shapes
from viapath.perception.segmentation import SegmentationParams, Segments
from viapath.perception.tracking import _motion_model

# -- the numpy statements of the detector's shape tests and of the segmentation (specifications) ---------------


def _padded(points, starts, counts):
    """Each segment as a row of the longest one's width (padding: its first point) and the mask of real points."""
    width = int(counts.max())
    column = np.arange(width)
    mask = column[None, :] < counts[:, None]
    index = np.where(mask, starts[:, None] + column[None, :], starts[:, None])
    return points[index], mask.astype(float)


def _chord_coordinates(padded, mask, first, chord, extent, origins):
    """Each point's coordinates along its segment's chord (``x``, from the chord's middle) and across it
    (``y``, positive towards the sensor); padded entries are 0."""
    u = chord / np.maximum(extent, 1e-12)[:, None]
    mid = first + 0.5 * chord
    n = np.stack([-u[:, 1], u[:, 0]], -1)
    n[((origins - mid) * n).sum(1) < 0] *= -1.0  # n points towards the sensor
    rel = padded - mid[:, None, :]
    x = (rel[..., 0] * u[:, None, 0] + rel[..., 1] * u[:, None, 1]) * mask
    y = (rel[..., 0] * n[:, None, 0] + rel[..., 1] * n[:, None, 1]) * mask
    return x, y, mid


def _convexity_t(x, y, mask, mid, origins, seg: SegmentationParams) -> np.ndarray:
    """t-statistic of the curvature towards the sensor of ``y = a + b x + c x²`` fitted across each chord
    (normal equations by Cramer's rule)."""
    x2 = x * x
    sx2 = x2.sum(1)
    a00, a01, a02, a11, a12, a22 = mask.sum(1), x.sum(1), sx2, sx2, (x2 * x).sum(1), (x2 * x2).sum(1)
    b0, b1, b2 = y.sum(1), (x * y).sum(1), (x2 * y).sum(1)
    c00, c01, c02 = a11 * a22 - a12 * a12, a02 * a12 - a01 * a22, a01 * a12 - a02 * a11
    c12, c22 = a01 * a02 - a00 * a12, a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    det = np.where(np.abs(det) > 1e-300, det, np.inf)
    curvature = (c02 * b0 + c12 * b1 + c22 * b2) / det
    inv22 = c22 / det
    distance = np.hypot(*(mid - origins).T)
    sigma = np.where(distance < seg.noise_switch_range_m, seg.noise_sigma_near_m, seg.noise_fraction_far * distance)
    return -curvature / (sigma * np.sqrt(np.maximum(inv22, 1e-30)))


def _segments_spec(ranges_m, angles_rad, origin_x_m, origin_y_m, scan_index, params) -> Segments:
    """Borges & Aldon's breakpoint rule on every pair of neighbouring valid beams, in numpy: split where the gap
    exceeds ``max(r sin Δφ / sin(λ - Δφ) + 3σ, min_jump)`` or more than ``max_gap_beams`` beams are invalid."""
    valid = np.flatnonzero(np.isfinite(ranges_m))
    r, a = ranges_m[valid], angles_rad[valid]
    points = np.stack([origin_x_m[valid] + r * np.cos(a), origin_y_m[valid] + r * np.sin(a)], -1)
    scans = scan_index[valid]
    gap = np.hypot(*np.diff(points, axis=0).T)
    adjacent = (np.diff(valid) <= params.max_gap_beams + 1) & (scans[1:] == scans[:-1])
    near = np.minimum(r[:-1], r[1:])
    angle = np.minimum(np.abs(np.diff(a)), 0.5 * params.grazing_angle_rad)
    sigma = np.where(near < params.noise_switch_range_m, params.noise_sigma_near_m, params.noise_fraction_far * near)
    jump = near * np.sin(angle) / np.sin(params.grazing_angle_rad - angle) + 3.0 * sigma
    split = (gap > np.maximum(jump, params.min_jump_m)) | ~adjacent
    starts = np.concatenate([[0], np.flatnonzero(split) + 1])
    counts = np.diff(np.append(starts, len(valid)))
    ends = starts + counts - 1
    occluded = np.array(
        [
            (s > 0 and adjacent[s - 1] and r[s - 1] < r[s]) or (e < len(r) - 1 and adjacent[e] and r[e + 1] < r[e])
            for s, e in zip(starts, ends, strict=True)
        ],
        dtype=bool,
    )
    keep = counts >= params.min_points
    index = np.concatenate([np.arange(s, s + c) for s, c in zip(starts[keep], counts[keep], strict=True)] + [[]])
    index = index.astype(np.int64)
    kept_counts = counts[keep]
    return Segments(
        valid[index],
        points[index],
        np.cumsum(kept_counts) - kept_counts,
        kept_counts,
        occluded[keep],
        scans[starts[keep]],
        points,
        valid,
    )


def _random_segments(rng, count):
    """``count`` segments (arcs of discs, straight pieces, noisy, 3-300 points) seen from random origins."""
    points, starts, counts, origins = [], [], [], []
    start = 0
    for _ in range(count):
        n = (
            int(rng.choice([3, 4, 7, 8, 9, 15, 16, 17, 40, 127, 128, 129, 200, 300]))
            if rng.random() < 0.5
            else int(rng.integers(3, 60))
        )
        origin = rng.uniform(-0.2, 0.2, 2)
        if rng.random() < 0.6:  # arc of a disc, seen from the origin
            centre = origin + rng.uniform(0.5, 5.0) * np.array([np.cos(a := rng.uniform(-np.pi, np.pi)), np.sin(a)])
            r = rng.uniform(0.03, 0.4)
            phi = np.arctan2(*(origin - centre)[::-1]) + np.linspace(-1.2, 1.2, n)
            p = centre + r * np.stack([np.cos(phi), np.sin(phi)], -1)
        else:  # straight piece (a wall)
            a, b = rng.uniform(-5, 5, 2), rng.uniform(-5, 5, 2)
            p = a + np.linspace(0, rng.uniform(0.01, 1.0), n)[:, None] * (b - a)
        p = p + rng.normal(0, rng.choice([0.0, 0.003, 0.02]), p.shape)
        if rng.random() < 0.05:
            p[:] = p[0]  # degenerate: every point the same (zero chord)
        points.append(p)
        starts.append(start)
        counts.append(n)
        origins.append(origin)
        start += n
    return np.concatenate(points), np.array(starts), np.array(counts), np.array(origins)


def _numpy_shape_tests(points, starts, counts, origins, seg):
    first = points[starts]
    chord = points[starts + counts - 1] - first
    extent = np.hypot(chord[:, 0], chord[:, 1])
    padded, mask = _padded(points, starts, counts)
    x, y, mid = _chord_coordinates(padded, mask, first, chord, extent, origins)
    return first, chord, extent, np.abs(y).max(1), x, y, mask, mid


def _same(a, b):
    return np.asarray(a).tobytes() == np.asarray(b).tobytes()


@pytest.mark.parametrize("seed", range(6))
def test_convexity_t_is_the_least_squares_curvature(seed):
    """Each segment's t-statistic is that of the curvature ``c`` of ``y = a + b x + c x²`` fitted by least
    squares to its points across the chord (np.linalg.lstsq), over its standard error ``sigma·sqrt((XᵀX)⁻¹₂₂)``
    with the range-dependent noise sigma, to within round-off (on segments with a well-posed fit)."""
    rng = np.random.default_rng(seed)
    seg = SegmentationParams()
    points, starts, counts, origins = _random_segments(rng, 30)
    first, chord, extent, _, x, y, mask, mid = _numpy_shape_tests(points, starts, counts, origins, seg)
    _, got = _shapes(points, starts, counts, first, chord, extent, origins, seg)
    checked = 0
    for row in range(len(x)):
        xs, ys = x[row][mask[row] > 0], y[row][mask[row] > 0]
        design = np.stack([np.ones_like(xs), xs, xs * xs], axis=1)
        if len(xs) < 4 or np.linalg.cond(design) > 1e6:
            continue
        coef = np.linalg.lstsq(design, ys, rcond=None)[0]
        distance = float(np.hypot(*(mid[row] - origins[row])))
        near = distance < seg.noise_switch_range_m
        sigma = seg.noise_sigma_near_m if near else seg.noise_fraction_far * distance
        error = sigma * np.sqrt(np.linalg.inv(design.T @ design)[2, 2])
        assert got[row] == pytest.approx(-coef[2] / error, rel=1e-6, abs=1e-6), row
        checked += 1
    assert checked > 10


def _shapes(points, starts, counts, first, chord, extent, origins, seg):
    """:func:`segment_shapes` of every segment: (sagitta, t-statistic)."""
    got_sagitta, got_t = np.empty(len(starts)), np.empty(len(starts))
    distance = np.hypot(*(first + 0.5 * chord - origins).T)
    segment_shapes(
        points,
        starts,
        counts,
        int(counts.max()),
        first,
        chord,
        extent,
        origins,
        distance,
        seg.noise_switch_range_m,
        seg.noise_sigma_near_m,
        seg.noise_fraction_far,
        got_sagitta,
        got_t,
    )
    return got_sagitta, got_t


@pytest.mark.parametrize("seed", range(6))
def test_shape_tests_are_their_numpy_statement_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    seg = SegmentationParams() if seed % 2 else SegmentationParams(noise_switch_range_m=3.0, noise_fraction_far=0.02)
    points, starts, counts, origins = _random_segments(rng, 40)
    first, chord, extent, sagitta, x, y, mask, mid = _numpy_shape_tests(points, starts, counts, origins, seg)
    with np.errstate(all="ignore"):
        t_numpy = _convexity_t(x, y, mask, mid, origins, seg)
    got_sagitta, got_t = _shapes(points, starts, counts, first, chord, extent, origins, seg)
    assert _same(got_sagitta, sagitta)
    assert _same(got_t, t_numpy)


def _best_total_cost(cost, gate):
    """The least total cost of any one-to-one pairing of allowed pairs (cost finite and at most ``gate``), each
    unpaired row and column costing ``gate / 2``: every pairing tried."""
    rows, cols = cost.shape

    def best(row, free):
        if row == rows:
            return 0.5 * gate * len(free)
        options = [0.5 * gate + best(row + 1, free)]
        for col in free:
            if np.isfinite(cost[row, col]) and cost[row, col] <= gate:
                options.append(cost[row, col] + best(row + 1, free - {col}))
        return min(options)

    return best(0, frozenset(range(cols)))


@pytest.mark.parametrize("seed", range(4))
def test_gated_assignment_is_the_cheapest_pairing(seed):
    """Pairs of allowed entries only, each row and column at most once, sorted, as Python ints, and no pairing
    is cheaper (every pairing of up to 6 rows and 6 columns tried)."""
    rng = np.random.default_rng(seed)
    paired = set()
    for _ in range(300):
        t, d = int(rng.integers(0, 7)), int(rng.integers(0, 7))
        cost = rng.uniform(0, 30, (t, d)) * rng.choice([1.0, 0.3])
        cost[rng.random((t, d)) < 0.3] = np.inf
        got = gated_assignment(cost, 13.8)
        assert got == sorted(got) and all(type(i) is int and type(j) is int for i, j in got)
        assert len({i for i, _ in got}) == len(got) == len({j for _, j in got})
        assert all(np.isfinite(cost[i, j]) and cost[i, j] <= 13.8 for i, j in got)
        total = sum(cost[i, j] for i, j in got) + 0.5 * 13.8 * (t + d - 2 * len(got))
        assert total == pytest.approx(_best_total_cost(cost, 13.8), abs=1e-9)
        paired.add(min(len(got), 2))
    assert paired == {0, 1, 2}


@pytest.mark.parametrize("dt", [0.1, 0.30000000000000004 - 0.2, 0.05, 1.0, 1e-3])
@pytest.mark.parametrize("sigma_a", [0.2, 0.5])
def test_motion_model_equals_reference(dt, sigma_a):
    f = np.eye(4)  # tracking.predict before wave 7, verbatim
    f[0, 2] = f[1, 3] = dt
    q = sigma_a**2
    qm = np.zeros((4, 4))
    qm[[0, 1], [0, 1]] = q * dt**3 / 3
    qm[[2, 3], [2, 3]] = q * dt
    qm[[0, 1, 2, 3], [2, 3, 0, 1]] = q * dt**2 / 2
    got_f, got_qm = _motion_model(dt, sigma_a)
    assert _same(got_f, f) and _same(got_qm, qm)


@pytest.mark.parametrize("seed", range(4))
def test_segment_beams_is_the_breakpoint_rule_bit_for_bit(seed):
    """The compiled clustering with the cached cosines, sines and breakpoint sines (BeamTables), and without
    tables given, gives the segments of the rule's numpy statement, bit for bit."""
    from viapath.perception.detection import _beam_layout
    from viapath.perception.scanner import ScannerModel, paper_scanners
    from viapath.perception.segmentation import BeamTables, segment_beams

    rng = np.random.default_rng(seed)
    scanner_sets = [
        paper_scanners(),
        (ScannerModel(name="wide", beam_count=1024, angle_increment_rad=2 * np.pi / 1024),),
        (ScannerModel(name="odd", beam_count=181, angle_increment_rad=np.deg2rad(1.0), mount_yaw_rad=0.3),),
    ]
    split = 0
    for scanners in scanner_sets:
        layout = _beam_layout(scanners)
        for params in (
            SegmentationParams(),
            SegmentationParams(max_gap_beams=0, min_points=1, grazing_angle_rad=0.3),
            SegmentationParams(max_gap_beams=3, min_points=5, min_jump_m=0.2),
        ):
            tables = BeamTables.of(layout.angles_rad, params)
            for _ in range(10):
                n = len(layout.angles_rad)
                ranges = np.repeat(rng.uniform(0.05, 5.5, n // 10 + 1), 10)[:n] + rng.normal(0, 0.01, n)
                ranges[rng.random(n) < rng.choice([0.0, 0.05, 0.5])] = np.nan
                args = (ranges, layout.angles_rad, layout.origin_x_m, layout.origin_y_m, layout.scan_index, params)
                want = _segments_spec(*args)
                split += len(want) > 1
                for got in (segment_beams(*args, tables), segment_beams(*args)):
                    for name in (
                        "beam_index",
                        "points",
                        "starts",
                        "counts",
                        "occluded",
                        "scan_index",
                        "all_points",
                        "all_beam_index",
                    ):
                        assert getattr(got, name).dtype == getattr(want, name).dtype, name
                        assert _same(getattr(got, name), getattr(want, name)), name
    assert split > 50


@pytest.mark.parametrize("seed", range(4))
def test_merge_duplicates_keeps_the_information(seed):
    """Merging fuses detections of different sources closer than the distance into their information-weighted
    mean: the total information (sum of 1/sigma²) and the information-weighted sum of the centres are kept, each
    merge removes one detection and keeps the larger radius; with no pair of different sources that close the
    detections come back as they were, bit for bit."""
    from viapath.perception.detection import _merge_duplicates

    rng = np.random.default_rng(seed)
    merged = untouched = 0
    for _ in range(200):
        n = int(rng.integers(0, 16))
        centres = rng.uniform(-1.0, 1.0, (n, 2)) * rng.choice([0.3, 1.0, 3.0])
        if n > 2:
            centres[1] = centres[0] + rng.normal(0, 0.05, 2)  # a front/rear pair of one object
        radii, sigma = rng.uniform(0.05, 0.4, n), rng.uniform(0.005, 0.1, n)
        source = rng.integers(0, 2, n)
        distance = float(rng.choice([0.0, 0.25, 0.6]))
        got = _merge_duplicates(centres, radii, sigma, source, distance)
        for a, b in zip(got, (centres, radii, sigma, source), strict=True):
            assert a.dtype == b.dtype and a.flags.c_contiguous
        gaps = np.hypot(*(centres[:, None] - centres[None]).transpose(2, 0, 1))
        close = (gaps < distance) & (source[:, None] != source[None])
        if not close.any():
            assert all(_same(a, b) for a, b in zip(got, (centres, radii, sigma, source))), "nothing to merge"
            untouched += 1
            continue
        out_centres, out_radii, out_sigma, _ = got
        assert len(out_centres) < n
        info, out_info = 1.0 / sigma**2, 1.0 / out_sigma**2
        assert out_info.sum() == pytest.approx(info.sum(), rel=1e-9)
        np.testing.assert_allclose(
            (out_info[:, None] * out_centres).sum(0), (info[:, None] * centres).sum(0), rtol=1e-9, atol=1e-9
        )
        assert set(out_radii.tolist()) <= set(radii.tolist()) and out_radii.max() == radii.max()
        merged += 1
    assert merged > 20 and untouched > 20
