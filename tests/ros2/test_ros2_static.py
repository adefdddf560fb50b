"""The node's static layer without ROS: a wall the detector rejects, and a known map, keep the robot clear."""

from __future__ import annotations

import numpy as np

from tests.ros2.test_ros2_core import SCANNERS, feed, make_core
from viapath.perception.raycast import simulate_scan
from viapath.ros2.convert import occupancy_layer
from viapath.static import StaticLayer, point_segment_distances

WALL = np.array([[[1.0, -2.0], [1.0, 2.0]]])  # across the path, 1 m ahead


def wall_scans(pose, walls=WALL):
    return [simulate_scan(s, np.asarray(pose, float), np.zeros((0, 2)), np.zeros(0), walls) for s in SCANNERS]


def test_a_wall_across_the_path_stops_the_robot_short_of_it():
    core = make_core()
    pose = np.array([0.0, 0.0, 0.0])
    speed = 0.3
    for k in range(40):  # the robot drives as commanded (a perfect base) and must never reach the wall
        t = 1.0 + 0.1 * k
        assert feed(core, t, tuple(pose), speed, scans=wall_scans(pose))
        result = core.cycle(t)
        speed = result.command.speed_mps
        pose = pose + 0.1 * speed * np.array([np.cos(pose[2]), np.sin(pose[2]), 0.0])
        pose[2] += 0.1 * result.command.turn_rate_radps
    assert len(core.static_now) > 0  # the wall is static geometry: the detector rejects it as a person
    gap = point_segment_distances(pose[None, :2], WALL)[0, 0] - core.settings.robot_radius_m
    assert 0.0 < gap < 1.0 and speed == 0.0


def test_occupancy_grid_cells_become_static_geometry_that_covers_them():
    rng = np.random.default_rng(2)
    cells = np.where(rng.uniform(size=(30, 40)) < 0.15, 100, 0)
    cells[5, 3:20] = 100  # a wall
    cells[rng.uniform(size=cells.shape) < 0.05] = -1  # unknown
    resolution, origin = 0.05, (1.0, -2.0, 0.3)
    layer = occupancy_layer(cells, resolution, *origin)
    rows, cols = np.nonzero(cells >= 65)
    local = np.c_[cols + 0.5, rows + 0.5] * resolution
    c, s = np.cos(origin[2]), np.sin(origin[2])
    centres = local @ np.array([[c, s], [-s, c]]) + origin[:2]
    distance = point_segment_distances(centres, layer.segments)
    assert np.all(distance.min(axis=1) <= 1e-9)  # every occupied cell's centre lies on a segment
    assert np.all(layer.radii_m >= resolution * np.sqrt(0.5) - 1e-12)  # and the radius covers the cell
    assert len(layer) < len(rows)  # runs, not one point per cell
    free = np.c_[np.nonzero(cells < 65)[1] + 0.5, np.nonzero(cells < 65)[0] + 0.5] * resolution
    free = free @ np.array([[c, s], [-s, c]]) + origin[:2]
    assert np.all(point_segment_distances(free, layer.segments).min(axis=1) >= resolution - 1e-9)


def test_a_known_map_keeps_the_robot_from_a_wall_it_cannot_see():
    core = make_core()
    core.set_map(StaticLayer(WALL))
    pose = np.array([0.0, 0.0, 0.0])
    empty = wall_scans(pose, np.zeros((0, 2, 2)))
    speed = 0.3
    for k in range(40):
        t = 1.0 + 0.1 * k
        assert feed(core, t, tuple(pose), speed, scans=empty)
        speed = core.cycle(t).command.speed_mps
        pose = pose + 0.1 * speed * np.array([1.0, 0.0, 0.0])
    assert 0.0 < pose[0] + core.settings.robot_radius_m < 1.0 and speed == 0.0


def test_markers_draw_the_static_layer():
    import pytest

    from viapath.ros2 import rclpy_available

    ok, why = rclpy_available()
    if not ok:
        pytest.skip(why)
    from viapath.observation import Command, Decision, Obstacles, Plan
    from viapath.path import DesignatedPath
    from viapath.planning import make_planner
    from viapath.ros2.convert import time_msg
    from viapath.ros2.core import CycleResult
    from viapath.ros2.markers import MarkerScenes, marker_array

    path = DesignatedPath([[0.0, 0.0], [4.0, 0.0]], half_widths_m=[1.0])
    static = StaticLayer(np.array([[[1.0, -1.0], [1.0, 1.0]], [[2.0, 0.5], [2.5, 0.5]]]))
    result = CycleResult(
        Command(0.0, 0.0),
        "driving",
        [],
        1.0,
        Decision(Command(0.0, 0.0), Plan("blocked", 0.0, np.zeros(2))),
        Obstacles.empty(),
        np.zeros(3),
        static=static,
    )
    scenes = MarkerScenes(robot_radius_m=0.25)
    markers = marker_array(scenes.scene(path, make_planner("viapath", path), result), None, "odom", time_msg(1.0))
    (line,) = [m for m in markers.markers if m.ns == "static"]
    points = np.array([[p.x, p.y] for p in line.points])
    assert np.allclose(points, static.segments.reshape(-1, 2))


def _drive(core, walls, cycles: int = 40):
    """The robot drives as commanded (a perfect base) along x; each cycle's ``way`` status."""
    pose, speed, ways = np.array([0.0, 0.0, 0.0]), 0.3, []
    for k in range(cycles):
        t = 1.0 + 0.1 * k
        assert feed(core, t, tuple(pose), speed, scans=wall_scans(pose, walls))
        result = core.cycle(t)
        speed = result.command.speed_mps
        pose = pose + 0.1 * speed * np.array([1.0, 0.0, 0.0])
        ways.append(result.status["way"])
    return pose, ways


def test_the_way_status_says_blocked_and_where_the_robot_waits_while_a_wall_closes_the_way():
    """A wall across the way (seen by the scanners): from the first cycles the status is ``blocked`` with a wait
    point short of the wall, the robot never beyond it; an open corridor: ``ok`` throughout."""
    core = make_core()
    pose, ways = _drive(core, WALL)
    assert all(w["state"] == "blocked" for w in ways[5:]), [w["state"] for w in ways]
    wait = np.array([float(ways[-1]["wait_x_m"]), float(ways[-1]["wait_y_m"])])
    assert point_segment_distances(wait[None], WALL)[0, 0] > core.settings.robot_radius_m  # short of the wall
    assert abs(pose[0] - wait[0]) < 0.1  # and the robot waits there
    assert ways[-1]["message"].startswith("blocked: static geometry closes the way")
    assert float(ways[-1]["blocked_for_s"]) >= 3.0
    open_core = make_core()
    _, ways = _drive(open_core, np.zeros((0, 2, 2)), cycles=20)
    assert all(w["state"] == "ok" and w["blocked"] == "0" for w in ways)
    assert ways[-1]["message"] == "the way is open"
