"""Segmentation, circle fits, wall rejection, leg pairing, fusion and blind sectors."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from viapath.perception.circle_fit import fit_circles
from viapath.perception.detection import DetectorParams, detect
from viapath.perception.fusion import blind_region, covered
from viapath.perception.raycast import simulate_scan
from viapath.perception.scanner import paper_scanners
from viapath.perception.segmentation import SegmentationParams, Segments, segment_beams


def fit_circle(points: np.ndarray, sensor_origin=(0.0, 0.0), **options):
    """One cluster through :func:`fit_circles`: returns ``(centre (2,), radius_m, rms_m)``."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    fits = fit_circles(
        points, np.array([0]), np.array([len(points)]), np.asarray(sensor_origin, float)[None, :], **options
    )
    return fits.centres[0], float(fits.radii_m[0]), float(fits.rms_m[0])


def segment_scan(
    ranges_m: np.ndarray, angles_rad: np.ndarray, params: SegmentationParams = SegmentationParams()
) -> Segments:
    """One sanitised scan (NaN = invalid) in its own frame through :func:`segment_beams`."""
    ranges_m = np.asarray(ranges_m, dtype=float)
    return segment_beams(ranges_m, angles_rad, 0.0, 0.0, np.zeros(len(ranges_m), dtype=int), params)


def arc(centre, radius, sensor, n, noise, rng, half_angle=np.pi / 2):
    """Points on the side of a circle facing ``sensor``, with radial noise."""
    towards = np.arctan2(sensor[1] - centre[1], sensor[0] - centre[0])
    theta = towards + np.linspace(-half_angle, half_angle, n)
    r = radius + rng.normal(0.0, noise, n)
    return np.asarray(centre) + np.stack([r * np.cos(theta), r * np.sin(theta)], -1)


@settings(max_examples=30, deadline=None, derandomize=True)
@given(x=st.floats(1.0, 4.0), y=st.floats(-2.0, 2.0), radius=st.floats(0.15, 0.35), seed=st.integers(0, 10_000))
def test_known_radius_geometric_fit_is_centimetre_accurate(x, y, radius, seed):
    rng = np.random.default_rng(seed)
    points = arc((x, y), radius, (0, 0), 25, 0.01, rng)
    centre, r, _rms = fit_circle(points, fixed_radius_m=radius)
    assert np.hypot(*(centre - (x, y))) < 0.02
    assert r == pytest.approx(radius, abs=1e-6)


def test_free_fit_and_prior_fit_beat_the_centroid_on_noisy_half_arcs():
    rng = np.random.default_rng(0)
    errors = {"free": [], "prior": [], "centroid": []}
    for _ in range(200):
        c = np.array([rng.uniform(1, 4), rng.uniform(-2, 2)])
        pts = arc(c, 0.25, (0, 0), 25, 0.02, rng)
        errors["free"].append(np.hypot(*(fit_circle(pts)[0] - c)))
        errors["prior"].append(np.hypot(*(fit_circle(pts, radius_prior_m=0.25, radius_prior_sigma_m=0.05)[0] - c)))
        errors["centroid"].append(np.hypot(*(pts.mean(0) - c)))
    rmse = {k: float(np.sqrt(np.mean(np.square(v)))) for k, v in errors.items()}
    assert rmse["centroid"] > 0.14  # the raw centroid sits ~2r/π in front of the centre
    assert rmse["free"] < 0.03 and rmse["prior"] < 0.03


def test_batched_fit_equals_one_by_one():
    rng = np.random.default_rng(3)
    arcs = [
        arc((rng.uniform(1, 3), rng.uniform(-1, 1)), r, (0, 0), n, 0.01, rng)
        for r, n in ((0.06, 8), (0.25, 30), (0.1, 12))
    ]
    points = np.concatenate(arcs)
    counts = np.array([len(a) for a in arcs])
    fits = fit_circles(points, np.cumsum(counts) - counts, counts, radius_prior_m=0.1)
    for k, a in enumerate(arcs):
        centre, radius, _ = fit_circle(a, radius_prior_m=0.1)
        np.testing.assert_allclose(fits.centres[k], centre, atol=1e-9)
        assert fits.radii_m[k] == pytest.approx(radius, abs=1e-9)


