"""The laser chain's shortcuts of wave 7 (docs/CHANGELOG-speed.md, "The laser chain (wave 7)") change no value.

Each rewritten piece is held to its earlier form, kept here verbatim as the reference, bit for bit,
on seeded random inputs:
* the cached beam tables of the segmentation and its compiled clustering against the per-scan numpy path;
* the numba shape tests of the detector (sagitta and convexity t-statistic of each segment) against
  the numpy path (``_padded``, ``_chord_coordinates``, ``_convexity_t``) (the pairwise summation they
  share with the escape kernel, :mod:`viapath.compiled.sums`, is tested in tests/planning/test_backends.py);
* ``_convexity_t``'s single stacked reduction against its eight separate ``.sum(1)``;
* ``_merge_duplicates`` (its early return when nothing is close);
* ``gated_assignment``'s direct answer for one-to-one gates against the union-find path;
* the tracker's cached motion model against the matrices it used to build every cycle.
"""

from __future__ import annotations

import numpy as np
import pytest

from viapath.perception.assignment import (
    _components,
    gated_assignment,
    linear_sum_assignment,
)
from viapath.perception.circle_fit import _numba_fit, _padded, solve_sym3
from viapath.perception.detection import _chord_coordinates, _convexity_t
from viapath.perception.segmentation import SegmentationParams
from viapath.perception.tracking import _motion_model

needs_numba = pytest.mark.skipif(_numba_fit() is None, reason="numba not installed")


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


def _convexity_t_reference(x, y, mask, mid, origins, seg):
    """``detection._convexity_t`` before wave 7, verbatim (eight separate row sums)."""
    count = mask.sum(1)
    x2 = x * x
    a = (count, x.sum(1), x2.sum(1), x2.sum(1), (x2 * x).sum(1), (x2 * x2).sum(1))
    coef, cofactors, det = solve_sym3(a, (y.sum(1), (x * y).sum(1), (x2 * y).sum(1)))
    inv22 = cofactors[5] / det
    distance = np.hypot(*(mid - origins).T)
    sigma = np.where(distance < seg.noise_switch_range_m, seg.noise_sigma_near_m, seg.noise_fraction_far * distance)
    return -coef[2] / (sigma * np.sqrt(np.maximum(inv22, 1e-30)))


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
def test_stacked_convexity_sums_equal_separate_sums(seed):
    rng = np.random.default_rng(seed)
    seg = SegmentationParams()
    points, starts, counts, origins = _random_segments(rng, 30)
    *_, x, y, mask, mid = _numpy_shape_tests(points, starts, counts, origins, seg)
    with np.errstate(all="ignore"):
        assert _same(_convexity_t(x, y, mask, mid, origins, seg), _convexity_t_reference(x, y, mask, mid, origins, seg))


