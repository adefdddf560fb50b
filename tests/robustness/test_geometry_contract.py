"""The geometry contract: every wall, box, polygon and static layer reaches the planner, the guard and
the shield as conservatively as it is (clipped to a window round the robot, never dropped whole), or is
refused with an error naming the field. Static geometry counts out to the robot's stopping distance plus
its planning reach, whatever its speed. Checks against brute force: exact point-segment distances and
a braking robot stepped in 1 ms steps (tests/robustness/_helpers.py), not the guard's own code."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.robustness._helpers import LIMITS, ROBOT_RADIUS_M, brute_stopping_distance_m, fresh, planners, robot
from viapath.guard import DEFAULT_CONFIG, with_static_rows
from viapath.observation import Observation, ObservationError, Obstacles
from viapath.scenarios.loader import ScenarioError, scenario_from_dict
from viapath.sim.loop import run_episode
from viapath.static import StaticLayer, box_edges, point_segment_distances


def _scene(**extra) -> dict:
    return {
        "name": "geometry-contract",
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.4, "radius": 0.25},
        "path": {"waypoints": [[0.0, 0.0], [6.0, 0.0]], "half_width": 1.0},
        "duration_s": 6.0,
        **extra,
    }


def _braking_path(speed_mps: float, command_speed_mps: float, heading: float = 0.0) -> np.ndarray:
    """Independent of viapath: hold the command for 0.1 s, then brake at the limit, in 1 ms steps;
    the robot centre's positions (S, 2) from the origin along ``heading``."""
    v, dt, t, x, out = speed_mps, 1e-3, 0.0, 0.0, []
    a = LIMITS.max_accel_mps2 * dt
    while t < 60.0:
        goal = command_speed_mps if t < 0.1 else 0.0
        v = min(goal, v + a) if goal > v else max(goal, v - a)
        x += v * dt
        t += dt
        out.append(x)
        if t >= 0.1 and v <= 0.0:
            break
    xs = np.array(out)
    return np.column_stack([xs * math.cos(heading), xs * math.sin(heading)])


def _drives_into(command, wall_x: float, speed_mps: float) -> bool:
    """The command, held and then braked, brings the robot's body (heading +x from the origin, turning
    ignored: it only shortens the way forward) onto the wall across the way at ``wall_x``."""
    if not command.speed_mps > 0:
        return False
    path = _braking_path(speed_mps, command.speed_mps)
    return bool(path[:, 0].max() + ROBOT_RADIUS_M > wall_x)


def test_a_fast_robot_with_gentle_brakes_stops_short_of_a_wall_70m_ahead():
    """2 m/s with 0.1 m/s² braking: 20 m to stop, beyond the fixed 12 m the static geometry used to be cut at."""
    scene = _scene(
        robot={
            "start": [0.0, 0.0],
            "heading": 0.0,
            "speed": 2.0,
            "radius": 0.25,
            "limits": {"max_speed_mps": 2.0, "max_accel_mps2": 0.1},
        },
        path={"waypoints": [[0.0, 0.0], [200.0, 0.0]], "half_width": 1.5},
        walls=[[[70.0, -3.0], [70.0, 3.0]]],
        duration_s=70.0,
    )
    episode = run_episode(scenario_from_dict(scene))
    m = episode.metrics
    assert m["max_speed_mps"] >= 1.99  # it did reach the speed that needs 20 m to stop
    assert m["static_contact"] == 0 and not m["collision"]
    assert episode.trace.robot_poses[:, 0].max() < 70.0 - 0.25
    assert abs(episode.trace.robot_speeds_mps[-1]) < 1e-6  # at rest in front of the wall


