"""The node's input contract without DDS: maps, transforms, scanner mounts and paths are refused with a
reason (the last good one kept) or reach the planner; work that grows with a path or a map is done by
the worker thread, never in the callback that receives it; path simplification is linear in time and
every dropped point stays within the tolerance (brute force: exact point-segment distances)."""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from viapath.path_simplify import REPEAT_M, simplify_polyline, sleeve_simplify
from viapath.ros2.background import Background
from viapath.ros2.convert import MAX_MAP_SEGMENTS, occupancy_layer
from viapath.ros2.core import PlannerCore
from viapath.ros2.settings import validate
from viapath.ros2.tf import TransformBuffer
from viapath.static import point_segment_distances


def _wall_cells(width=40, height=40, column=20):
    cells = np.zeros((height, width), dtype=np.int16)
    cells[:, column] = 100
    return cells


@pytest.mark.parametrize(
    "origin",
    [(math.nan, 0.0, 0.0), (0.0, 1e300, 0.0), (math.inf, 0.0, 0.0), (2e6, 0.0, 0.0), (0.0, 0.0, math.nan)],
)
def test_a_map_whose_origin_is_not_a_place_is_refused(origin):
    with pytest.raises(ValueError, match="occupancy grid: origin"):
        occupancy_layer(_wall_cells(), 0.05, *origin)


def test_a_map_of_more_occupied_runs_than_any_building_is_refused():
    side = int(math.isqrt(2 * MAX_MAP_SEGMENTS)) + 2
    checkerboard = (np.indices((side, side)).sum(axis=0) % 2 * 100).astype(np.int8)
    with pytest.raises(ValueError, match="runs of occupied cells"):
        occupancy_layer(checkerboard, 0.05, 0.0, 0.0, 0.0)


def test_a_good_map_covers_each_occupied_cell():
    """Brute force: every occupied cell's centre lies within its segment's radius (the cell's half-diagonal)."""
    rng = np.random.default_rng(3)
    cells = (rng.random((30, 50)) < 0.2).astype(np.int16) * 100
    layer = occupancy_layer(cells, 0.1, 1.0, -2.0, 0.3)
    rows, cols = np.nonzero(cells >= 65)
    c, s = math.cos(0.3), math.sin(0.3)
    local = np.column_stack([(cols + 0.5) * 0.1, (rows + 0.5) * 0.1])
    world = local @ np.array([[c, s], [-s, c]]) + [1.0, -2.0]
    distance = point_segment_distances(world, layer.segments).min(axis=1)
    assert distance.max() <= 1e-9


def test_a_stale_dynamic_transform_is_not_used_and_a_static_one_always_is():
    tf = TransformBuffer(max_age_s=2.0)
    assert tf.set("map", "odom", 100.0, 1.0, 2.0, 0.5)
    assert tf.set("base_link", "laser", 0.0, 0.2, 0.0, 0.0, static=True)
    assert tf.lookup("odom", "map", now_s=101.0) is not None
    assert tf.lookup("odom", "map", now_s=100.0 + 3600.0) is None  # stamped an hour ago
    assert tf.lookup("base_link", "laser", now_s=1e9) == (0.2, 0.0, 0.0)  # /tf_static holds for all time


@pytest.mark.parametrize("mount", [(1e6, 0.0, 0.0), (0.0, -11.0, 0.0), (math.nan, 0.0, 0.0), (0.0, 0.0, math.inf)])
def test_a_scanner_mount_beyond_the_parameters_bounds_is_refused_and_the_old_one_kept(mount):
    core = PlannerCore(validate({}))
    core.set_mount(0, 0.1, 0.0, 0.0)
    assert core.mount_problem(*mount)
    with pytest.raises(ValueError, match="scanner mount"):
        core.set_mount(0, *mount)
    assert core.health[0].mount == (0.1, 0.0, 0.0)


def test_a_good_scanner_mount_from_tf_is_used():
    core = PlannerCore(validate({}))
    assert core.set_mount(0, 0.2, 0.05, 0.1)
    assert core.health[0].model.mount_x_m == pytest.approx(0.2)


