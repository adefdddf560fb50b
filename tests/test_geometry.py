"""geometry.py against brute force: direction scans, dense time sampling, exact surface conditions.

Nothing here compares with a number printed by our own code: every expected value comes from a
definition (tangent line at distance R, via point on cone and cylinder, first sampled contact).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, example, given
from hypothesis import strategies as st

from tests._core_helpers import core_settings
from viapath.geometry import (
    LEFT,
    RIGHT,
    closest_approach,
    cross2,
    first_contact_time,
    legs_first_contact,
    rotate,
    tangent_vectors,
    via_times,
    wrap_angle,
)

N_TIME_SAMPLES = 20001

coord = st.floats(-5.0, 5.0, allow_nan=False, allow_infinity=False)
point = st.tuples(coord, coord).map(np.array)
radius = st.floats(0.05, 1.5)
velocity_component = st.floats(-1.0, 1.0, allow_nan=False)
velocity = st.tuples(velocity_component, velocity_component).map(np.array)
side = st.sampled_from([LEFT, RIGHT])


# --------------------------------------------------------------------------- small helpers


@core_settings
@given(st.floats(-1e4, 1e4, allow_nan=False))
def test_wrap_angle_range_and_equivalence(angle):
    wrapped = float(wrap_angle(angle))
    assert -np.pi < wrapped <= np.pi
    turns = (angle - wrapped) / (2 * np.pi)
    assert abs(turns - round(turns)) < 1e-9 * max(1.0, abs(angle))
    # Same direction as the input.
    assert np.hypot(np.cos(wrapped) - np.cos(angle), np.sin(wrapped) - np.sin(angle)) < 1e-9


def test_wrap_angle_boundaries_and_arrays():
    values = np.array([np.pi, -np.pi, 3 * np.pi, -3 * np.pi, 0.0, 2 * np.pi])
    wrapped = wrap_angle(values)
    assert wrapped.shape == values.shape
    assert np.all(wrapped > -np.pi) and np.all(wrapped <= np.pi)
    np.testing.assert_allclose(wrapped[:4], np.pi)  # -pi is excluded: the range is (-pi, pi]
    np.testing.assert_allclose(wrapped[4:], 0.0, atol=1e-12)


@core_settings
@given(point, point, st.floats(-10, 10))
def test_rotate_preserves_length_and_turns_by_angle(a, b, angle):
    r = rotate(a, angle)
    assert np.hypot(*r) == pytest.approx(np.hypot(*a), abs=1e-9)
    # cross(a, Rot(θ) a) = |a|² sin θ and a·Rot(θ)a = |a|² cos θ: a counter-clockwise turn by θ.
    assert float(cross2(a, r)) == pytest.approx(np.dot(a, a) * np.sin(angle), abs=1e-9)
    assert float(np.dot(a, r)) == pytest.approx(np.dot(a, a) * np.cos(angle), abs=1e-9)
    # cross2 is the z component: antisymmetric, zero for parallel vectors.
    assert float(cross2(a, b)) == pytest.approx(-float(cross2(b, a)), abs=1e-12)
    assert float(cross2(a, 2.5 * a)) == pytest.approx(0.0, abs=1e-9)


# --------------------------------------------------------------------------- tangents


def _scan_tangent_directions(origin, centre, radius_m, n=100001):
    """Extreme directions (CCW, CW) of rays from origin that hit the disc, by scanning all directions."""
    d = centre - origin
    base = np.arctan2(d[1], d[0])
    phi = np.linspace(-np.pi, np.pi, n)
    u = np.stack([np.cos(base + phi), np.sin(base + phi)], axis=-1)
    # The ray hits the disc when the centre is ahead and within R of the ray's line.
    perpendicular = np.abs(u[:, 0] * d[1] - u[:, 1] * d[0])
    ahead = u @ d > 0
    hit = ahead & (perpendicular <= radius_m)
    assert hit.any()
    return base + phi[hit].max(), base + phi[hit].min(), phi[1] - phi[0]


@core_settings
@given(point, point, radius, side)
def test_tangent_vectors_are_tangent_and_match_direction_scan(origin, centre, radius_m, which):
    distance = np.hypot(*(centre - origin))
    assume(distance > radius_m * 1.01)
    w, valid = tangent_vectors(origin, centre, np.float64(radius_m), which)
    assert bool(valid)
    touch = origin + w
    # The tangent point is on the circle, and the line origin->touch is perpendicular to the radius there.
    assert np.hypot(*(touch - centre)) == pytest.approx(radius_m, abs=1e-9)
    assert float(np.dot(w, touch - centre)) == pytest.approx(0.0, abs=1e-9)
    # Perpendicular distance from the centre to the tangent line equals the radius.
    direction = w / np.hypot(*w)
    assert abs(float(cross2(direction, centre - origin))) == pytest.approx(radius_m, abs=1e-9)
    # The direction is the extreme of the rays that hit the disc: CCW extreme for LEFT, CW for RIGHT.
    ccw, cw, step = _scan_tangent_directions(origin, centre, radius_m)
    expected = ccw if which == LEFT else cw
    assert abs(float(wrap_angle(np.arctan2(w[1], w[0]) - expected))) <= 2 * step


@core_settings
@given(point, point, radius, st.floats(0.0, 0.3), st.lists(st.floats(0.0, 10.0), min_size=1, max_size=5))
def test_tangent_vectors_to_growing_circle_broadcast(origin, centre, radius_m, growth, times):
    """The planner calls tangent_vectors with a radius R + g t per row and both sides at once."""
    radii = radius_m + growth * np.asarray(times)
    origins = np.repeat(origin[None], len(radii), 0)
    centres = np.repeat(centre[None], len(radii), 0)
    w, valid = tangent_vectors(origins[:, None, :], centres[:, None, :], radii[:, None], np.array([LEFT, RIGHT])[None])
    assert w.shape == (len(radii), 2, 2)
    valid = np.broadcast_to(valid, (len(radii), 2))  # validity does not depend on the side
    distance = np.hypot(*(centre - origin))
    for k, r in enumerate(radii):
        assert bool(valid[k, 0]) == bool(valid[k, 1]) == (distance > r)
        if distance > r * 1.01:
            for j in range(2):
                assert np.hypot(*(origin + w[k, j] - centre)) == pytest.approx(r, abs=1e-9)
                assert float(np.dot(w[k, j], origin + w[k, j] - centre)) == pytest.approx(0.0, abs=1e-9)
            # Left and right tangents are mirror images about the centre line.
            assert float(cross2(centre - origin, w[k, 0])) >= -1e-12
            assert float(cross2(centre - origin, w[k, 1])) <= 1e-12


def test_tangent_vectors_invalid_inside_disc():
    origin = np.array([0.0, 0.0])
    w, valid = tangent_vectors(origin, np.array([0.3, 0.0]), np.float64(0.5), LEFT)
    assert not bool(valid)
    assert np.all(np.isfinite(w))  # no NaN leaks out to the planner


# --------------------------------------------------------------------------- via points

ROOT_CASES = {
    # name: robot position, obstacle centre, obstacle velocity, robot speed, combined radius
    "robot_faster_head_on": ([0, 0], [2, 0], [-0.3, 0], 0.5, 0.5),
    "obstacle_standing": ([0, 0], [2, 0.3], [0, 0], 0.2, 0.5),
    "obstacle_faster_from_behind_two_roots": ([0, 0], [-1.5, 0.0], [0.6, 0], 0.3, 0.5),
    "obstacle_faster_crossing_two_roots": ([0, 0], [2.0, -2.0], [0.0, 0.8], 0.5, 0.4),
    "obstacle_faster_running_away_no_root": ([0, 0], [2, 0], [0.9, 0], 0.2, 0.5),
    "equal_speeds_approaching": ([0, 0], [3, 0.5], [-0.3, 0], 0.3, 0.5),
    "equal_speeds_receding": ([0, 0], [3, 0.5], [0.3, 0], 0.3, 0.5),
}


def _check_via_roots(origin, centre, obstacle_velocity, speed, radius_m, which):
    """Check both roots of one (side) against the definitions and a dense time scan; return them."""
    w, valid = tangent_vectors(origin, centre, np.float64(radius_m), which)
    assert bool(valid)
    t_early, t_late = (float(t) for t in via_times(w, obstacle_velocity, speed))
    roots = [t for t in (t_early, t_late) if np.isfinite(t)]
    for t in roots:
        assert t > 0
        via = origin + w + obstacle_velocity * t
        # On the robot's reachable cone: |via - p| = v t ...
        assert np.hypot(*(via - origin)) == pytest.approx(speed * t, rel=1e-9, abs=1e-9)
        # ... and on the obstacle's cylinder surface: |via - c(t)| = R.
        assert np.hypot(*(via - centre - obstacle_velocity * t)) == pytest.approx(radius_m, abs=1e-9)
        # The robot velocity to the via point has the candidate speed.
        assert np.hypot(*(obstacle_velocity + w / t)) == pytest.approx(speed, rel=1e-9)
    if len(roots) == 2:
        assert t_early <= t_late
    if np.isfinite(t_late):
        assert np.isfinite(t_early)

    # Dense scan of f(t) = |w + v_obs t| - v t: the roots are its sign changes.
    horizon = 1.37 * max(roots) + 1.0 if roots else 1e4
    grid = np.linspace(0.0, horizon, N_TIME_SAMPLES)
    f = np.hypot(*(w[None] + obstacle_velocity[None] * grid[:, None]).T) - speed * grid
    changes = set(np.flatnonzero(np.diff(np.sign(f)) != 0).tolist())
    brackets = [int(np.searchsorted(grid, t)) - 1 for t in roots]
    expected = {b for b in brackets if brackets.count(b) % 2 == 1}
    if len(roots) == 1 and speed < np.hypot(*obstacle_velocity):
        # A faster obstacle gives two crossings or none; a single one is a double root: the
        # avoiding line only touches the cone, f touches zero without changing sign.
        expected = set()
        assert f.min() > -1e-9
    assert changes == expected, (changes, expected, roots)
    if not roots:
        # No crossing at all, ever: robot can't be faster than the obstacle then.
        assert speed <= np.hypot(*obstacle_velocity) + 1e-12
        assert f.min() > -1e-9
    if speed > np.hypot(*obstacle_velocity):
        assert len(roots) == 1  # faster robot: exactly one crossing per side
    return t_early, t_late


@pytest.mark.parametrize("name", list(ROOT_CASES))
@pytest.mark.parametrize("which", [LEFT, RIGHT])
def test_via_points_root_cases(name, which):
    origin, centre, obstacle_velocity, speed, radius_m = (np.asarray(x, dtype=float) for x in ROOT_CASES[name])
    t_early, t_late = _check_via_roots(origin, centre, obstacle_velocity, float(speed), float(radius_m), which)
    n_roots = int(np.isfinite(t_early)) + int(np.isfinite(t_late))
    expected_roots = {
        "robot_faster_head_on": 1,
        "obstacle_standing": 1,
        "obstacle_faster_from_behind_two_roots": 2,
        # Right tangent: pass behind it early or let it go by; left (ahead of it, on its far side): none.
        "obstacle_faster_crossing_two_roots": 2 if which == RIGHT else 0,
        "obstacle_faster_running_away_no_root": 0,
        "equal_speeds_approaching": 1,
        "equal_speeds_receding": 0,
    }[name]
    assert n_roots == expected_roots


def test_via_point_standing_obstacle_is_the_tangent_point():
    origin, centre = np.array([0.0, 0.0]), np.array([2.0, 0.3])
    w, _ = tangent_vectors(origin, centre, np.float64(0.5), LEFT)
    t_early, t_late = via_times(w, np.zeros(2), 0.25)
    assert float(t_early) == pytest.approx(np.hypot(*w) / 0.25, rel=1e-12)
    assert np.isinf(t_late)


@core_settings
@given(point, point, velocity, st.floats(0.05, 1.0), radius, side)
def test_via_points_random(origin, centre, obstacle_velocity, speed, radius_m, which):
    assume(np.hypot(*(centre - origin)) > radius_m * 1.01)
    w, _ = tangent_vectors(origin, centre, np.float64(radius_m), which)
    t_early, t_late = via_times(w, obstacle_velocity, speed)
    # Keep to well-conditioned cases: a root beyond 1e3 s is a near-parallel graze, irrelevant to planning.
    assume(all(not np.isfinite(t) or t < 1e3 for t in (float(t_early), float(t_late))))
    # Avoid near-double roots, which the sampled scan cannot resolve.
    assume(not (np.isfinite(t_late) and float(t_late - t_early) < 1e-3 * float(t_late)))
    _check_via_roots(origin, centre, obstacle_velocity, speed, radius_m, which)


def test_via_times_vectorised_matches_scalar():
    rng = np.random.default_rng(3)
    w = rng.uniform(-3, 3, (50, 2))
    v_obs = rng.uniform(-1, 1, (50, 2))
    speeds = rng.uniform(0.05, 1.0, 50)
    t_early, t_late = via_times(w, v_obs, speeds)
    for k in range(50):
        early, late = via_times(w[k], v_obs[k], speeds[k])
        assert float(early) == t_early[k] and float(late) == t_late[k]


# --------------------------------------------------------------------------- moving-disc contact


def _brute_distance_margin(rel_position, rel_velocity, radius_m, growth, tau):
    moved = rel_position[None] + rel_velocity[None] * tau[:, None]
    return np.hypot(*moved.T) - (radius_m + growth * tau)


def _check_first_contact(tau_code, rel_position, rel_velocity, radius_m, growth, duration):
    """First-contact time vs. 20000-sample scan: it is a real contact, nothing earlier, nothing missed."""
    tau = np.linspace(0.0, duration, N_TIME_SAMPLES)
    margin = _brute_distance_margin(rel_position, rel_velocity, radius_m, growth, tau)
    hits = np.flatnonzero(margin < -1e-9)
    if len(hits):
        # A sampled contact: the code must report one no later than that sample.
        assert np.isfinite(tau_code), "contact missed"
        assert tau_code <= tau[hits[0]] + 1e-9
    if np.isfinite(tau_code):
        assert 0.0 <= tau_code <= duration * (1 + 1e-12)
        at = _brute_distance_margin(rel_position, rel_velocity, radius_m, growth, np.array([tau_code]))[0]
        if tau_code == 0.0:
            assert at <= 1e-9  # already touching
        else:
            assert abs(at) <= 1e-7 * (1 + np.hypot(*rel_velocity) * tau_code)  # on the surface
        # No sampled contact before it.
        assert np.all(margin[tau < tau_code - 1e-9] > -1e-9)
    else:
        assert margin.min() > -1e-9
    return tau[hits[0]] if len(hits) else np.inf


def _aim(rel_position, rel_velocity, aimed, miss):
    """Half the examples head for a point near the obstacle (contacts and near misses), half at random."""
    if not aimed:
        return rel_velocity
    target = np.asarray(miss) - rel_position
    norm = np.hypot(*target)
    return rel_velocity if norm == 0 else target / norm * max(np.hypot(*rel_velocity), 0.05)


miss = st.tuples(st.floats(-1.5, 1.5), st.floats(-1.5, 1.5))


@core_settings
@given(point, velocity, radius, st.floats(0.1, 30.0), st.booleans(), miss)
def test_first_contact_time_matches_sampling(rel_position, rel_velocity, radius_m, duration, aimed, miss_point):
    rel_velocity = _aim(rel_position, rel_velocity, aimed, miss_point)
    tau_code = float(first_contact_time(rel_position, rel_velocity, radius_m, duration))
    _check_first_contact(tau_code, rel_position, rel_velocity, radius_m, 0.0, duration)


@core_settings
@given(point, velocity, radius, st.floats(0.0, 0.6), st.floats(0.1, 30.0), st.booleans(), miss)
# a subnormal growth round touching discs: the root's denominator is a few subnormals (c / it overflows)
@example(np.zeros(2), np.zeros(2), 1.0, 2.2250738585e-313, 1.0, False, (0.0, 0.0))
@example(np.array([3.0, 0.0]), np.zeros(2), 1.0, 2.2250738585e-313, 1.0, False, (0.0, 0.0))
def test_first_contact_time_growing_radius_matches_sampling(
    rel_position, rel_velocity, radius_m, growth, duration, aimed, miss_point
):
    rel_velocity = _aim(rel_position, rel_velocity, aimed, miss_point)
    tau_code = float(first_contact_time(rel_position, rel_velocity, radius_m, duration, growth=growth))
    _check_first_contact(tau_code, rel_position, rel_velocity, radius_m, growth, duration)


CONTACT_CASES = {
    # name: rel position, rel velocity, radius, growth, duration, contact expected by construction
    "head_on": ([3, 0], [-1, 0], 0.5, 0.0, 10, True),
    "receding": ([3, 0], [1, 0], 0.5, 0.0, 10, False),
    "already_overlapping": ([0.2, 0.1], [1, 0], 0.5, 0.0, 10, True),
    "exactly_touching": ([0.5, 0.0], [0, 1], 0.5, 0.0, 10, True),
    "still_apart": ([2, 0], [0, 0], 0.5, 0.0, 10, False),
    "near_miss": ([3, 0.6], [-1, 0], 0.5, 0.0, 10, False),
    "too_late": ([30, 0], [-1, 0], 0.5, 0.0, 10, False),
    "cone_swallows_standing_robot": ([2, 0], [0, 0], 0.5, 0.2, 10, True),
    "cone_grows_as_fast_as_it_recedes": ([0, 2], [0.3, 0], 0.5, 0.3, 20, True),  # a = 0: linear
    "cone_faster_than_relative_motion": ([3, 1], [0.1, 0.2], 0.3, 0.5, 10, True),  # a < 0
    "cone_too_slow": ([3, 1], [1, 0], 0.3, 0.1, 10, False),
    "growth_but_overlapping": ([0.1, 0], [0, 0], 0.5, 0.2, 10, True),
}


@pytest.mark.parametrize("name", list(CONTACT_CASES))
def test_first_contact_named_cases(name):
    p, v, r, g, duration, expect_contact = CONTACT_CASES[name]
    p, v = np.asarray(p, dtype=float), np.asarray(v, dtype=float)
    tau_code = float(first_contact_time(p, v, r, duration, growth=g))
    _check_first_contact(tau_code, p, v, r, g, duration)
    assert np.isfinite(tau_code) == expect_contact
    if np.hypot(*p) <= r:
        assert tau_code == 0.0


@core_settings
@given(
    st.integers(1, 4),
    st.integers(1, 4),
    st.floats(0.0, 0.4),
    st.booleans(),
    st.randoms(use_true_random=False),
)
def test_legs_first_contact_matches_sampling(n_legs, n_obstacles, growth_scale, per_obstacle_growth, rnd):
    rng = np.random.default_rng(rnd.randrange(2**32))
    starts = rng.uniform(-3, 3, (n_legs, 2))
    start_times = rng.uniform(0, 5, n_legs)
    velocities = rng.uniform(-0.6, 0.6, (n_legs, 2))
    durations = rng.uniform(0.5, 15, n_legs)
    positions = rng.uniform(-4, 4, (n_obstacles, 2))
    obstacle_velocities = rng.uniform(-0.6, 0.6, (n_obstacles, 2))
    radii = rng.uniform(0.3, 1.0, n_obstacles)
    growth = growth_scale * rng.uniform(0, 1, n_obstacles) if per_obstacle_growth else growth_scale
    contact = legs_first_contact(
        starts, start_times, velocities, durations, positions, obstacle_velocities, radii, growth
    )
    assert contact.shape == (n_legs, n_obstacles)
    g = np.broadcast_to(np.asarray(growth, dtype=float), (n_obstacles,))
    for k in range(n_legs):
        for j in range(n_obstacles):
            # Robot minus obstacle, both expressed from the leg's start (absolute time t0 + τ).
            centre_at_start = positions[j] + obstacle_velocities[j] * start_times[k]
            rel_position = starts[k] - centre_at_start
            rel_velocity = velocities[k] - obstacle_velocities[j]
            radius_at_start = radii[j] + g[j] * start_times[k]
            _check_first_contact(float(contact[k, j]), rel_position, rel_velocity, radius_at_start, g[j], durations[k])


def test_legs_first_contact_already_in_contact_and_separated():
    starts = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
    start_times = np.array([0.0, 2.0, 0.0])
    velocities = np.array([[0.0, 0.0], [0.0, 0.0], [0.3, 0.0]])
    durations = np.array([5.0, 5.0, 20.0])
    # Obstacle reaches the robot's spot at t = 2 s (it starts 0.6 m away at 0.3 m/s toward it... and passes).
    positions = np.array([[-0.6, 0.0]])
    obstacle_velocities = np.array([[0.3, 0.0]])
    radii = np.array([0.4])
    contact = legs_first_contact(starts, start_times, velocities, durations, positions, obstacle_velocities, radii)
    # Leg 0 (waits from t=0): gap 0.6 - 0.4 closes at 0.3 m/s -> contact at 0.2/0.3 s.
    assert contact[0, 0] == pytest.approx(0.2 / 0.3, rel=1e-12)
    # Leg 1 starts at t=2 s with the obstacle centred on it: contact at its start.
    assert contact[1, 0] == 0.0
    # Leg 2 runs away at the obstacle's speed: the gap stays 0.6 > 0.4, never in contact.
    assert np.isinf(contact[2, 0])


# --------------------------------------------------------------------------- closest approach


@core_settings
@given(point, velocity, st.floats(0.0, 30.0))
def test_closest_approach_matches_sampling(rel_position, rel_velocity, duration):
    distance, tau = closest_approach(rel_position, rel_velocity, duration)
    distance, tau = float(distance), float(tau)
    assert 0.0 <= tau <= duration
    assert distance == pytest.approx(np.hypot(*(rel_position + rel_velocity * tau)), abs=1e-12)
    grid = np.linspace(0.0, duration, N_TIME_SAMPLES)
    sampled = np.hypot(*(rel_position[None] + rel_velocity[None] * grid[:, None]).T)
    resolution = np.hypot(*rel_velocity) * (grid[1] - grid[0] if duration > 0 else 0.0)
    assert sampled.min() >= distance - 1e-9
    assert sampled.min() <= distance + resolution + 1e-9


def test_closest_approach_batched_and_standing():
    rel_position = np.array([[3.0, 1.0], [3.0, 1.0], [1.0, 0.0]])
    rel_velocity = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, 0.0]])
    distance, tau = closest_approach(rel_position, rel_velocity, 10.0)
    np.testing.assert_allclose(distance, [1.0, np.hypot(3, 1), 1.0])
    np.testing.assert_allclose(tau, [3.0, 0.0, 0.0])
