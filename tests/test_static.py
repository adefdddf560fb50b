"""Static geometry (viapath.static): sampling into discs, distances and shapes, checked by brute force."""

from __future__ import annotations

import numpy as np

from viapath.static import (
    StaticLayer,
    box_edges,
    merge_close_shapes,
    point_segment_distances,
    polygon_edges,
    sample_discs,
    segment_distances,
)


def _dense_points(segments: np.ndarray, per_segment: int = 400) -> np.ndarray:
    f = np.linspace(0.0, 1.0, per_segment)[None, :, None]
    return (segments[:, None, 0] + f * (segments[:, None, 1] - segments[:, None, 0])).reshape(-1, 2)


def test_discs_cover_the_capsule_of_every_segment():
    """Any point within R (>= the robot radius used for the pad) of a segment is within R + pad of some disc
    centre: checked on random points near random segments, by brute force."""
    rng = np.random.default_rng(0)
    for _ in range(50):
        segments = rng.uniform(-3, 3, (int(rng.integers(1, 6)), 2, 2))
        points_only = rng.uniform(size=len(segments)) < 0.2
        segments[points_only, 1] = segments[points_only, 0]
        robot_radius = rng.uniform(0.1, 0.4)
        spacing = rng.uniform(0.05, 0.3)
        centres, radii, ids = sample_discs(segments, np.arange(len(segments)), robot_radius, spacing)
        assert len(centres) == len(radii) == len(ids)
        big_r = robot_radius + rng.uniform(0.0, 0.2)
        points = rng.uniform(-3.5, 3.5, (4000, 2))
        near = point_segment_distances(points, segments).min(axis=1) <= big_r
        covered = (np.hypot(*(points[:, None] - centres[None]).transpose(2, 0, 1)) <= big_r + radii[None]).any(axis=1)
        assert np.all(covered[near])
        # ... and no disc reaches further than R + pad from its segment: the sampling is not a fattening.
        assert np.all(point_segment_distances(centres, segments).min(axis=1) <= 1e-9)
        assert radii.max() <= np.sqrt(robot_radius**2 + (spacing / 2) ** 2) - robot_radius + 1e-12


def test_shared_polyline_ends_are_sampled_once():
    line = np.c_[np.linspace(0, 3, 11), np.zeros(11)]
    segments = np.stack([line[:-1], line[1:]], axis=1)
    centres, _, _ = sample_discs(segments, np.zeros(10, dtype=np.int64), 0.25, 0.3)
    assert len(centres) == len(np.unique(np.round(centres, 9), axis=0)) == 11


def test_segment_distances_against_dense_sampling():
    rng = np.random.default_rng(1)
    starts, ends = rng.uniform(-2, 2, (60, 2)), rng.uniform(-2, 2, (60, 2))
    ends[:10] = starts[:10]  # moves of length 0
    segments = rng.uniform(-2, 2, (7, 2, 2))
    segments[0, 1] = segments[0, 0]  # a point
    exact = segment_distances(starts, ends, segments)
    for p in range(len(starts)):
        moving = _dense_points(np.array([[starts[p], ends[p]]]), 2000)
        brute = point_segment_distances(moving, segments).min(axis=0)
        assert np.all(exact[p] <= brute + 1e-12)
        assert np.all(brute - exact[p] <= 4.0 / 2000 + 1e-9)  # the dense sampling's own step


def test_box_and_polygon_outlines():
    edges = box_edges([1.0, 2.0], [0.6, 0.4], np.pi / 2)
    corners = edges[:, 0]
    assert np.allclose(np.sort(corners[:, 0]), [0.8, 0.8, 1.2, 1.2])
    assert np.allclose(np.sort(corners[:, 1]), [1.7, 1.7, 2.3, 2.3])
    assert np.allclose(edges[:, 1], np.roll(corners, -1, axis=0))  # closed
    assert polygon_edges([[0, 0], [1, 0], [0, 1]]).shape == (3, 2, 2)


def test_close_shapes_merge_and_far_ones_do_not():
    a = box_edges([0, 0], [0.4, 0.4])
    b = box_edges([0.8, 0], [0.4, 0.4])  # 0.4 m from a
    c = box_edges([5, 5], [0.4, 0.4])
    layer = StaticLayer.of_shapes([a, b, c])
    merged = merge_close_shapes(layer, 0.5)
    assert len(np.unique(merged.shape_ids[:8])) == 1
    assert merged.shape_ids[8] != merged.shape_ids[0]
    assert len(np.unique(merge_close_shapes(layer, 0.3).shape_ids)) == 3


def test_layer_radii_widen_the_discs():
    layer = StaticLayer(np.array([[[0.0, 0.0], [1.0, 0.0]]]), radii_m=[0.05])
    _, radii, _ = layer.discs(0.25, 0.1)
    plain = StaticLayer(np.array([[[0.0, 0.0], [1.0, 0.0]]])).discs(0.25, 0.1)[1]
    assert np.allclose(radii, plain + 0.05)


def test_finite_drops_non_finite_segments_once_and_is_kept():
    """The finite part of a layer is made once: asking again (each cycle, for a map) gives the same layer."""
    segments = np.array([[[0.0, 0.0], [1.0, 0.0]], [[np.nan, 0.0], [1.0, 1.0]], [[2.0, 2.0], [3.0, np.inf]]])
    layer = StaticLayer(segments, np.array([0, 1, 2]))
    finite = layer.finite()
    assert np.array_equal(finite.segments, segments[:1]) and finite.shape_ids.tolist() == [0]
    assert layer.finite() is finite and finite.finite() is finite
    clean = StaticLayer(segments[:1], np.array([7]))
    assert clean.finite() is clean and clean.finite() is clean