def test_breakpoint_threshold_grows_with_range():
    """Two neighbouring beams 0.352° apart, the second one ``jump`` farther: split exactly when the jump exceeds
    ``r sin Δφ / sin(λ - Δφ) + 3σ`` (Borges & Aldon), which grows with the range ``r``."""
    params = SegmentationParams()
    step = np.deg2rad(0.352)
    angles = np.array([0.0, step])
    for near in (0.5, 2.0, 4.0):
        sigma = params.noise_sigma_near_m if near < params.noise_switch_range_m else params.noise_fraction_far * near
        threshold = max(near * np.sin(step) / np.sin(params.grazing_angle_rad - step) + 3 * sigma, params.min_jump_m)
        for jump, splits in ((0.9 * threshold, False), (1.1 * threshold, True)):
            # the gap between the two points (the second beam is longer by ``jump``): close to ``jump`` itself
            ranges = np.array([near, near + jump])
            gap = np.hypot(*(ranges[1] * np.array([np.cos(step), np.sin(step)]) - [ranges[0], 0.0]))
            got = segment_beams(ranges, angles, 0.0, 0.0, np.zeros(2, dtype=int), SegmentationParams(min_points=1))
            assert (len(got) == 2) == (gap > threshold) == splits, (near, jump)
    assert threshold > 0.2  # at 4 m neighbouring beams are 2.5 cm apart; a grazing wall needs > 14 cm


def test_segmentation_splits_on_jumps_and_skips_invalid_beams():
    angles = np.deg2rad(np.arange(40) * 0.352)
    ranges = np.full(40, 3.0)
    ranges[10:20] = 2.0  # object in front of the wall
    ranges[25] = np.nan  # a single dropout does not split the wall
    segments = segment_scan(ranges, angles)
    assert [int(c) for c in segments.counts] == [10, 10, 19]
    assert segments.occluded.tolist() == [True, False, True]  # wall pieces beside the object are partly hidden


def scene_detections(centres, radii, walls=None, params=DetectorParams(), seed=0, pose=(0.0, 0.0, 0.0)):
    rng = np.random.default_rng(seed)
    scanners = paper_scanners()
    scans = [simulate_scan(s, pose, centres, radii, walls, rng) for s in scanners]
    return detect(scanners, scans, params), scanners, scans


def test_ten_obstacles_all_found_walls_rejected():
    rng = np.random.default_rng(4)
    angles = np.linspace(-np.pi, np.pi, 10, endpoint=False)
    distance = rng.uniform(1.0, 3.0, 10)
    centres = np.stack([distance * np.cos(angles), distance * np.sin(angles)], -1)
    walls = np.array([[[-5, -4.0], [5, -4.0]], [[-5, 4.0], [5, 4.0]], [[4.5, -4], [4.5, 4]]])
    detections, _, _ = scene_detections(centres, np.full(10, 0.25), walls)
    assert len(detections) == 10
    d = np.hypot(*(detections.centres[:, None, :] - centres[None, :, :]).transpose(2, 0, 1))
    assert d.min(axis=1).max() < 0.06  # each detection lands on an obstacle
    assert len(set(d.argmin(axis=1))) == 10


def test_an_empty_room_gives_no_detection():
    walls = np.array([[[-3, -2.0], [4, -2.0]], [[-3, 2.0], [4, 2.0]], [[4, -2], [4, 2]], [[-3, -2], [-3, 2]]])
    for seed in range(5):
        detections, _, _ = scene_detections(np.zeros((0, 2)), np.zeros(0), walls, seed=seed)
        assert len(detections) == 0


def test_object_seen_by_both_scanners_is_one_detection():
    # beside the robot both 240° fields overlap: an obstacle at 90° is seen by the front and the rear scanner
    detections, _scanners, _scans = scene_detections([[0.0, 1.0]], [0.25])
    assert sum(d["accepted"] for d in detections.segments) == 2
    assert len(detections) == 1
    assert np.hypot(*(detections.centres[0] - (0.0, 1.0))) < 0.05


def test_two_legs_become_one_person_two_people_stay_two():
    params = DetectorParams.for_legs()
    legs = [[2.0, 0.15], [2.1, -0.15], [2.0, -1.2], [2.05, -1.45]]
    detections, _, _ = scene_detections(legs, np.full(4, 0.06), params=params, seed=2)
    assert len(detections.legs) == 4
    assert sorted(detections.leg_count.tolist()) == [2, 2]
    persons = detections.centres[np.argsort(detections.centres[:, 1])]
    np.testing.assert_allclose(persons, [[2.025, -1.325], [2.05, 0.0]], atol=0.06)


