"""Baselines behind the planner protocol, on the paper's scenarios (same loop, limits and sensing)."""

import importlib.util

import numpy as np
import pytest

from viapath.observation import Command, MotionLimits, Observation, Obstacles, RobotState
from viapath.path import DesignatedPath
from viapath.planning import available_planners, make_planner
from viapath.scenarios import load_scenario
from viapath.sim.loop import run_episode


def _metrics(scenario, planner):
    return run_episode(load_scenario(scenario), planner=planner).metrics


def test_baselines_register_by_name():
    assert {"follow", "stop", "dwa", "vo"} <= set(available_planners())


def test_follow_collides_head_on_and_is_at_fault():
    metrics = _metrics("paper-front", "follow")
    assert metrics["collision"] and metrics["at_fault_collision"]
    assert metrics["max_lateral_deviation_m"] < 0.01  # it never leaves the path


def test_follow_hit_from_behind_is_not_at_fault():
    metrics = _metrics("paper-behind", "follow")
    assert metrics["collision"] and not metrics["at_fault_collision"]


def test_stop_waits_for_the_crossing_person():
    metrics = _metrics("paper-side", "stop")
    assert metrics["reached_goal"] and not metrics["collision"]
    assert metrics["min_speed_mps"] < 0.01  # it did stop
    assert _metrics("paper-side", "follow")["collision"]  # and stopping is what saved it


@pytest.mark.parametrize("planner", ["dwa", "vo"])
@pytest.mark.parametrize("scenario", ["paper-front", "paper-side", "paper-behind", "two-obstacles"])
def test_avoiding_baselines_reach_goal_without_collision_inside_corridor(planner, scenario):
    metrics = _metrics(scenario, planner)
    assert metrics["reached_goal"]
    assert not metrics["collision"]
    assert metrics["time_outside_corridor_s"] == 0.0


def test_vo_never_commands_a_velocity_inside_a_velocity_obstacle_when_a_free_one_exists():
    path = DesignatedPath([[0.0, 0.0], [10.0, 0.0]], half_width_m=1.5)
    planner = make_planner("vo", path, nominal_speed_mps=0.3, limits=MotionLimits(), robot_radius_m=0.25)
    obstacles = Obstacles(np.array([[1.5, 0.0]]), np.array([[-0.5, 0.0]]), np.array([0.25]))
    observation = Observation(0.0, RobotState(np.zeros(2), 0.0, 0.3), obstacles)
    decision = planner.plan(observation)
    assert decision.plan.status == "vo"
    # The chosen velocity deflects sideways (straight ahead is in the VO) and prefers the left.
    end = decision.plan.waypoints[-1]
    assert end[1] > 0.2


def test_dwa_commands_stay_in_the_dynamic_window():
    path = DesignatedPath([[0.0, 0.0], [10.0, 0.0]], half_width_m=1.0)
    limits = MotionLimits(max_speed_mps=0.6, max_accel_mps2=0.8, max_turn_rate_radps=2.0, max_turn_accel_radps2=6.0)
    planner = make_planner("dwa", path, nominal_speed_mps=0.3, limits=limits, robot_radius_m=0.25)
    decision = planner.plan(Observation(0.0, RobotState(np.zeros(2), 0.5, 0.1, 0.2)))
    command: Command = decision.command
    assert abs(command.speed_mps - 0.1) <= 0.08 + 1e-9
    assert abs(command.turn_rate_radps - 0.2) <= 0.6 + 1e-9
    assert command.turn_rate_radps < 0.2  # heading 0.5 rad off the path: it turns back


@pytest.mark.skipif(importlib.util.find_spec("navground") is None, reason="navground (extra 'navground') not installed")
@pytest.mark.parametrize("planner", ["nav-orca", "nav-hl", "nav-hrvo", "nav-sf"])
def test_navground_peers_run_behind_the_protocol(planner):
    metrics = _metrics("paper-side", planner)
    assert metrics["reached_goal"]
    assert not metrics["collision"]


@pytest.mark.skipif(importlib.util.find_spec("navground") is None, reason="navground (extra 'navground') not installed")
def test_navground_corridor_borders_bound_the_centre_line():
    from viapath.planning.navground_peers import corridor_borders

    segments = corridor_borders(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 3.0]]), np.array([1.25, 1.25]))
    assert len(segments) == 6  # two borders of two segments each, and the two end caps
    points = np.array([p for segment in segments for p in segment])
    # The cap behind the start lies 1.25 m behind it.
    assert np.any(np.all(np.isclose(points, [-1.25, 1.25]), axis=1))
    # Mitred inner corner of an L turning left is at (3 - 1.25, 1.25); the outer at (3 + 1.25, -1.25).
    assert np.any(np.all(np.isclose(points, [1.75, 1.25]), axis=1))
    assert np.any(np.all(np.isclose(points, [4.25, -1.25]), axis=1))


def test_at_fault_is_decided_at_the_onset_of_contact():
    from viapath.sim.metrics import at_fault_collision

    class _Trace:  # the fields at_fault_collision reads
        robot_radius_m = 0.25
        obstacle_radii_m = np.array([0.25])

    trace = _Trace()
    times = np.arange(4)
    # The robot drives +x at 0.2 m/s; the person comes from ahead and touches it in step 1->2.
    trace.robot_poses = np.column_stack([0.02 * times, np.zeros(4), np.zeros(4)])
    trace.robot_speeds_mps = np.full(4, 0.2)
    trace.obstacle_positions = np.array([[[0.9, 0.0]], [[0.7, 0.0]], [[0.45, 0.0]], [[0.3, 0.0]]])
    assert at_fault_collision(trace)
    # The same contact with the robot standing still is not its fault.
    trace.robot_speeds_mps = np.zeros(4)
    assert not at_fault_collision(trace)
    # Nor when the person runs into the robot from behind.
    trace.robot_speeds_mps = np.full(4, 0.2)
    trace.obstacle_positions = np.array([[[-0.9, 0.0]], [[-0.6, 0.0]], [[-0.3, 0.0]], [[0.0, 0.0]]])
    assert not at_fault_collision(trace)


def test_at_fault_seen_1s_ignores_people_who_appear_beside_the_robot():
    from viapath.sim.metrics import at_fault_collision

    class _Trace:
        robot_radius_m = 0.25
        obstacle_radii_m = np.array([0.25])
        dt_s = 0.1

    trace = _Trace()
    steps = 30
    times = np.arange(steps)
    # The robot drives +x at 0.2 m/s; a standing person at x = 1.0 is touched at about step 19.
    trace.robot_poses = np.column_stack([0.02 * times, np.zeros(steps), np.zeros(steps)])
    trace.robot_speeds_mps = np.full(steps, 0.2)
    trace.obstacle_positions = np.tile([[1.0, 0.0]], (steps, 1, 1)).astype(float)
    first_touch = int(np.argmax(0.02 * times > 1.0 - 0.5))
    assert at_fault_collision(trace) and at_fault_collision(trace, seen_for_s=1.0)
    # The same person marked in the data only 0.5 s before the contact: at fault, but not seen 1 s.
    trace.obstacle_positions[: first_touch - 5] = np.nan
    assert at_fault_collision(trace)
    assert not at_fault_collision(trace, seen_for_s=1.0)
    # Present for 1.5 s before the contact: counts again.
    trace.obstacle_positions = np.tile([[1.0, 0.0]], (steps, 1, 1)).astype(float)
    trace.obstacle_positions[: first_touch - 15] = np.nan
    assert at_fault_collision(trace, seen_for_s=1.0)