def test_the_path_callback_returns_before_the_path_is_read():
    """The node's path job: reading the message happens in the worker, so a message whose reading blocks
    does not block the submitting thread; the old path stays until the new one is taken."""
    core = PlannerCore(validate({}))
    core.set_path([[0.0, 0.0], [5.0, 0.0]])
    old = core.path
    release = threading.Event()

    def slow_points():
        release.wait(10.0)
        return np.column_stack([np.linspace(0.0, 9.0, 1000), np.zeros(1000)])

    background = Background()
    started = time.monotonic()
    background.submit("path", lambda: core.prepare_path_message("odom", slow_points()))
    assert time.monotonic() - started < 1.0
    assert background.take("path") is None and background.busy("path")
    assert core.path is old
    release.set()
    deadline = time.monotonic() + 10.0
    outcome = None
    while outcome is None and time.monotonic() < deadline:
        outcome = background.take("path")
        time.sleep(0.01)
    assert outcome is not None and outcome.error is None
    accepted, _what = core.use_path_message(outcome.value)
    assert accepted and core.path is not old and core.path.goal.tolist() == [9.0, 0.0]


def test_a_newer_job_supersedes_an_older_one_and_errors_are_results():
    background = Background()
    gate = threading.Event()
    background.submit("path", lambda: gate.wait(5.0) and "first")
    time.sleep(0.05)
    background.submit("path", lambda: "second")
    background.submit("path", lambda: "third")  # replaces "second", which never runs
    gate.set()
    deadline = time.monotonic() + 5.0
    seen = []
    while time.monotonic() < deadline and "third" not in seen:
        outcome = background.take("path")
        if outcome is not None:
            seen.append(outcome.value)
        time.sleep(0.01)
    assert seen == ["third"]
    background.submit("map", lambda: 1 / 0)
    deadline = time.monotonic() + 5.0
    outcome = None
    while outcome is None and time.monotonic() < deadline:
        outcome = background.take("map")
        time.sleep(0.01)
    assert isinstance(outcome.error, ZeroDivisionError)


@pytest.mark.parametrize("bad", [[(0.0, 0.0, 1.0, 1.0)], [(0.0, 0.0, 0.0, 0.0)], [(0.0, 0.0, 1e300, 1.0)]])
def test_a_path_with_a_quaternion_that_is_no_rotation_is_refused(bad):
    core = PlannerCore(validate({}))
    core.set_path([[0.0, 0.0], [5.0, 0.0]])
    accepted, what = core.on_path("odom", [[0.0, 0.0], [3.0, 0.0]], [(0.0, 0.0, 0.0, 1.0)] + bad)
    assert not accepted and "pose 1" in what
    assert core.path.goal.tolist() == [5.0, 0.0]


def _brute_within(points, out, tolerance):
    segments = np.stack([out[:-1], out[1:]], axis=1) if len(out) > 1 else np.stack([out, out], axis=1)
    return point_segment_distances(points, segments).min(axis=1).max() <= tolerance + 1e-9


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    steps=st.lists(st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)), min_size=1, max_size=60),
    scale=st.sampled_from([0.01, 0.1, 1.0]),
    tolerance=st.sampled_from([0.01, 0.05, 0.3]),
)
@example(steps=[(0.0, 6.103515625e-05)], scale=0.01, tolerance=0.01)  # a path of one point and its repeat
def test_simplified_paths_keep_every_point_within_the_tolerance(steps, scale, tolerance):
    points = np.cumsum(np.vstack([[0.0, 0.0], np.array(steps) * scale]), axis=0)
    for simplify in (simplify_polyline, sleeve_simplify):
        out = simplify(points, tolerance)
        # the ends are kept; a point repeating the next (within REPEAT_M) is dropped, so the first kept is within
        # REPEAT_M per point dropped at the start
        near_first = REPEAT_M * len(points)
        assert np.allclose(out[0], points[0], rtol=0, atol=near_first) and np.array_equal(out[-1], points[-1])
        assert _brute_within(points, out, tolerance), simplify.__name__


