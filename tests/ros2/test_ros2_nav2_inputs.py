"""viapath as Nav2's controller against hostile maps, transforms and goals, over DDS: real processes
(``viapath ros2 nav2`` and the driver ``_nav2_input_driver.py``), their own ROS domain, ended by pid.

A map that is no place (NaN or 1e300 origin, empty frame_id) is refused and the last good map kept (the
robot stays short of its wall); a scanner mount from TF 1e6 m out and a quaternion that is no rotation
are refused (logged); a goal whose poses all lie at the robot succeeds; empty goals and goals with a NaN
(among 3 poses or 20 000) end with INVALID_PATH; a 30 000-pose zig-zag goal is followed once the way opens;
the way closed by the mapped wall is a WARN ``blocked`` on /diagnostics, the open way OK; a goal running when
the node is shut down gets its result."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from _ros2_procs import Processes, domain_id, viapath

WALL_X_M = 1.225  # the map's wall (cell centres); its cells reach 0.025 m nearer
ROBOT_RADIUS_M = 0.25
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6
INVALID_PATH = 103
OK_LEVEL, WARN_LEVEL = 0, 1


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


@pytest.mark.parametrize("name", ["empty", "nan_short", "nan_long"])
def test_empty_and_nan_goals_of_any_length_end_with_invalid_path(driven, name):
    phases, _ = driven
    record = phases["bad_goals"][name]
    assert record.get("status") == ABORTED and record.get("code") == INVALID_PATH, record


def test_a_30000_pose_zig_zag_goal_is_taken_and_followed(driven):
    phases, _ = driven
    way = phases["open_way"]
    assert way["goal"].get("accepted")
    assert way["largest_x"] - way["start_x"] > 0.3  # it drove along the new goal's way
    # preempted by the next goal, not refused
    assert way["goal"].get("status") == ABORTED and way["goal"].get("message") == "preempted by a new path"


def test_the_way_closed_by_the_mapped_wall_is_a_blocked_warning_and_the_open_way_ok(driven):
    """On /diagnostics: WARN "blocked" with where the robot waits within 3 s of the goal through the wall, as
    long as that goal runs; OK ("the way is open") within 3 s of the goal sent after the wall's map was replaced
    by a free one."""
    phases, _ = driven
    ways = phases["ways"]
    sent = phases["good_map"]["goal"]["sent_s"]
    blocked = [(t, message) for t, level, message in ways if level == WARN_LEVEL and t >= sent]
    assert blocked and blocked[0][0] - sent <= 3.0, ways
    assert blocked[0][1].startswith("blocked: static geometry closes the way") and "waits at (" in blocked[0][1]
    x_wait = float(blocked[0][1].split("waits at (")[1].split(",")[0])
    assert x_wait < WALL_X_M - 0.025 - ROBOT_RADIUS_M  # short of the wall
    opened = phases["open_way"]["goal"]["sent_s"]
    after = [(t, level, message) for t, level, message in ways if t >= opened]
    assert after and after[0][1] == OK_LEVEL and after[0][2] == "the way is open", ways
    assert after[0][0] - opened <= 3.0
    ended = phases["goal_at_robot"]["sent_s"]  # the goal through the wall replaced (then no path: OK again)
    assert [level for t, level, _ in ways if sent <= t < ended][-1] == WARN_LEVEL  # blocked as long as it ran


def test_the_map_is_taken_by_a_participant_other_than_the_scans(driven):
    """A 10 000 x 10 000 map is 100 MB of fragments: through the participant that takes the scans they crowded out
    best-effort scans (lost: a cycle missed). The node subscribes to the map from a DDS participant of its own."""
    phases, _ = driven
    found = phases["participants"]
    assert len(found["/map"]) == 1 and len(found["/scan_front"]) == 1, found
    assert found["/scan_front"] == found["/odom"]  # the control loop's inputs share one participant
    assert found["/map"] != found["/scan_front"]


def test_goals_and_maps_are_taken_as_arrays_not_python_messages(driven):
    """The lean takes are in use on this build (the node says when it falls back to Python messages)."""
    _, node_err = driven
    assert "taken as Python messages" not in node_err and "maps taken by rclpy" not in node_err
    assert "map: 0 static segments" in node_err  # the free map was taken (by the thread of its own)


def test_a_running_goal_is_canceled_when_asked(driven):
    phases, _ = driven
    assert phases["cancel"].get("accepted") and phases["cancel"].get("status") == CANCELED, phases["cancel"]