def test_fusion_covers_360_degrees_and_keeps_the_source():
    angles = np.linspace(-np.pi, np.pi, 36, endpoint=False)
    centres = np.stack([2.5 * np.cos(angles), 2.5 * np.sin(angles)], -1)
    scanners = paper_scanners()
    scans = [simulate_scan(s, (0, 0, 0), centres, np.full(36, 0.1)) for s in scanners]
    fused = detect(scanners, scans).fused
    bearings = np.degrees(np.arctan2(fused.points_robot[:, 1], fused.points_robot[:, 0]))
    hist, _ = np.histogram(bearings, bins=36, range=(-180, 180))
    assert (hist > 0).all()
    assert set(np.unique(fused.scanner_index)) == {0, 1}
    distance = np.hypot(*fused.points_robot.T)
    assert distance.min() > 2.39 and distance.max() < 2.6  # on the discs (centres 2.5 m, r = 0.1 m)


def test_blind_region_of_the_paper_set_up_and_of_narrow_scanners():
    paper = blind_region(paper_scanners(), 0.25)
    # the unseen diamond between the scanners reaches 0.145·tan 60° = 0.251 m beside the robot
    assert paper.blind_depth_m.max() == pytest.approx(0.145 * np.tan(np.pi / 3), abs=0.002)
    assert paper.sectors_rad == []
    narrow = blind_region(paper_scanners(beam_count=513), 0.25)  # 180° each
    assert len(narrow.sectors_rad) == 2
    centres = sorted(np.degrees(np.mean(s)) for s in narrow.sectors_rad)
    assert centres == pytest.approx([-90.0, 90.0], abs=1.0)
    assert np.isinf(narrow.blind_depth_m).any()
    assert not covered(paper_scanners(beam_count=513), np.array([[0.0, 3.0]]))[0]
    assert covered(paper_scanners(), np.array([[0.0, 3.0]]))[0]


@pytest.mark.skipif(
    __import__("importlib.util").util.find_spec("numba") is None,
    reason="numba not installed (pip install 'viapath[fast]')",
)
def test_free_fit_recovers_exact_circles():
    """Points exactly on a circle (any arc of 3 to 60 points, seen from anywhere): the free fit returns that
    circle, with residual 0."""
    rng = np.random.default_rng(11)
    for _ in range(50):
        centre, radius = rng.uniform(-4, 4, 2), rng.uniform(0.04, 0.5)
        points = arc(centre, radius, rng.uniform(-1, 1, 2) + centre * 3, int(rng.integers(3, 60)), 0.0, rng)
        got, r, rms = fit_circle(points, sensor_origin=(centre * 3).tolist())
        np.testing.assert_allclose(got, centre, atol=1e-7)
        assert r == pytest.approx(radius, abs=1e-7) and rms < 1e-7


@pytest.mark.parametrize("options", [dict(), dict(radius_prior_m=0.2, radius_prior_sigma_m=0.05)])
def test_fit_minimises_its_cost(options):
    """On noisy arcs the fit is a minimum of its cost ``Σ (|p - c| - r)² + weight (r - prior)²``: no centre or
    radius 1 mm away in any of 26 directions costs less, and the reported RMS is the residuals'."""
    rng = np.random.default_rng(4)
    weight = (0.01 / options["radius_prior_sigma_m"]) ** 2 if options else 0.0
    prior = options.get("radius_prior_m", 0.0)

    def cost(points, c, r):
        return np.sum((np.hypot(*(points - c[:2]).T) - r) ** 2) + weight * (r - prior) ** 2

    steps = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1) if (i, j, k) != (0, 0, 0)])
    for _ in range(40):
        centre = np.array([rng.uniform(0.5, 4), rng.uniform(-2, 2)])
        points = arc(centre, rng.uniform(0.05, 0.3), (0, 0), int(rng.integers(8, 40)), 0.01, rng)
        c, r, rms = fit_circle(points, **options)
        assert rms == pytest.approx(np.sqrt(np.mean((np.hypot(*(points - c).T) - r) ** 2)), rel=1e-9)
        best = cost(points, c, r)
        for step in steps * 1e-3:
            assert cost(points, c + step[:2], r + step[2]) >= best - 1e-12