def test_a_zig_zag_is_simplified_in_linear_work():
    """Douglas-Peucker's work on a zig-zag grows with the square of its points; the simplification
    switches to the sleeve within its budget: the work counted, not timed (the sleeve visits each point
    a bounded number of times, which the counting wrapper below checks on the plain Python form of the
    compiled pass; the compiled pass gives the same points)."""
    from viapath.jit import python_function
    from viapath.path_simplify import _sleeve_keep

    n = 30_000
    zig = np.column_stack([np.arange(n) * 0.01, np.where(np.arange(n) % 2, 0.1, -0.1)])
    out = simplify_polyline(zig, 0.05)
    assert len(out) == n  # nothing can go: each point is 0.2 m off its neighbours' line
    visits = {"count": 0}

    original_hypot = math.hypot

    def counting_hypot(*args):
        visits["count"] += 1
        return original_hypot(*args)

    xs, ys = zig[:, 0].copy(), zig[:, 1].copy()
    math.hypot = counting_hypot
    try:
        kept = python_function(_sleeve_keep)(xs, ys, 0.05)
    finally:
        math.hypot = original_hypot
    assert 0 < visits["count"] <= 3 * n
    assert np.array_equal(zig[kept], sleeve_simplify(zig, 0.05))


# -- property: hostile maps and paths through the node's core ---------------------------------------

_ORIGINS = st.one_of(
    st.floats(-3.0, -1.0),
    st.sampled_from([math.nan, math.inf, -math.inf, 1e300, -1e7, 2e6]),
)
_RESOLUTIONS = st.one_of(st.floats(0.02, 0.2), st.sampled_from([0.0, -0.05, math.nan, math.inf, 1e300]))


@settings(max_examples=25, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(ox=_ORIGINS, oy=_ORIGINS, resolution=_RESOLUTIONS, yaw=st.sampled_from([0.0, 0.3, math.nan]), data=st.data())
def test_hostile_maps_reach_the_planner_or_are_refused_and_no_command_drives_into_the_known_map(
    ox, oy, resolution, yaw, data
):
    """A good map has a wall 1.0 m ahead; then a random map arrives. Refused: the good map stays.
    Accepted: it is the map. Either way the robot, driven by the node's commands, never overlaps the
    geometry of the map in use (brute force: exact distances from the body to the map's segments)."""
    from tests.ros2.test_ros2_hostile import Robot, cycle, make_core

    core = make_core(static_layer=False)
    good = np.zeros((60, 60), dtype=np.int16)
    good[:, 40] = 100  # with the origin below: a wall across the way at x = -1 + 40.5 * 0.05 = 1.025 m
    core.set_map(occupancy_layer(good, 0.05, -1.0, -1.5, 0.0))
    cells = (np.asarray(data.draw(st.lists(st.booleans(), min_size=400, max_size=400))).reshape(20, 20) * 100).astype(
        np.int16
    )
    cells[:8, :] = cells[12:, :] = 0  # keep the robot's own place free in any accepted map
    try:
        layer = occupancy_layer(cells, resolution, ox, oy, yaw)
    except ValueError as error:
        assert str(error).startswith("occupancy grid:")
        expected = core.map_layer
    else:
        assert np.isfinite(layer.segments).all() and (np.abs(layer.segments) <= 1e6).all()
        core.set_map(layer)
        expected = core.map_layer
    robot = Robot(people=[])
    t = 1.0
    for _ in range(25):
        cycle(core, robot, t)
        t += 0.1
        if len(expected):
            gap = point_segment_distances(np.array([[robot.x, robot.y]]), expected.segments)[0] - expected.padding_m
            assert gap.min() >= 0.25 - 0.02, (robot.x, robot.y)
    assert core.map_layer is expected


@settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(
    points=st.lists(
        st.tuples(
            st.one_of(st.floats(-50.0, 50.0), st.sampled_from([math.nan, math.inf, 1e300, -2e6])),
            st.floats(-50.0, 50.0),
        ),
        max_size=12,
    ),
    quaternion=st.sampled_from([None, (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 1.0, 1.0), (0.0, 0.0, 0.0, 0.0)]),
)
def test_hostile_paths_reach_the_planner_or_are_refused(points, quaternion):
    """Refused: the old path stays, and the reason is counted. Accepted: every waypoint is finite and
    within the guard's bounds. An empty path clears it (the robot brakes)."""
    core = PlannerCore(validate({}))
    core.set_path([[0.0, 0.0], [5.0, 0.0]])
    old = core.path
    orientations = None if quaternion is None else [quaternion] * len(points)
    accepted, what = core.on_path("odom", points, orientations)
    if not points:
        assert accepted and core.path is None
    elif accepted:
        assert core.path is not old and np.isfinite(core.path.waypoints).all()
        assert (np.abs(core.path.waypoints) <= 1e6).all()
    else:
        assert core.path is old and core.paths_refused == 1 and what.startswith("path refused")
