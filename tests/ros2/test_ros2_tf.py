"""The planar TF buffer and the path helpers of the Nav2 interface (no ROS needed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from viapath.path_simplify import simplify_polyline
from viapath.ros2.core import PlannerCore
from viapath.ros2.settings import validate
from viapath.ros2.tf import TransformBuffer, apply


def test_chain_map_odom_base_link_and_a_scanner():
    tf = TransformBuffer()
    assert tf.set("map", "odom", 0.0, 1.0, 2.0, math.pi / 2, static=True)
    assert tf.set("odom", "base_link", 10.0, 3.0, 0.0, 0.0)
    assert tf.set("base_link", "laser_rear", 0.0, -0.145, 0.0, math.pi, static=True)
    x, y, yaw = tf.lookup("map", "base_link", 10.0)
    assert (x, y) == pytest.approx((1.0, 5.0)) and yaw == pytest.approx(math.pi / 2)
    # a point 1 m ahead of the rear scanner is 1.145 m behind the robot centre
    pose = tf.lookup("odom", "laser_rear", 10.0)
    assert apply(pose, 1.0, 0.0) == pytest.approx((3.0 - 1.145, 0.0))
    # and back: map -> odom is the inverse
    inv = tf.lookup("odom", "map")
    assert apply(inv, *apply(tf.lookup("map", "odom"), 0.3, -0.7)) == pytest.approx((0.3, -0.7))


def test_dynamic_edges_interpolate_and_refuse_stale_times():
    tf = TransformBuffer(tolerance_s=0.2)
    tf.set("odom", "base_link", 1.0, 0.0, 0.0, 0.0)
    tf.set("odom", "base_link", 2.0, 1.0, 0.0, math.pi / 2)
    x, y, yaw = tf.lookup("odom", "base_link", 1.5)
    assert (x, y, yaw) == pytest.approx((0.5, 0.0, math.pi / 4))
    assert tf.lookup("odom", "base_link", 2.1) is not None  # the newest, a little late
    assert tf.lookup("odom", "base_link", 2.5) is None  # too far past the newest
    assert tf.lookup("odom", "base_link", 0.5) is None  # before the oldest
    assert tf.lookup("map", "base_link") is None  # no map frame
    assert not tf.set("base_link", "odom", 3.0, 0.0, 0.0, 0.0)  # a loop
    assert not tf.set("odom", "base_link", float("nan"), 0.0, 0.0, 0.0)


def test_simplify_keeps_corners_and_drops_dense_points():
    line = np.column_stack([np.linspace(0, 5, 101), np.zeros(101)])
    corner = np.vstack([line, np.column_stack([np.full(40, 5.0), np.linspace(0.05, 2.0, 40)])])
    out = simplify_polyline(corner, 0.05)
    assert out.tolist() == [[0.0, 0.0], [5.0, 0.0], [5.0, 2.0]]
    assert simplify_polyline([[1.0, 1.0], [1.0, 1.0]], 0.05).tolist() == [[1.0, 1.0]]


def test_speed_limit_caps_the_command_and_zero_lifts_it():
    core = PlannerCore(validate({"max_speed_mps": 0.6}))
    core.set_speed_limit(50.0, True)
    assert core.speed_limit_mps == pytest.approx(0.3)
    core.set_speed_limit(0.15, False)
    assert core.speed_limit_mps == pytest.approx(0.15)
    core.set_speed_limit(0.0, False)
    assert core.speed_limit_mps is None


def test_a_resent_path_keeps_the_planner_and_a_changed_one_replaces_it():
    core = PlannerCore(validate({}))
    core.set_path([[0.0, 0.0], [5.0, 0.0]])
    planner = core.planner
    assert core.same_path([[0.0, 0.0], [5.0, 0.0005]])
    assert not core.same_path([[0.0, 0.0], [5.0, 0.5]])
    assert core.planner is planner
    core.clear_path()
    assert core.path is None and core.planner is None
