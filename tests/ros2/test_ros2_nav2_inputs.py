"""viapath as Nav2's controller against hostile maps, transforms and goals, over DDS: real processes
(``viapath ros2 nav2`` and the driver ``_nav2_input_driver.py``), their own ROS domain, ended by pid.

A map that is no place (NaN or 1e300 origin, empty frame_id) is refused and the last good map kept (the
robot stays short of its wall); a scanner mount from TF 1e6 m out and a quaternion that is no rotation
are refused (logged); a goal whose poses all lie at the robot succeeds; a goal running when the node
is shut down gets its result."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from _ros2_procs import Processes, domain_id, viapath

WALL_X_M = 1.225  # the map's wall (cell centres); its cells reach 0.025 m nearer
ROBOT_RADIUS_M = 0.25
SUCCEEDED, ABORTED = 4, 6


@pytest.fixture(scope="module")
def driven(tmp_path_factory):
    from viapath.ros2 import interfaces, rclpy_available

    ok, why = rclpy_available()
    if not ok:
        pytest.skip(why)
    interfaces.build()
    folder = tmp_path_factory.mktemp("nav2_inputs")
    procs = Processes(folder)
    domain = domain_id()
    out = folder / "driven.json"
    try:
        node = procs.start(
            "node",
            viapath(
                "ros2",
                "nav2",
                "--ros-args",
                "-p",
                "autostart:=true",
                "-p",
                "map_topic:=map",
                "-p",
                "scan_timeout_s:=5.0",
                "-p",
                "odom_timeout_s:=5.0",
                "-p",
                "progress_patience_s:=60.0",
            ),
            domain,
        )
        driver = procs.start(
            "driver", [sys.executable, str(Path(__file__).with_name("_nav2_input_driver.py")), str(out)], domain
        )
        code = procs.wait(driver, 240.0)
        _out, driver_err = procs.output(driver)
        assert code == 0, driver_err[-3000:]
        procs.stop(node)
        _node_out, node_err = procs.output(node)
        yield json.loads(out.read_text()), node_err
    finally:
        procs.stop_all()


def test_the_robot_drives_up_to_the_mapped_wall_and_stops_short_of_it(driven):
    phases, _ = driven
    assert 0.3 < phases["good_map"]["largest_x"] < WALL_X_M - 0.025 - ROBOT_RADIUS_M


@pytest.mark.parametrize("phase", ["nan_origin", "huge_origin", "empty_frame"])
def test_a_map_that_is_no_place_is_refused_and_the_wall_kept(driven, phase):
    phases, node_err = driven
    assert phases[phase]["largest_x"] < WALL_X_M - 0.025 - ROBOT_RADIUS_M
    assert node_err.count("map refused") >= 3


def test_a_mount_far_out_and_a_quaternion_that_is_no_rotation_are_refused(driven):
    phases, node_err = driven
    assert "mount from TF (1e+06" in node_err and "refused" in node_err
    assert "transform map -> odom refused" in node_err
    assert phases["bad_tf"]["largest_x"] < WALL_X_M - 0.025 - ROBOT_RADIUS_M


def test_a_goal_with_every_pose_at_the_robot_succeeds(driven):
    phases, _ = driven
    assert phases["goal_at_robot"].get("status") == SUCCEEDED


def test_a_goal_running_at_shutdown_gets_its_result(driven):
    phases, _ = driven
    assert phases["shutdown_during_goal"].get("accepted")
    assert phases["shutdown_during_goal"].get("status") == ABORTED