@pytest.mark.parametrize("speed", [0.6, 2.0, 5.0])
@pytest.mark.parametrize("accel", [0.1, 0.8])
def test_static_geometry_counts_out_to_the_stopping_distance_plus_the_reach(speed, accel):
    """A wall across the way just inside stopping distance + reach is among the planner's obstacles."""
    from viapath.observation import MotionLimits

    limits = MotionLimits(max_speed_mps=speed, max_accel_mps2=accel)
    reach = brute_stopping_distance_m(speed, limits) + DEFAULT_CONFIG.static_reach_m
    x = max(reach, DEFAULT_CONFIG.static_range_m) - 0.5
    static = StaticLayer(np.array([[[x, -2.0], [x, 2.0]]]))
    observation = Observation(0.0, robot(speed=speed), Obstacles.empty(), static)
    merged = with_static_rows(observation, limits=limits).obstacles
    assert merged.static_count > 0
    nearest = np.hypot(*merged.positions[merged.is_static].T).min()
    assert nearest <= x + DEFAULT_CONFIG.static_spacing_m


@pytest.mark.parametrize("size", ["1e300", "3e6", "inf", "nan", "-1"])
def test_a_box_too_large_for_the_world_is_refused_naming_the_field(size):
    with pytest.raises(ScenarioError, match=r"boxes\.0(\.size)?"):
        scenario_from_dict(_scene(boxes=[{"center": [3.0, 0.0], "size": [1.0, float(size)]}]))


def test_a_box_of_any_accepted_size_on_the_path_is_avoided_and_counted():
    """The largest box a scenario takes (corners at ±1e6 m) across the path: the robot stops short of it,
    and the metrics measure the clearance to it (a finite number)."""
    episode = run_episode(scenario_from_dict(_scene(boxes=[{"center": [2.0, 0.0], "size": [1.0, 1.99998e6]}])))
    m = episode.metrics
    assert m["static_contact"] == 0 and not m["collision"]
    assert m["min_static_clearance_m"] is not None and 0.0 < m["min_static_clearance_m"] < 1.3
    assert episode.trace.robot_poses[:, 0].max() < 1.5 - 0.25


@pytest.mark.parametrize("far", [1e7, 1e300, 1.7e308])
@pytest.mark.parametrize("name", planners())
def test_geometry_beyond_the_coordinate_bound_is_clipped_never_dropped(name, far):
    """A box whose far corners lie beyond any map (1e7 … the largest float) straight across the path
    0.45 m ahead, within the robot's stopping distance: its near edge still stops the robot (it used to be
    dropped whole with its far corners)."""
    edges = np.array(
        [[[0.45, -far], [0.45, far]], [[0.45, far], [far, far]], [[far, far], [far, -far]], [[far, -far], [0.45, -far]]]
    )
    static = StaticLayer(edges, np.zeros(4, dtype=np.int64))
    decision = fresh(name).plan(Observation(0.0, robot(speed=0.6), Obstacles.empty(), static))
    assert not _drives_into(decision.command, 0.45, 0.6), (name, decision.command, decision.plan.status)


def test_a_wall_of_any_length_costs_discs_in_proportion_to_the_window_only():
    """Eight walls 2000 km long (accepted in a scenario): the discs the planner gets are bounded by the
    window round the robot, and the nearest one is where the nearest wall is."""
    walls = np.array([[[-1e6, 0.6 + k], [1e6, 0.6 + k]] for k in range(8)])
    observation = Observation(0.0, robot(), Obstacles.empty(), StaticLayer(walls))
    merged = with_static_rows(observation).obstacles
    window = 2 * (DEFAULT_CONFIG.static_range_m + DEFAULT_CONFIG.static_spacing_m)
    assert merged.static_count <= 8 * (window / 0.1 + 2)
    nearest = (np.hypot(*merged.positions.T) - merged.radii_m).min()
    assert 0.6 - 0.02 <= nearest <= 0.6 + 1e-9  # discs cover the wall with at most ~1 cm to spare


def test_a_static_layer_cannot_be_changed_under_the_planner():
    """Its arrays are read-only copies: neither writing to them nor to the array it was made from
    moves a wall behind the discs the planner has cached."""
    source = np.array([[[5.0, -1.0], [5.0, 1.0]]])
    layer = StaticLayer(source)
    with pytest.raises(ValueError):
        layer.segments[0, :, 0] = 0.6
    source[0, :, 0] = 0.4  # the caller's own array changes ...
    assert layer.segments[0, 0, 0] == 5.0  # ... the layer's does not
    planner = fresh("viapath")
    first = planner.plan(Observation(0.0, robot(), Obstacles.empty(), layer))
    assert first.command.speed_mps > 0  # the wall is 5 m away
    moved = StaticLayer(source)  # the wall in front of the robot: a new layer
    second = planner.plan(Observation(0.1, robot(speed=0.6), Obstacles.empty(), moved))
    assert not _drives_into(second.command, 0.4, 0.6)


