"""path.py against brute force: the corridor is the union of capsules of the densely sampled polyline.

The reference distances come from sampling every segment densely (``conftest.sample_polyline``);
tolerances are that sampling's resolution, never a number printed by the code under test.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests._core_helpers import brute_segment_distances, core_settings, sample_polyline, sampling_error
from viapath.geometry import cross2
from viapath.path import DesignatedPath, SubgoalPolicy, SubgoalTracker

PER_SEGMENT = 4000


@st.composite
def paths(draw, max_segments=4):
    """A random polyline (steps of 0.5–3 m in any direction) with one corridor half-width per segment."""
    n = draw(st.integers(1, max_segments))
    start = np.array([draw(st.floats(-3, 3)), draw(st.floats(-3, 3))])
    steps = [draw(st.floats(0.5, 3.0)) for _ in range(n)]
    angles = [draw(st.floats(-np.pi, np.pi)) for _ in range(n)]
    waypoints = [start]
    for length, angle in zip(steps, angles):
        waypoints.append(waypoints[-1] + length * np.array([np.cos(angle), np.sin(angle)]))
    widths = [draw(st.floats(0.2, 1.5)) for _ in range(n)]
    return DesignatedPath(np.array(waypoints), half_widths_m=widths)


def _queries(draw, path, count):
    lo, hi = path.waypoints.min(axis=0) - 2.0, path.waypoints.max(axis=0) + 2.0
    xs = [draw(st.floats(lo[0], hi[0])) for _ in range(count)]
    ys = [draw(st.floats(lo[1], hi[1])) for _ in range(count)]
    return np.stack([xs, ys], axis=-1)


@st.composite
def path_and_points(draw, count=12):
    path = draw(paths())
    return path, _queries(draw, path, count)


def test_brute_reference_matches_exact_point_segment_distance():
    """The dense-sampling reference itself, checked on a hand-solvable case."""
    samples, _ = sample_polyline(np.array([[0.0, 0.0], [4.0, 0.0]]), PER_SEGMENT)
    points = np.array([[2.0, 1.5], [-3.0, 4.0], [7.0, 0.0], [1.0, 0.0]])
    d = brute_segment_distances(points, samples)[:, 0]
    np.testing.assert_allclose(d, [1.5, 5.0, 3.0, 0.0], atol=sampling_error([[0, 0], [4, 0]], PER_SEGMENT) + 1e-12)


@core_settings
@given(path_and_points())
def test_project_matches_brute_force(case):
    path, points = case
    samples, sample_arcs = sample_polyline(path.waypoints, PER_SEGMENT)
    err = sampling_error(path.waypoints, PER_SEGMENT) + 1e-9
    per_segment = brute_segment_distances(points, samples)
    index, arc, lateral = path.project(points)
    assert index.shape == arc.shape == lateral.shape == (len(points),)
    # |lateral deviation| is the distance to the polyline.
    np.testing.assert_allclose(np.abs(lateral), per_segment.min(axis=1), atol=err)
    # The reported arc length names a point of the path at exactly that distance.
    for k, p in enumerate(points):
        foot = path.point_at(arc[k])
        assert np.hypot(*(p - foot)) == pytest.approx(abs(lateral[k]), abs=1e-9)
        assert per_segment[k, index[k]] <= per_segment[k].min() + 2 * err  # the segment is a nearest one
    # Where the nearest segment is unambiguous, the arc and the side agree with the brute-force foot.
    flat = samples.reshape(-1, 2)
    flat_arcs = sample_arcs.reshape(-1)
    spacing = 2 * sampling_error(path.waypoints, PER_SEGMENT)
    for k, p in enumerate(points):
        order = np.sort(per_segment[k])
        if len(order) > 1 and order[1] - order[0] < 1e-2:
            continue
        nearest = int(np.argmin(np.hypot(*(flat - p).T)))
        assert arc[k] == pytest.approx(flat_arcs[nearest], abs=1.5 * spacing + 1e-9)
        segment = int(np.argmin(per_segment[k]))
        foot = flat[nearest]
        along = np.dot(foot - path.waypoints[segment], path.segment_directions[segment])
        interior = 1e-2 < along < path.segment_lengths_m[segment] - 1e-2
        if interior and abs(lateral[k]) > 1e-2:
            direction = path.waypoints[segment + 1] - path.waypoints[segment]
            assert np.sign(lateral[k]) == np.sign(float(cross2(direction, p - foot)))  # + is left


def test_lateral_deviation_sign_convention():
    path = DesignatedPath([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]], half_width_m=1.0)
    # Left of travel is positive: north of the first leg, west of the second.
    lateral = path.lateral_deviation(np.array([[2.0, 0.5], [2.0, -0.5], [3.5, 2.0], [4.5, 2.0]]))
    np.testing.assert_allclose(lateral, [0.5, -0.5, 0.5, -0.5])


@core_settings
@given(path_and_points())
def test_corridor_excess_and_contains_match_brute_force(case):
    path, points = case
    samples, _ = sample_polyline(path.waypoints, PER_SEGMENT)
    err = sampling_error(path.waypoints, PER_SEGMENT) + 1e-9
    brute_excess = np.min(brute_segment_distances(points, samples) - path.half_widths_m, axis=1)
    excess = path.corridor_excess(points)
    np.testing.assert_allclose(excess, brute_excess, atol=err)
    inside = path.contains(points)
    assert np.all(inside[brute_excess < -err])
    assert not np.any(inside[brute_excess > err])


def test_corridor_per_segment_widths_and_outer_corner():
    # Narrow first leg (0.3), wide second leg (1.0) of an L; the outer corner is a round cap.
    path = DesignatedPath([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]], half_widths_m=[0.3, 1.0])
    points = np.array([[2.0, 0.4], [2.0, 0.25], [4.8, -0.5], [4.8, -0.7], [3.2, 2.0], [2.9, 2.0]])
    samples, _ = sample_polyline(path.waypoints, PER_SEGMENT)
    brute_excess = np.min(brute_segment_distances(points, samples) - path.half_widths_m, axis=1)
    expected_inside = brute_excess <= 0
    assert expected_inside.tolist() == [False, True, True, False, True, False]  # sanity of the set-up itself
    np.testing.assert_array_equal(path.contains(points), expected_inside)


@st.composite
def path_and_legs(draw, count=4):
    path = draw(paths(max_segments=3))
    legs = []
    for _ in range(count):
        # Ends near the path (a point on it plus an offset up to 1.5 half-widths), so both outcomes occur.
        ends = []
        cum = path.cumulative_length_m
        if len(cum) > 2 and draw(st.booleans()):
            # Across a junction: the ends near consecutive segments (the sampled branch of the code).
            i = draw(st.integers(0, len(cum) - 3))
            arcs = [draw(st.floats(cum[i], cum[i + 1])), draw(st.floats(cum[i + 1], cum[i + 2]))]
        else:
            arcs = [draw(st.floats(0.0, path.length_m)) for _ in range(2)]
        for arc in arcs:
            angle = draw(st.floats(-np.pi, np.pi))
            r = draw(st.floats(0.0, 1.5)) * float(path.half_widths_m.max())
            ends.append(path.point_at(arc) + r * np.array([np.cos(angle), np.sin(angle)]))
        legs.append(ends)
    legs = np.array(legs)
    spacing = draw(st.sampled_from([0.05, 0.01]))
    return path, legs[:, 0], legs[:, 1], spacing


@core_settings
@given(path_and_legs())
def test_legs_inside_matches_dense_sampling_of_leg(case):
    path, starts, ends, spacing = case
    per_segment = 800
    samples, _ = sample_polyline(path.waypoints, per_segment)
    err = sampling_error(path.waypoints, per_segment) + 1e-9
    inside = path.legs_inside(starts, ends, spacing_m=spacing)
    assert inside.shape == (len(starts),)
    n_leg = 151
    fractions = np.linspace(0.0, 1.0, n_leg)
    for k in range(len(starts)):
        leg_points = starts[k] + fractions[:, None] * (ends[k] - starts[k])
        excess = np.min(brute_segment_distances(leg_points, samples) - path.half_widths_m, axis=1)
        gap = np.hypot(*(ends[k] - starts[k])) / (n_leg - 1)
        if inside[k]:
            # The code samples legs across a junction every `spacing` m: between two inside points an
            # excursion out of a union of convex capsules is at most half that spacing.
            assert excess.max() <= spacing / 2 + err, (k, excess.max())
        else:
            # Some part of the leg is outside (up to our own sampling resolution).
            assert excess.max() > -(gap / 2 + err), (k, excess.max())


def test_legs_inside_across_a_corner():
    path = DesignatedPath([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]], half_width_m=0.5)
    starts = np.array([[3.2, 0.3], [2.0, -0.45], [1.0, 0.0], [4.0, 1.0], [1.0, 0.0]])
    ends = np.array([[4.3, 1.0], [3.55, 1.0], [3.0, 0.0], [4.0, 3.0], [1.0, 0.8]])
    samples, _ = sample_polyline(path.waypoints, 2000)
    fractions = np.linspace(0.0, 1.0, 1001)
    expected = []
    for a, b in zip(starts, ends):
        leg = a + fractions[:, None] * (b - a)
        expected.append(bool(np.all(np.min(brute_segment_distances(leg, samples) - 0.5, axis=1) <= 0)))
    # Set-up sanity: cutting the inner corner is fine; the second leg leaves the corridor in its middle
    # although both its ends are inside; the last ends outside.
    assert expected == [True, False, True, True, False]
    np.testing.assert_array_equal(path.legs_inside(starts, ends, spacing_m=0.01), expected)


def test_legs_inside_finds_a_shallow_excursion_at_the_inner_corner():
    """A leg across the junction that leaves the corridor by 1.4 cm, over 4 cm, just outside the
    concave corner (3.5, 0.5); both ends are well inside (one in each capsule only)."""
    path = DesignatedPath([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]], half_width_m=0.5)
    direction = np.array([1.0, 1.0]) / np.sqrt(2)
    outward = np.array([-1.0, 1.0]) / np.sqrt(2)
    closest = np.array([3.5, 0.5]) + 0.02 * outward
    start, end = closest - 1.0 * direction, closest + 1.3 * direction
    samples, _ = sample_polyline(path.waypoints, 4000)
    leg = start + np.linspace(0, 1, 4601)[:, None] * (end - start)
    excess = np.min(brute_segment_distances(leg, samples) - 0.5, axis=1)
    assert 0.01 < excess.max() < 0.02 and excess[0] < 0 and excess[-1] < 0  # set-up sanity
    assert not path.legs_inside(start[None], end[None], spacing_m=0.005)[0]
    assert path.legs_inside(start[None], end[None], spacing_m=0.005, tolerance_m=0.02)[0]


def test_legs_inside_empty_and_per_leg_tolerance():
    path = DesignatedPath([[0.0, 0.0], [4.0, 0.0]], half_width_m=0.5)
    assert path.legs_inside(np.zeros((0, 2)), np.zeros((0, 2))).shape == (0,)
    starts = np.array([[1.0, 0.0], [1.0, 0.0]])
    ends = np.array([[2.0, 0.55], [2.0, 0.55]])  # 5 cm outside
    np.testing.assert_array_equal(path.legs_inside(starts, ends, tolerance_m=np.array([0.0, 0.1])), [False, True])


@core_settings
@given(paths(), st.lists(st.floats(-2.0, 20.0), min_size=1, max_size=20))
def test_point_at_is_consistent_with_arc_length(path, arcs):
    samples, sample_arcs = sample_polyline(path.waypoints, 50)
    # The point at a sampled arc length is that sample (built independently by linear interpolation).
    for pts, a in zip(samples.reshape(-1, 2), sample_arcs.reshape(-1)):
        np.testing.assert_allclose(path.point_at(a), pts, atol=1e-9)
    for i, w in enumerate(path.waypoints):
        np.testing.assert_allclose(path.point_at(path.cumulative_length_m[i]), w, atol=1e-9)
    # Clamped outside [0, length]; 1-Lipschitz in the arc length; on the path.
    np.testing.assert_allclose(path.point_at(-1.0), path.waypoints[0])
    np.testing.assert_allclose(path.point_at(path.length_m + 1.0), path.goal)
    points = np.array([path.point_at(a) for a in arcs])
    clamped = np.clip(arcs, 0.0, path.length_m)
    for i in range(len(arcs)):
        for j in range(len(arcs)):
            assert np.hypot(*(points[i] - points[j])) <= abs(clamped[i] - clamped[j]) + 1e-9
    assert np.all(np.abs(path.lateral_deviation(points)) < 1e-9)
    assert path.length_m == pytest.approx(float(np.sum(np.hypot(*np.diff(path.waypoints, axis=0).T))))


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(waypoints=[[0, 0]], half_width_m=1.0),
        dict(waypoints=[[0, 0], [0, 0]], half_width_m=1.0),
        dict(waypoints=[[0, 0], [1, np.nan]], half_width_m=1.0),
        dict(waypoints=[[0, 0], [1, 0]], half_width_m=-1.0),
        dict(waypoints=[[0, 0], [1, 0]], half_width_m=np.inf),
        dict(waypoints=[[0, 0], [1, 0], [2, 0]], half_widths_m=[1.0]),
        dict(waypoints=[[0, 0], [1, 0]]),
    ],
)
def test_designated_path_rejects_bad_input(kwargs):
    with pytest.raises(ValueError):
        DesignatedPath(**kwargs)


# --------------------------------------------------------------------------- subgoal tracker

L_PATH = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]]


def test_tracker_goes_to_the_corner_before_turning():
    """Junction rule: head for the corner itself, switch only within reach distance of it."""
    path = DesignatedPath(L_PATH, half_width_m=1.0)
    policy = SubgoalPolicy(reach_threshold_m=0.2)
    tracker = SubgoalTracker(path, policy)
    switched_at = None
    for x in np.arange(0.0, 4.0001, 0.01):
        before = tracker.index
        tracker.update(np.array([x, 0.0]))
        if tracker.index != before:
            switched_at = x
            break
    assert switched_at is not None
    # First x within the reach threshold of the corner (4, 0), to the step size.
    assert 4.0 - switched_at <= policy.reach_threshold_m + 1e-9
    assert 4.0 - switched_at > policy.reach_threshold_m - 0.01 - 1e-9
    np.testing.assert_array_equal(tracker.subgoal, [4.0, 4.0])


def test_tracker_switches_within_reach_from_any_side():
    path = DesignatedPath(L_PATH, half_width_m=1.0)
    for angle in np.linspace(-np.pi, np.pi, 13):
        for r, expect in ((0.19, 2), (0.21, None)):
            tracker = SubgoalTracker(path, SubgoalPolicy(reach_threshold_m=0.2))
            position = np.array([4.0, 0.0]) + r * np.array([np.cos(angle), np.sin(angle)])
            tracker.update(position)
            if expect is not None:
                assert tracker.index == expect
            else:
                # Outside the reach circle it switches only if already past the corner along the first leg.
                passed = position[0] >= 4.0
                assert tracker.index == (2 if passed else 1)


def test_tracker_does_not_turn_back_for_a_passed_subgoal():
    """After swerving around an obstacle the robot is past the subgoal but not within reach of it."""
    path = DesignatedPath([[0.0, 0.0], [3.0, 0.0], [6.0, 0.0]], half_width_m=1.0)
    tracker = SubgoalTracker(path, SubgoalPolicy(reach_threshold_m=0.2))
    tracker.update(np.array([2.5, 0.8]))
    assert tracker.index == 1
    tracker.update(np.array([3.1, 0.8]))  # 0.81 m from (3, 0), but past it
    assert tracker.index == 2
    # Moving back behind it later does not bring the old subgoal back.
    tracker.update(np.array([2.0, 0.0]))
    assert tracker.index == 2
    np.testing.assert_array_equal(tracker.subgoal, [6.0, 0.0])


def test_tracker_skips_several_passed_subgoals_at_once():
    path = DesignatedPath([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]], half_width_m=1.0)
    tracker = SubgoalTracker(path)
    assert tracker.update(np.array([2.5, 0.6])) == 3
    assert tracker.is_final


def test_tracker_bypasses_subgoal_with_standing_obstacle():
    """Paper Fig. 3: an obstacle stands on the corner subgoal; give it up when close, go for the next."""
    path = DesignatedPath(L_PATH, half_width_m=1.0)
    policy = SubgoalPolicy(reach_threshold_m=0.2, bypass_distance_m=1.0, blocked_clearance_m=0.1)
    obstacle = np.array([[4.0, 0.0]])
    radii = np.array([0.25])
    tracker = SubgoalTracker(path, policy)
    tracker.update(np.array([2.5, 0.0]), 0.25, obstacle, radii)  # 1.5 m away: not yet
    assert tracker.index == 1 and tracker.bypassed == []
    tracker.update(np.array([3.1, 0.0]), 0.25, obstacle, radii)  # 0.9 m away: bypass
    assert tracker.index == 2 and tracker.bypassed == [1]
    np.testing.assert_array_equal(tracker.subgoal, [4.0, 4.0])


def test_tracker_blocked_clearance_boundary():
    path = DesignatedPath(L_PATH, half_width_m=1.0)
    policy = SubgoalPolicy(reach_threshold_m=0.2, bypass_distance_m=1.0, blocked_clearance_m=0.1)
    robot = np.array([3.3, 0.0])
    # gap = distance - obstacle radius - robot radius; blocked when gap <= clearance.
    for distance, blocked in ((0.55, True), (0.65, False)):
        tracker = SubgoalTracker(path, policy)
        tracker.update(robot, 0.25, np.array([[4.0, distance]]), np.array([0.25]))
        assert (tracker.index == 2) == blocked
    # No obstacles at all: never blocked.
    tracker = SubgoalTracker(path, policy)
    tracker.update(robot, 0.25, np.zeros((0, 2)), np.zeros(0))
    assert tracker.index == 1


def test_tracker_never_bypasses_the_goal():
    path = DesignatedPath([[0.0, 0.0], [4.0, 0.0]], half_width_m=1.0)
    tracker = SubgoalTracker(path, SubgoalPolicy(goal_tolerance_m=0.1))
    obstacle = np.array([[4.0, 0.0]])
    tracker.update(np.array([3.5, 0.0]), 0.25, obstacle, np.array([0.25]))
    assert tracker.index == 1 and tracker.is_final and tracker.bypassed == []
    assert not tracker.goal_reached(np.array([3.5, 0.0]))
    assert tracker.goal_reached(np.array([3.95, 0.05]))
    assert not tracker.goal_reached(np.array([4.0, 0.11]))


@core_settings
@given(paths(), st.lists(st.tuples(st.floats(-8, 8), st.floats(-8, 8)), min_size=1, max_size=30))
def test_tracker_index_is_monotone_and_bounded(path, positions):
    tracker = SubgoalTracker(path)
    previous = tracker.index
    for p in positions:
        index = tracker.update(np.array(p))
        assert previous <= index <= len(path.waypoints) - 1
        # After an update the robot is neither within reach of, nor past, an intermediate subgoal.
        if not tracker.is_final:
            assert np.hypot(*(tracker.subgoal - p)) > tracker.policy.reach_threshold_m
            segment = tracker.index - 1
            along = np.dot(np.array(p) - path.segment_starts[segment], path.segment_directions[segment])
            assert along < path.segment_lengths_m[segment]
        previous = index


def test_corridor_excess_of_one_point_equals_the_array_path():
    """One point (the robot's, every cycle) takes a scalar shortcut: bit for bit what the array
    arithmetic gives for the same point among others, on corners, ends, inside and outside, and
    on the segments' own lines (where the clamp decides)."""
    rng = np.random.default_rng(3)
    paths = [
        DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0),
        DesignatedPath([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0], [-1.0, 4.5]], half_widths_m=[1.2, 0.7, 2.0]),
        DesignatedPath([[0.3, -0.1], [2.5, 0.5], [5.0, -0.5], [8.0, 0.0]], half_width_m=1.5),
    ]
    for path in paths:
        points = np.concatenate(
            [
                rng.uniform(-3.0, 10.0, (400, 2)),
                path.waypoints,
                path.waypoints[:-1] + 0.5 * path.segment_vectors,
                path.waypoints[:-1] - 0.3 * path.segment_vectors,
            ]
        )
        many = path.corridor_excess(points)
        for point, expected in zip(points, many):
            one = path.corridor_excess(point)
            assert isinstance(one, np.float64)
            assert one == expected
