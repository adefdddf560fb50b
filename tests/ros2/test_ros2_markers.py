"""The MarkerArray of a cycle holds what the planner saw: corridor, tracks and their velocities, the
x-y-t forecasts (time as the height), via points and the plan; tracks read back from it."""

from __future__ import annotations

import numpy as np
import pytest

from viapath.ros2 import rclpy_available

OK, WHY = rclpy_available()
pytestmark = pytest.mark.skipif(not OK, reason=WHY)


def test_markers_of_a_cycle():
    from viapath.path import DesignatedPath
    from viapath.ros2.convert import time_msg
    from viapath.ros2.markers import Scene, corridor_edges, marker_array, tracks_from_markers

    path = DesignatedPath([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]], half_widths_m=[1.0, 0.5])
    left, right = corridor_edges(path)
    assert np.allclose(left[:2], [[0, 1], [4, 1]]) and np.allclose(right[2:], [[4.5, 0], [4.5, 3]])
    scene = Scene(corridor_left=left, corridor_right=right, path=path.waypoints,
                  track_ids=np.array([7, 9]), track_positions=np.array([[2.0, 0.5], [3.0, -0.5]]),
                  track_velocities=np.array([[-0.3, 0.0], [0.0, 0.4]]), track_radii_m=np.array([0.25, 0.3]),
                  via_points=np.array([[1.5, 0.9]]), plan=np.array([[0.0, 0.0], [1.5, 0.9], [4.0, 0.0]]))
    msg = marker_array(scene, "odom", time_msg(12.5))
    by_ns = {}
    for m in msg.markers[1:]:
        by_ns.setdefault(m.ns, []).append(m)
        assert m.header.frame_id == "odom" and m.header.stamp.sec == 12 and m.header.stamp.nanosec == 500_000_000
    assert msg.markers[0].action == msg.markers[0].DELETEALL
    assert set(by_ns) == {"corridor", "path", "tracks", "velocities", "forecasts", "via_points", "plan"}
    ids, positions, velocities = tracks_from_markers(msg)
    assert list(ids) == [7, 9] and np.allclose(positions, scene.track_positions) and np.allclose(velocities, scene.track_velocities)
    # The forecast of track 7 at t = 4 s: a ring of radius 0.25 around (2 - 1.2, 0.5), drawn at height 4 * 0.2.
    forecast = next(m for m in by_ns["forecasts"] if m.id == 7)
    points = np.array([[p.x, p.y, p.z] for p in forecast.points])
    top = points[np.isclose(points[:, 2], 0.8)]
    assert len(top) > 0 and np.allclose(np.hypot(top[:, 0] - 0.8, top[:, 1] - 0.5), 0.25)
    assert np.isclose(points[:, 2].min(), 0.0)
    assert [(p.x, p.y) for p in by_ns["via_points"][0].points] == [(1.5, 0.9)]