@pytest.mark.parametrize("bad", [[[[0, 0], [1, 0]]], np.zeros((1, 2, 2)), None, "wall", 3.0])
def test_observation_static_of_another_type_is_an_error_naming_the_field(bad):
    with pytest.raises(ObservationError, match=r"^static: expected a viapath\.static\.StaticLayer"):
        Observation(0.0, robot(), Obstacles.empty(), bad)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"shape_ids": ["a"]}, "static.shape_ids"),
        ({"shape_ids": [0.5]}, "static.shape_ids"),
        ({"shape_ids": [1, 2]}, "static.shape_ids"),
        ({"radii_m": [1e300]}, "static.radii_m"),
        ({"radii_m": [-1.0]}, "static.radii_m"),
        ({"radii_m": [float("nan")]}, "static.radii_m"),
        ({"radii_m": "wide"}, "static.radii_m"),
        ({"radii_m": [1.0, 2.0]}, "static.radii_m"),
    ],
)
def test_bad_static_fields_are_errors_naming_the_field(kwargs, field):
    with pytest.raises(ValueError, match=rf"^{field}: expected"):
        StaticLayer(np.array([[[1.0, 0.0], [1.0, 1.0]]]), **kwargs)


def test_static_segments_that_are_not_numbers_are_an_error_naming_the_field():
    with pytest.raises(ValueError, match=r"^static\.segments: expected"):
        StaticLayer([[["a", 0], [1, 0]]])


@pytest.mark.parametrize(
    "extra",
    [
        {"walls": [[[-1.0, 0.25], [6.0, 0.25]]]},  # touching: clearance exactly 0
        {"walls": [[[-1.0, 0.1], [6.0, 0.1]]]},  # overlapping
        {"boxes": [{"center": [0.0, 0.0], "size": [3.0, 3.0]}]},  # inside a closed box, far from its edges
        {"polygons": [{"points": [[-2.0, -2.0], [3.0, -2.0], [0.0, 3.0]]}]},
    ],
)
def test_a_robot_placed_on_or_inside_static_geometry_is_in_contact_and_not_at_fault(extra):
    m = run_episode(scenario_from_dict(_scene(duration_s=2.0, **extra))).metrics
    assert m["static_contact"] >= 1 and m["collision"]
    assert not m["at_fault_collision"]
    assert m["min_static_clearance_m"] <= 0.0


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    data=st.data(),
    name=st.sampled_from(planners()),
    speed=st.floats(0.3, 0.6),
)
def test_random_static_layers_reach_the_planner_or_are_refused(data, name, speed):
    """Random layers (huge, far, NaN, degenerate, many shapes) with one known wall across the way
    within reach: the layer is refused with a named error, or no command drives into the known wall."""
    coordinate = st.one_of(
        st.floats(-20.0, 20.0),
        st.sampled_from([1e7, -1e7, 1e300, -1e300, float("nan"), float("inf")]),
    )
    junk = data.draw(st.lists(st.lists(coordinate, min_size=4, max_size=4), max_size=6))
    wall_x = data.draw(st.floats(0.3, 0.5))  # within the stopping distance from 0.6 m/s
    wall = np.array([[[wall_x, -5.0], [wall_x, 5.0]]])
    segments = np.concatenate([wall, np.array(junk, dtype=float).reshape(-1, 2, 2)])
    radii = data.draw(st.one_of(st.none(), st.floats(0.0, 0.2), st.sampled_from([1e300, -1.0, float("nan")])))
    try:
        layer = StaticLayer(segments, radii_m=radii)
    except ValueError as error:
        assert str(error).startswith("static.")
        return
    decision = fresh(name).plan(Observation(0.0, robot(speed=speed), Obstacles.empty(), layer))
    assert not _drives_into(decision.command, wall_x, speed), (name, decision.command, decision.plan.status)


