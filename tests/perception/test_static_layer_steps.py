"""The static layer's compiled steps against their specifications, on seeded random input.

* The thinning (:func:`~viapath.perception.static_layer.thin_runs`) against its numpy statement kept here
  (:func:`_thin_runs_spec`), bit for bit: the same segments, runs and radii.
* The marking: a return is static unless it lies within a track's radius + margin (brute force over every
  return and track), and a beam is marked tentative when only tentative tracks explain its return.
* The merging of shapes (:func:`viapath.static.merge_close_shapes`) against the connected components of the
  overlap graph of the shapes' grown bounding boxes, found by a breadth-first search.
"""

from __future__ import annotations

import numpy as np
import pytest

from viapath.perception.scanner import ScannerModel
from viapath.perception.static_layer import StaticLayerParams, StaticObstacleLayer, thin_runs
from viapath.static import StaticLayer, merge_close_shapes


def _thin_runs_spec(points, run, step_m):
    """The thinning in numpy: each run's first and last return and those where its length passes a multiple of
    ``step_m``; segments between consecutive kept returns of a run (a run of one return: a point); each
    segment's radius the largest distance of the returns it stands for."""
    count = len(points)
    first = np.flatnonzero(np.diff(run, prepend=-1) != 0)
    last = np.append(first[1:], count) - 1
    step = np.zeros(count)
    step[1:] = np.hypot(*np.diff(points, axis=0).T)
    step[first] = 0.0
    along = np.cumsum(step)
    along -= np.repeat(along[first], np.diff(np.append(first, count)))
    bucket = np.floor(along / step_m).astype(np.int64)
    keep = np.zeros(count, dtype=bool)
    keep[first] = keep[last] = True
    keep[1:] |= (bucket[1:] != bucket[:-1]) & (run[1:] == run[:-1])
    kept = np.flatnonzero(keep)
    joined = run[kept[1:]] == run[kept[:-1]]
    single = first[first == last]
    segment_starts = np.concatenate([kept[:-1][joined], single])
    segment_ends = np.concatenate([kept[1:][joined], single])
    order = np.argsort(segment_starts, kind="stable")
    segment_starts, segment_ends = segment_starts[order], segment_ends[order]
    segments = np.stack([points[segment_starts], points[segment_ends]], axis=1)
    owner = np.searchsorted(segment_starts, np.arange(count), side="right") - 1
    at_end = np.isin(np.arange(count), last) & ~np.isin(np.arange(count), single)
    owner[at_end] = np.searchsorted(segment_ends, np.arange(count)[at_end], side="left")
    a, b = segments[owner, 0], segments[owner, 1]
    d = b - a
    length2 = np.einsum("ij,ij->i", d, d)
    t = np.clip(np.einsum("ij,ij->i", points - a, d) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
    deviation = np.hypot(*(points - a - t[:, None] * d).T)
    radii = np.zeros(len(segments))
    np.maximum.at(radii, owner, deviation)
    return segments, run[segment_starts], radii


@pytest.mark.parametrize("seed", range(8))
def test_thinning_is_its_numpy_statement_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    for _ in range(30):
        count = int(rng.integers(1, 400))
        # a random walk of returns (walls, clutter), cut into runs of 1 to 80 returns
        points = np.cumsum(rng.normal(0, rng.choice([0.01, 0.05, 0.2]), (count, 2)), axis=0)
        run = np.cumsum(rng.random(count) < rng.choice([0.02, 0.1, 0.5]))
        step_m = float(rng.choice([0.05, 0.15, 0.4]))
        got = thin_runs(points, run, step_m)
        want = _thin_runs_spec(points, run, step_m)
        for g, w in zip(got, want, strict=True):
            assert g.dtype == w.dtype and g.shape == w.shape and g.tobytes() == w.tobytes()


def test_returns_that_tracks_explain_are_not_static_and_tentative_ones_are_marked():
    """Brute force: a return is a person's when within a track's radius + margin of its centre; every other
    valid return lies within its segment's radius of the layer; a beam is marked tentative exactly when the
    tracks that explain its return are all tentative."""
    rng = np.random.default_rng(3)
    scanner = ScannerModel(name="ring", beam_count=720, angle_increment_rad=2 * np.pi / 720, mount_x_m=0.0)
    params = StaticLayerParams()
    checked = 0
    for _ in range(20):
        ranges = np.repeat(rng.uniform(0.5, 4.0, 72), 10) + rng.normal(0, 0.01, 720)
        ranges[rng.random(720) < 0.05] = np.inf
        angles = scanner.beam_angles_rad()
        points = np.stack([ranges * np.cos(angles), ranges * np.sin(angles)], 1)
        finite = np.flatnonzero(np.isfinite(ranges))
        tracks = points[rng.choice(finite, 4, replace=False)] + rng.normal(0, 0.1, (4, 2))
        radii = rng.uniform(0.1, 0.3, 4)
        confirmed = rng.random(4) < 0.5
        layer = StaticObstacleLayer((scanner,), params)
        static = layer.update(0.0, np.zeros(3), [ranges], tracks, radii, confirmed)
        current, tentative = layer._from_scans((scanner,), np.zeros(3), [ranges], tracks, radii, confirmed)
        near = np.hypot(*(points[:, None] - tracks[None]).transpose(2, 0, 1)) <= radii + params.explained_margin_m
        near[~np.isfinite(ranges)] = False
        explained = near.any(1)
        expected_tentative = explained & ~(near & confirmed).any(1)
        assert np.array_equal(tentative[0], expected_tentative)
        free = finite[~explained[finite]]
        a, b = current.segments[:, 0], current.segments[:, 1]
        d = b - a
        for i in free:
            t = np.clip(((points[i] - a) * d).sum(1) / np.maximum((d * d).sum(1), 1e-300), 0, 1)
            distance = np.hypot(*(points[i] - a - t[:, None] * d).T)
            assert (distance <= current.padding_m + 1e-9).any(), i
            checked += 1
        assert len(static) >= len(current)
    assert checked > 1000


def _components_spec(layer: StaticLayer, gap_m: float) -> np.ndarray:
    """Per segment, the smallest id of the shapes linked to its shape through overlapping boxes (each shape's
    bounding box grown by its largest radius and half the gap), by breadth-first search."""
    ids = np.unique(layer.shape_ids)
    boxes = []
    for shape in ids:
        rows = layer.shape_ids == shape
        corners = layer.segments[rows].reshape(-1, 2)
        grow = layer.padding_m[rows].max() + gap_m / 2
        boxes.append((corners.min(0) - grow, corners.max(0) + grow))
    root = {}
    for start in range(len(ids)):
        if start in root:
            continue
        group, frontier = {start}, [start]
        while frontier:
            k = frontier.pop()
            for j in range(len(ids)):
                if j not in group and (boxes[k][0] <= boxes[j][1]).all() and (boxes[j][0] <= boxes[k][1]).all():
                    group.add(j)
                    frontier.append(j)
        for k in group:
            root[k] = min(group)
    return np.array([ids[root[int(np.searchsorted(ids, s))]] for s in layer.shape_ids], dtype=np.int64)


@pytest.mark.parametrize("seed", range(6))
def test_merging_joins_the_connected_shapes_and_no_others(seed):
    rng = np.random.default_rng(seed)
    for _ in range(20):
        count = int(rng.integers(1, 60))
        starts = rng.uniform(-5, 5, (count, 2))
        segments = np.stack([starts, starts + rng.normal(0, 0.3, (count, 2))], axis=1)
        shape_ids = rng.integers(0, max(1, count // 2), count) * 3 + 7
        layer = StaticLayer(segments, shape_ids, rng.uniform(0, 0.1, count))
        gap = float(rng.choice([0.0, 0.3, 0.6]))
        merged = merge_close_shapes(layer, gap)
        assert np.array_equal(merged.shape_ids, _components_spec(layer, gap))
        assert np.array_equal(merged.segments, layer.segments)  # merging changes the ids only
