"""Ray casting against independent references (marching, closed-form distances) and scanner readings."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from viapath.perception.raycast import cast_rays, simulate_scan
from viapath.perception.scanner import ScannerModel, paper_scanners, sanitize_ranges


def march(origin, angle, centres, radii, segments, step=1e-3, max_range=8.0):
    """Brute-force reference: walk along the ray in 1 mm steps until a point is inside a disc or within a wall's line."""
    d = np.array([np.cos(angle), np.sin(angle)])
    t = np.arange(0.0, max_range, step)
    pts = np.asarray(origin)[None, :] + t[:, None] * d
    hit = np.zeros(len(t), dtype=bool)
    for c, r in zip(centres, radii):
        hit |= np.hypot(*(pts - c).T) <= r
    for a, b in segments:
        # a wall is hit where consecutive march points fall on opposite sides of it, inside its span
        e = b - a
        side = np.sign((pts[:, 0] - a[0]) * e[1] - (pts[:, 1] - a[1]) * e[0])
        s = ((pts - a) @ e) / (e @ e)
        crossing = np.zeros(len(t), dtype=bool)
        crossing[1:] = (side[1:] != side[:-1]) & (s[1:] >= 0) & (s[1:] <= 1)
        hit |= crossing
    index = np.flatnonzero(hit)
    return t[index[0]] if len(index) else np.inf


def point_segment_distance(p, a, b):
    p, a, b = (np.asarray(v, dtype=float) for v in (p, a, b))
    e = b - a
    s = np.clip((p - a) @ e / (e @ e), 0.0, 1.0)
    return float(np.hypot(*(a + s * e - p)))


coordinate = st.floats(-3.0, 3.0, allow_nan=False)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    centres=st.lists(st.tuples(coordinate, coordinate), min_size=0, max_size=4),
    radii=st.lists(st.floats(0.05, 0.6), min_size=4, max_size=4),
    walls=st.lists(st.tuples(coordinate, coordinate, coordinate, coordinate), min_size=0, max_size=3),
    angle=st.floats(-np.pi, np.pi),
)
def test_ray_casting_matches_brute_force_marching(centres, radii, walls, angle):
    centres = np.array(centres, dtype=float).reshape(-1, 2)
    radii = np.array(radii[: len(centres)])
    segments = np.array(walls, dtype=float).reshape(-1, 2, 2)
    segments = segments[np.hypot(*(segments[:, 1] - segments[:, 0]).T) > 0.05]
    segments = segments[[point_segment_distance((0.0, 0.0), a, b) > 0.01 for a, b in segments]]  # scanner not on a wall
    origin = np.array([0.0, 0.0])
    inside = np.hypot(*(centres - origin).T) <= radii
    exact = cast_rays(origin, [angle], centres, radii, segments)[0]
    if inside.any():
        assert exact == 0.0
        return
    reference = march(origin, angle, centres, radii, segments)
    assert exact <= reference + 2e-3  # never misses what the march hits
    if np.isinf(exact):
        return
    d = np.array([np.cos(angle), np.sin(angle)])
    point = origin + exact * d
    surface = [abs(np.hypot(*(point - c)) - r) for c, r in zip(centres, radii)]
    surface += [point_segment_distance(point, a, b) for a, b in segments]
    assert min(surface) < 1e-6  # the hit lies on a disc or a wall
    if exact < reference - 2e-3:
        # the 1 mm march stepped over a grazing contact: tangent to a disc or at a wall's end
        tangent = [abs(abs(d[0] * (c - origin)[1] - d[1] * (c - origin)[0]) - r) < 1e-3 for c, r in zip(centres, radii)]
        at_end = [min(np.hypot(*(point - a)), np.hypot(*(point - b))) < 2e-3 for a, b in segments]
        assert any(tangent) or any(at_end)


def test_disc_straight_ahead_and_wall_behind_it():
    ranges = cast_rays(
        (0.0, 0.0),
        [0.0, np.pi / 2, np.pi],
        [[2.0, 0.0]],
        [0.25],
        [[[5.0, -1.0], [5.0, 1.0]], [[-1.0, -1.0], [-1.0, 1.0]]],
    )
    assert ranges[0] == pytest.approx(1.75)  # the disc occludes the wall at x = 5
    assert np.isinf(ranges[1])
    assert ranges[2] == pytest.approx(1.0)


def test_absent_obstacles_nan_rows_are_ignored():
    ranges = cast_rays((0.0, 0.0), [0.0], [[np.nan, np.nan], [3.0, 0.0]], [0.25, 0.25])
    assert ranges[0] == pytest.approx(2.75)


