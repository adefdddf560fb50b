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
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from viapath.ros2.background import Background
from viapath.ros2.convert import MAX_MAP_SEGMENTS, occupancy_layer
from viapath.ros2.core import PlannerCore, simplify_polyline, sleeve_simplify
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
def test_simplified_paths_keep_every_point_within_the_tolerance(steps, scale, tolerance):
    points = np.cumsum(np.vstack([[0.0, 0.0], np.array(steps) * scale]), axis=0)
    for simplify in (simplify_polyline, sleeve_simplify):
        out = simplify(points, tolerance)
        assert np.allclose(out[0], points[0]) and np.allclose(out[-1], points[-1])
        assert _brute_within(points, out, tolerance), simplify.__name__


def test_a_zig_zag_is_simplified_in_linear_work():
    """Douglas-Peucker's work on a zig-zag grows with the square of its points; the simplification
    switches to the sleeve within its budget: the work counted, not timed (the sleeve visits each point
    a bounded number of times, which the counting wrapper below checks)."""
    n = 30_000
    zig = np.column_stack([np.arange(n) * 0.01, np.where(np.arange(n) % 2, 0.1, -0.1)])
    out = simplify_polyline(zig, 0.05)
    assert len(out) == n  # nothing can go: each point is 0.2 m off its neighbours' line
    visits = {"count": 0}

    original_hypot = math.hypot

    def counting_hypot(*args):
        visits["count"] += 1
        return original_hypot(*args)

    math.hypot = counting_hypot
    try:
        sleeve_simplify(zig, 0.05)
    finally:
        math.hypot = original_hypot
    assert visits["count"] <= 3 * n
