"""The MarkerArray of a cycle holds what the planner saw, drawn from the shared scene
(viapath.viz.scene): the corridor, tracks and their velocities, the x-y-t forecasts (time as the
height, the planner's uncertainty cone), via points and the plan; tracks read back from it."""

from __future__ import annotations

import numpy as np
import pytest

from viapath.ros2 import rclpy_available

OK, WHY = rclpy_available()
pytestmark = pytest.mark.skipif(not OK, reason=WHY)


def _segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = b - a
    t = np.clip(((points - a) @ d) / (d @ d), 0.0, 1.0)
    return np.hypot(*(points - (a + t[:, None] * d)).T)


def tracks_from_markers(markers) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ids, positions (N, 2), velocities (N, 2)) back from a MarkerArray of :func:`marker_array`."""
    ids, positions, velocities = [], [], []
    arrows = {m.id: m for m in markers.markers if m.ns == "velocities"}
    for m in markers.markers:
        if m.ns == "tracks":
            ids.append(m.id)
            positions.append((m.pose.position.x, m.pose.position.y))
            a = arrows.get(m.id)
            velocities.append((a.points[1].x - a.points[0].x, a.points[1].y - a.points[0].y) if a else (np.nan, np.nan))
    return (
        np.array(ids, dtype=int),
        np.array(positions, dtype=float).reshape(-1, 2),
        np.array(velocities, dtype=float).reshape(-1, 2),
    )


def test_markers_of_a_cycle():
    from viapath.observation import Command, Decision, Obstacles, Plan
    from viapath.path import DesignatedPath
    from viapath.planning import make_planner
    from viapath.ros2.convert import time_msg
    from viapath.ros2.core import CycleResult
    from viapath.ros2.markers import MarkerScenes, marker_array

    path = DesignatedPath([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]], half_widths_m=[1.0, 0.5])
    planner = make_planner("viapath", path, nominal_speed_mps=0.2)
    tracks = Obstacles(
        np.array([[2.0, 0.5], [3.0, -0.5]]),
        np.array([[-0.3, 0.0], [0.0, 0.4]]),
        np.array([0.25, 0.3]),
        position_sigma_m=np.array([0.05, 0.05]),
        velocity_sigma_mps=np.array([0.02, 0.0]),
        ids=np.array([7, 9]),
    )
    plan = Plan(
        "avoid",
        0.2,
        np.array([1.5, 0.9]),
        via_points=np.array([[1.5, 0.9]]),
        waypoints=np.array([[0.0, 0.0], [1.5, 0.9], [4.0, 0.0]]),
    )
    result = CycleResult(
        Command(0.2, 0.1),
        "driving",
        [],
        12.5,
        Decision(Command(0.2, 0.1), plan),
        tracks,
        np.array([0.0, 0.0, 0.0]),
        cycle_time_ms=3.0,
    )
    scenes = MarkerScenes(robot_radius_m=0.23)
    scene = scenes.scene(path, planner, result)
    msg = marker_array(scene, scenes.builder(path, planner).path_view, "odom", time_msg(12.5))
    by_ns = {}
    for m in msg.markers[1:]:
        by_ns.setdefault(m.ns, []).append(m)
        assert m.header.frame_id == "odom" and m.header.stamp.sec == 12 and m.header.stamp.nanosec == 500_000_000
    assert msg.markers[0].action == msg.markers[0].DELETEALL
    assert set(by_ns) == {"corridor", "path", "tracks", "velocities", "forecasts", "via_points", "plan"}
    # Corridor: one capsule outline per segment, every point at the half width from its segment.
    assert len(by_ns["corridor"]) == 2
    for marker, (a, b), half_width in zip(
        sorted(by_ns["corridor"], key=lambda m: m.id),
        [(path.waypoints[0], path.waypoints[1]), (path.waypoints[1], path.waypoints[2])],
        [1.0, 0.5],
    ):
        points = np.array([[p.x, p.y] for p in marker.points])
        assert len(points) > 8 and np.allclose(_segment_distance(points, a, b), half_width, atol=1e-9)
    ids, positions, velocities = tracks_from_markers(msg)
    assert (
        list(ids) == [7, 9] and np.allclose(positions, tracks.positions) and np.allclose(velocities, tracks.velocities)
    )
    # Track 7's forecast at the horizon T: a ring around p + v T of the combined radius grown by the
    # planner's cone (k σ_v T, capped), drawn at height T · scale.
    settings = scene.xyt.settings
    horizon, scale = settings.horizon_s, settings.time_scale_m_per_s
    assert horizon == pytest.approx(planner.config.horizon_s)
    forecast = next(m for m in by_ns["forecasts"] if m.id == 7)
    points = np.array([[p.x, p.y, p.z] for p in forecast.points])
    top = points[np.isclose(points[:, 2], horizon * scale)]
    radius = 0.25 + 0.23 + min(settings.uncertainty_sigmas * 0.02 * horizon, settings.max_inflation_m)
    centre = np.array([2.0, 0.5]) + horizon * np.array([-0.3, 0.0])
    assert len(top) > 0 and np.allclose(np.hypot(*(top[:, :2] - centre).T), radius)
    bottom = points[np.isclose(points[:, 2], 0.0)]
    assert np.allclose(np.hypot(*(bottom[:, :2] - [2.0, 0.5]).T), 0.25 + 0.23)
    assert [(p.x, p.y) for p in by_ns["via_points"][0].points] == [(1.5, 0.9)]
    assert np.allclose([[p.x, p.y] for p in by_ns["plan"][0].points], plan.waypoints)


def test_a_braking_cycle_without_a_decision_still_shows_the_tracks():
    from viapath.observation import Command, Obstacles
    from viapath.path import DesignatedPath
    from viapath.planning import make_planner
    from viapath.ros2.convert import time_msg
    from viapath.ros2.core import CycleResult
    from viapath.ros2.markers import MarkerScenes, marker_array

    path = DesignatedPath([[0.0, 0.0], [4.0, 0.0]], half_widths_m=1.0)
    planner = make_planner("viapath", path, nominal_speed_mps=0.2)
    tracks = Obstacles(np.array([[1.0, 0.0]]), np.array([[0.0, 0.0]]), np.array([0.25]), ids=np.array([3]))
    result = CycleResult(Command(0.0, 0.0), "braking", ["no odometry"], 1.0, None, tracks, np.zeros(3))
    scenes = MarkerScenes(robot_radius_m=0.23)
    msg = marker_array(
        scenes.scene(path, planner, result), scenes.builder(path, planner).path_view, "odom", time_msg(1.0)
    )
    ids, positions, _ = tracks_from_markers(msg)
    assert list(ids) == [3] and np.allclose(positions, [[1.0, 0.0]])
    assert "plan" not in {m.ns for m in msg.markers}
