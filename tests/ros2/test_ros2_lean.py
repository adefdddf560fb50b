"""Big messages taken as arrays (viapath.ros2.lean), without DDS: the middleware's CDR bytes of a message
(``serialize_message``) taken by rclpy with the lean classes (``deserialize_message`` runs the same creation,
deserialisation and conversion as a subscription's or an action server's take) give what the ordinary Python
message gives, field by field, and no Python object per pose; the node's goal checks refuse what they must."""

from __future__ import annotations

import array
import gc
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from viapath.ros2 import rclpy_available

OK, WHY = rclpy_available()
pytestmark = pytest.mark.skipif(not OK, reason=WHY)

_COORDINATES = st.one_of(st.floats(-1e3, 1e3), st.sampled_from([math.nan, math.inf, -math.inf, 1e300, -0.0, 5e-324]))


def _path(positions, orientations, frame: str, first_pose_frame: str, stamp=(0, 0)):
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path

    msg = Path()
    msg.header.frame_id = frame
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    for k, ((x, y), (qx, qy, qz, qw)) in enumerate(zip(positions, orientations, strict=True)):
        pose = PoseStamped()
        pose.header.frame_id = first_pose_frame if k == 0 else "elsewhere"
        pose.pose.position.x, pose.pose.position.y = x, y
        pose.pose.orientation.x, pose.pose.orientation.y = qx, qy
        pose.pose.orientation.z, pose.pose.orientation.w = qz, qw
        msg.poses.append(pose)
    return msg


def _same(a, b) -> bool:
    return (
        a.frame_id == b.frame_id
        and a.first_pose_frame_id == b.first_pose_frame_id
        and a.stamp_s == b.stamp_s
        and not a.error
        and np.array_equal(a.positions, b.positions, equal_nan=True)
        and np.array_equal(a.orientations, b.orientations, equal_nan=True)
    )


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    poses=st.lists(st.tuples(_COORDINATES, _COORDINATES, _COORDINATES, _COORDINATES), max_size=40),
    frame=st.sampled_from(["", "odom", "map", "a/very/long/frame_" + "x" * 300, "é"]),
    first=st.sampled_from(["", "odom", "base_link"]),
    stamp=st.tuples(st.integers(-(2**31), 2**31 - 1), st.integers(0, 999_999_999)),
)
def test_a_path_taken_as_arrays_is_the_python_message_field_by_field(poses, frame, first, stamp):
    from nav_msgs.msg import Path
    from rclpy.serialization import deserialize_message, serialize_message

    from viapath.ros2.lean import PathArrays, lean_path_type

    lean = lean_path_type()
    assert lean is not None  # the layout check passed on this build
    msg = _path([p[:2] for p in poses], [(p[2], p[3], p[0], p[1]) for p in poses], frame, first, stamp)
    raw = serialize_message(msg)
    taken = deserialize_message(raw, lean)
    assert isinstance(taken, PathArrays) and len(taken) == len(poses)
    assert _same(taken, PathArrays.of(deserialize_message(raw, Path)))


def test_a_goal_request_taken_as_arrays_keeps_its_id_and_path():
    from rclpy.serialization import deserialize_message, serialize_message

    from viapath.ros2 import interfaces
    from viapath.ros2.lean import LeanGoalRequest, PathArrays, lean_goal_request_type

    interfaces.load()
    from nav2_msgs.action import FollowPath

    lean = lean_goal_request_type(FollowPath)
    assert lean is not None
    rng = np.random.default_rng(4)
    request = FollowPath.Impl.SendGoalService.Request()
    request.goal_id.uuid = rng.integers(0, 256, 16).astype(np.uint8)
    points = rng.uniform(-50, 50, (500, 2))
    request.goal.path = _path(points, [(0.0, 0.0, 0.0, 1.0)] * len(points), "map", "map", (3, 500))
    request.goal.controller_id, request.goal.goal_checker_id = "FollowPath", "goal_checker"
    taken = deserialize_message(serialize_message(request), lean)
    assert isinstance(taken, LeanGoalRequest)
    assert bytes(taken.goal_id.uuid) == bytes(request.goal_id.uuid)
    assert _same(taken.goal.path, PathArrays.of(request.goal.path))
    assert taken.goal.path.stamp_s == pytest.approx(3.0000005)


def test_taking_a_long_path_makes_no_python_object_per_pose():
    """The ordinary take makes about seven objects per pose (what stalls the control loop); the lean one a
    handful whatever the length."""
    from nav_msgs.msg import Path
    from rclpy.serialization import deserialize_message, serialize_message

    from viapath.ros2 import convert
    from viapath.ros2.lean import lean_path_type

    lean = lean_path_type()
    n = 20_000
    raw = serialize_message(convert.path_message(np.c_[np.arange(n) * 0.01, np.zeros(n)], "odom", convert.time_msg(0)))

    def objects_made(kind) -> int:
        gc.collect()
        gc.disable()
        try:
            before = len(gc.get_objects())
            taken = deserialize_message(raw, kind)
            made = len(gc.get_objects()) - before
        finally:
            gc.enable()
        assert taken is not None
        return made

    assert objects_made(Path) > 5 * n  # the check sees per-pose objects where they are made
    assert objects_made(lean) < 50


def test_an_occupancy_grid_taken_with_its_cells_as_an_array():
    from nav_msgs.msg import OccupancyGrid
    from rclpy.serialization import deserialize_message, serialize_message

    from viapath.ros2.convert import occupancy_layer_from_message
    from viapath.ros2.lean import lean_grid_type

    lean = lean_grid_type()
    assert lean is not None
    rng = np.random.default_rng(7)
    grid = OccupancyGrid()
    grid.header.frame_id = "odom"
    grid.info.resolution, grid.info.width, grid.info.height = 0.05, 37, 23
    grid.info.origin.position.x, grid.info.origin.position.y = -1.25, 0.75
    grid.info.origin.orientation.z, grid.info.origin.orientation.w = math.sin(0.2), math.cos(0.2)
    grid.data = array.array("b", rng.choice([-1, 0, 50, 65, 100], 37 * 23).astype(np.int8).tobytes())
    raw = serialize_message(grid)
    taken, plain = deserialize_message(raw, lean), deserialize_message(raw, OccupancyGrid)
    assert taken.error == "" and taken.header.frame_id == "odom"
    assert taken.data.tobytes() == plain.data.tobytes()
    ours, theirs = occupancy_layer_from_message(taken), occupancy_layer_from_message(plain)
    assert len(ours) > 0 and np.array_equal(ours.segments, theirs.segments)
    assert np.array_equal(ours.radii_m, theirs.radii_m)


def test_goal_checks_refuse_unreadable_empty_and_non_finite_paths_of_any_length():
    from viapath.ros2.lean import PathArrays
    from viapath.ros2.nav2 import _quickly_invalid

    invalid = 103

    def path(points, error=""):
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        return PathArrays("odom", 0.0, points, np.tile([0.0, 0.0, 0.0, 1.0], (len(points), 1)), error=error)

    long = np.c_[np.arange(50_000) * 0.01, np.zeros(50_000)]
    assert _quickly_invalid(path(long), invalid) == (0, "")
    for bad in (math.nan, math.inf):
        spoiled = long.copy()
        spoiled[-7, 1] = bad
        assert _quickly_invalid(path(spoiled), invalid) == (invalid, "path with NaN or infinite coordinates")
    assert _quickly_invalid(path([]), invalid) == (invalid, "empty path")
    code, why = _quickly_invalid(path([], error="ValueError: 9 poses announced and none there"), invalid)
    assert code == invalid and "could not be read" in why and "9 poses announced" in why