@needs_numba
@pytest.mark.parametrize("seed", range(6))
def test_numba_shape_tests_equal_numpy(seed):
    from viapath.compiled.perception import segment_shape_kernel

    rng = np.random.default_rng(seed)
    seg = SegmentationParams() if seed % 2 else SegmentationParams(noise_switch_range_m=3.0, noise_fraction_far=0.02)
    points, starts, counts, origins = _random_segments(rng, 40)
    first, chord, extent, sagitta, x, y, mask, mid = _numpy_shape_tests(points, starts, counts, origins, seg)
    with np.errstate(all="ignore"):
        t_numpy = _convexity_t(x, y, mask, mid, origins, seg)
    got_sagitta, got_t = np.empty(len(starts)), np.empty(len(starts))
    distance = np.hypot(*(first + 0.5 * chord - origins).T)
    segment_shape_kernel(
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
    assert _same(got_sagitta, sagitta)
    assert _same(got_t, t_numpy)
    # and on a subset of the rows padded to the full width, as detect() hands the long segments to _convexity_t
    rows = rng.random(len(starts)) < 0.5
    with np.errstate(all="ignore"):
        assert _same(got_t[rows], _convexity_t(x[rows], y[rows], mask[rows], mid[rows], origins[rows], seg))


def _gated_assignment_reference(cost, gate):
    """``assignment.gated_assignment`` before wave 7, verbatim (every component through union-find)."""
    cost = np.asarray(cost, dtype=float)
    allowed = np.isfinite(cost) & (cost <= gate)
    pairs = []
    if not allowed.any():
        return pairs
    for rows, cols in _components(allowed):
        if len(rows) == 1 and len(cols) == 1:
            pairs.append((rows[0], cols[0]))
            continue
        sub = cost[np.ix_(rows, cols)]
        sub_allowed = allowed[np.ix_(rows, cols)]
        t, d = sub.shape
        big = np.full((t + d, d + t), 1e12)
        big[:t, :d] = np.where(sub_allowed, sub, 1e12)
        big[np.arange(t), d + np.arange(t)] = 0.5 * gate
        big[t + np.arange(d), np.arange(d)] = 0.5 * gate
        big[t:, d:] = 0.0
        r, c = linear_sum_assignment(big)
        for i, j in zip(r, c, strict=True):
            if i < t and j < d and sub_allowed[i, j]:
                pairs.append((rows[i], cols[j]))
    return sorted(pairs)


@pytest.mark.parametrize("seed", range(4))
def test_gated_assignment_equals_reference(seed):
    rng = np.random.default_rng(seed)
    for _ in range(300):
        t, d = int(rng.integers(0, 9)), int(rng.integers(0, 9))
        cost = rng.uniform(0, 30, (t, d)) * rng.choice([1.0, 0.3])
        cost[rng.random((t, d)) < 0.3] = np.inf
        got, want = gated_assignment(cost, 13.8), _gated_assignment_reference(cost, 13.8)
        assert got == want
        assert all(type(i) is int and type(j) is int for i, j in got)


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
def test_segment_beams_with_tables_equals_without(seed):
    """The cached cosines, sines and breakpoint sines (BeamTables), and the compiled clustering, give the
    segments of the per-scan numpy computation."""
    from viapath.perception.detection import _beam_layout
    from viapath.perception.scanner import ScannerModel, paper_scanners
    from viapath.perception.segmentation import BeamTables, segment_beams

    compiled = _numba_fit() is not None
    rng = np.random.default_rng(seed)
    scanner_sets = [
        paper_scanners(),
        (ScannerModel(name="wide", beam_count=1024, angle_increment_rad=2 * np.pi / 1024),),
        (ScannerModel(name="odd", beam_count=181, angle_increment_rad=np.deg2rad(1.0), mount_yaw_rad=0.3),),
    ]
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
                want = segment_beams(*args)
                for got in [segment_beams(*args, tables)] + (
                    [segment_beams(*args, tables, "numba")] if compiled else []
                ):
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


def _merge_duplicates_reference(centres, radii, sigma, source, distance_m):
    """``detection._merge_duplicates`` before wave 7, verbatim."""
    if len(centres) < 2 or distance_m <= 0 or source.min() == source.max():
        return centres, radii, sigma, source
    d = np.hypot(*(centres[:, None, :] - centres[None, :, :]).transpose(2, 0, 1))
    d[source[:, None] == source[None, :]] = np.inf
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


@pytest.mark.parametrize("seed", range(4))
def test_merge_duplicates_equals_reference(seed):
    from viapath.perception.detection import _merge_duplicates

    rng = np.random.default_rng(seed)
    for _ in range(200):
        n = int(rng.integers(0, 16))
        centres = rng.uniform(-1.0, 1.0, (n, 2)) * rng.choice([0.3, 1.0, 3.0])
        if n > 2:
            centres[1] = centres[0] + rng.normal(0, 0.05, 2)  # a front/rear pair of one object
        radii, sigma = rng.uniform(0.05, 0.4, n), rng.uniform(0.005, 0.1, n)
        source = rng.integers(0, 2, n)
        distance = float(rng.choice([0.0, 0.25, 0.6]))
        got = _merge_duplicates(centres, radii, sigma, source, distance)
        want = _merge_duplicates_reference(centres, radii, sigma, source, distance)
        for a, b in zip(got, want, strict=True):
            assert a.dtype == b.dtype and a.shape == b.shape and _same(a, b)
            assert a.flags.c_contiguous