def test_scanner_mount_pose_front_and_rear():
    front, rear = paper_scanners()
    assert front.beam_count == 683 and np.degrees(front.field_of_view_rad) == pytest.approx(240.0, abs=0.5)
    # obstacle 2 m ahead of the robot centre, robot at (1, 1) heading +y
    robot = (1.0, 1.0, np.pi / 2)
    centre = [[1.0, 3.0]]
    front_ranges = simulate_scan(front, robot, centre, [0.25])
    middle = front.beam_count // 2
    assert front_ranges[middle] == pytest.approx(2.0 - 0.145 - 0.25, abs=1e-9)
    rear_ranges = simulate_scan(rear, robot, [[1.0, -1.0]], [0.25])  # 2 m behind
    assert rear_ranges[middle] == pytest.approx(2.0 - 0.145 - 0.25, abs=1e-9)
    # the robot's own body is never seen: an empty world gives only invalid readings
    assert np.isinf(simulate_scan(front, robot, np.zeros((0, 2)), np.zeros(0))).all()


@pytest.mark.parametrize("encoding, check", [("inf", np.isposinf), ("nan", np.isnan), ("zero", lambda r: r == 0.0)])
def test_invalid_readings_encoded_like_drivers_and_sanitised(encoding, check):
    scanner = ScannerModel(invalid_encoding=encoding)
    readings = simulate_scan(scanner, (0, 0, 0), [[1.0, 0.0]], [0.2], rng=np.random.default_rng(0))
    miss = np.ones(scanner.beam_count, dtype=bool)
    miss[np.isfinite(cast_rays(scanner.world_pose((0, 0, 0))[:2], scanner.beam_angles_rad(), [[1.0, 0.0]], [0.2]))] = (
        False
    )
    assert check(readings[miss]).all()
    assert np.isfinite(readings[~miss]).all() and (readings[~miss] > 0).all()
    clean = sanitize_ranges(readings, scanner.range_min_m, scanner.range_max_m)
    assert np.isnan(clean[miss]).all() and np.isfinite(clean[~miss]).all()


def test_sanitize_accepts_every_driver_convention():
    raw = [0.0, np.nan, np.inf, -np.inf, 0.01, 1.5, 30.0, -1.0]
    clean = sanitize_ranges(raw, range_min_m=0.02, range_max_m=5.6)
    assert np.isnan(clean[[0, 1, 2, 3, 4, 6, 7]]).all()
    assert clean[5] == 1.5


def test_range_noise_follows_the_datasheet():
    scanner = ScannerModel()
    rng = np.random.default_rng(1)
    near = scanner.measure(np.full(20000, 0.5), rng) - 0.5
    far = scanner.measure(np.full(20000, 3.0), rng) - 3.0
    assert np.std(near) == pytest.approx(0.010, rel=0.05)
    assert np.std(far) == pytest.approx(0.030, rel=0.05)
    assert not np.isfinite(scanner.measure(np.array([6.0, 0.01]))).any()


def test_scanner_rejects_bad_configuration():
    with pytest.raises(ValueError, match="range_min_m"):
        ScannerModel(range_min_m=5.0, range_max_m=4.0)
    with pytest.raises(ValueError, match="invalid_encoding"):
        ScannerModel(invalid_encoding="minus-one")
    with pytest.raises(ValueError, match="finite"):
        ScannerModel(mount_x_m=float("nan"))


def test_rays_aimed_at_disc_centres_and_across_walls_stop_at_the_closed_form_distance():
    """A ray aimed at a disc's centre stops at |c - o| - r; one crossing a wall at right angles at the wall's
    distance; with both, at the nearer; a ray aimed away meets neither."""
    rng = np.random.default_rng(5)
    for _ in range(200):
        origin = rng.uniform(-2, 2, 2)
        centre = rng.uniform(-6, 6, 2)
        radius = rng.uniform(0.05, 0.5)
        if np.hypot(*(centre - origin)) <= radius + 1e-3:
            continue
        bearing = np.arctan2(*(centre - origin)[::-1])
        to_disc = np.hypot(*(centre - origin)) - radius
        wall_distance = rng.uniform(0.1, 8.0)
        along = np.array([np.cos(bearing), np.sin(bearing)])
        across = np.array([-along[1], along[0]])
        foot = origin + wall_distance * along
        wall = np.array([[foot - across, foot + across]])
        assert cast_rays(origin, [bearing], [centre], [radius])[0] == pytest.approx(to_disc, abs=1e-9)
        assert cast_rays(origin, [bearing], np.zeros((0, 2)), [], wall)[0] == pytest.approx(wall_distance, abs=1e-9)
        both = cast_rays(origin, [bearing], [centre], [radius], wall)[0]
        assert both == pytest.approx(min(to_disc, wall_distance), abs=1e-9)
        assert np.isinf(cast_rays(origin, [bearing + np.pi], [centre], [radius])[0])