def test_the_box_edges_used_above_are_a_closed_rectangle():
    """Sanity of the fixture: box_edges gives four edges, each corner shared."""
    edges = box_edges([0.0, 0.0], [2.0, 1.0])
    assert np.allclose(edges[:, 1], np.roll(edges[:, 0], -1, axis=0))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_part_of_a_large_layer_near_the_robot_holds_every_segment_within_reach(seed):
    """A map-sized layer (above the size that is indexed): every segment whose exact distance to the
    centre (less its padding) is within the reach is in ``near``, whatever the segment's length, padding
    or place (brute force: exact point-segment distances over the whole layer)."""
    from viapath.static import NEAR_INDEX_MIN_SEGMENTS

    rng = np.random.default_rng(seed)
    n = NEAR_INDEX_MIN_SEGMENTS + 5000
    starts = rng.uniform(-300.0, 300.0, (n, 2))
    lengths = rng.choice([0.0, 0.05, 3.0, 15.0, 40.0, 500.0], n, p=[0.2, 0.4, 0.2, 0.1, 0.05, 0.05])
    angles = rng.uniform(-np.pi, np.pi, n)
    ends = starts + lengths[:, None] * np.column_stack([np.cos(angles), np.sin(angles)])
    segments = np.stack([starts, ends], axis=1)
    segments[:5] = [[[1e300, 0.0], [-1e300, 1.0]]] * 5  # far-flung ones cross every window
    radii = rng.choice([0.0, 0.035, 5.0], n, p=[0.5, 0.45, 0.05])
    layer = StaticLayer(segments, radii_m=radii)
    for _ in range(5):
        centre = rng.uniform(-200.0, 200.0, 2)
        reach = float(rng.choice([12.0, 30.0]))
        near = layer.near(centre, reach)
        with np.errstate(over="ignore", invalid="ignore"):
            distance = point_segment_distances(centre[None], np.clip(segments, -1e12, 1e12))[0] - radii
        must = {tuple(s.ravel()) for s in segments[distance <= reach]}
        got = {tuple(s.ravel()) for s in near.segments}
        assert must <= got
        assert len(near) < len(layer)  # it is a part: the index did its work


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), segments=st.integers(65, 400), seed=st.integers(0, 10_000))
def test_a_long_path_gives_the_same_corridor_numbers_from_its_near_segments(data, segments, seed):
    """A path of many subgoals is checked against the segments near the points only (its cost per cycle
    does not grow with its length): the numbers equal those of every segment, bit for bit, for points in
    the corridor, near it and far from it."""
    import viapath.path as path_module
    from viapath.path import DesignatedPath

    rng = np.random.default_rng(seed)
    steps = rng.normal(size=(segments, 2)) * data.draw(st.sampled_from([0.05, 0.5, 3.0])) + [0.3, 0.0]
    waypoints = np.cumsum(np.vstack([[0.0, 0.0], steps]), axis=0)
    widths = rng.uniform(0.2, 1.5, segments)
    path = DesignatedPath(waypoints, half_widths_m=widths)
    centre = waypoints[rng.integers(0, len(waypoints))]
    points = centre + rng.normal(size=(data.draw(st.integers(1, 300)), 2)) * data.draw(
        st.sampled_from([0.3, 2.0, 50.0])
    )
    windowed = path.corridor_excess(points)
    single = [path.corridor_excess(p) for p in points[:5]]
    many, path_module._MANY_SEGMENTS = path_module._MANY_SEGMENTS, 10**9  # every segment, as before
    try:
        full = DesignatedPath(waypoints, half_widths_m=widths)
        assert np.array_equal(windowed, full.corridor_excess(points))
        assert all(float(a) == float(full.corridor_excess(p)) for a, p in zip(single, points[:5]))
    finally:
        path_module._MANY_SEGMENTS = many
