"""The issue-4 built-in scenarios: each loads, starts clear, and the paper's planner (oracle
perception) brings the robot to the goal without contact and without leaving the corridor."""

from __future__ import annotations

import numpy as np
import pytest

from viapath.scenarios.loader import builtin_names, load_scenario
from viapath.sim.loop import run_episode
from viapath.sim.obstacles import scenario_obstacle_states

NEW_SCENARIOS = ["s-bend", "doorway", "hallway", "overtaking", "corner-person"]

_episodes: dict[str, object] = {}


def _episode(name: str):
    if name not in _episodes:
        _episodes[name] = run_episode(load_scenario(name))
    return _episodes[name]


@pytest.mark.parametrize("name", NEW_SCENARIOS)
def test_scenario_is_built_in_and_starts_clear(name):
    assert name in builtin_names()
    scenario = load_scenario(name)
    robot = scenario.robot
    positions, _, radii = scenario_obstacle_states(scenario, np.array([0.0]))
    gap = np.hypot(*(positions[0] - np.asarray(robot.start)).T) - radii - robot.radius
    assert gap.min() > 0.5, "an obstacle starts next to the robot"
    # Nothing stands (now or for good) on the goal; the start and the goal are on the path.
    goal = np.asarray(scenario.path.waypoints[-1])
    times = np.arange(0.0, scenario.duration_s, scenario.dt_s)
    positions, velocities, radii = scenario_obstacle_states(scenario, times)
    static = np.all(np.hypot(*velocities.transpose(2, 0, 1)) == 0.0, axis=0)
    final_gap = np.hypot(*(positions[-1] - goal).T) - radii - robot.radius
    assert np.all(final_gap[static] > 0.1)
    assert tuple(scenario.path.waypoints[0]) == tuple(robot.start)


@pytest.mark.parametrize("name", NEW_SCENARIOS)
def test_planner_reaches_goal_without_collision_inside_corridor(name):
    metrics = _episode(name).metrics
    assert metrics["reached_goal"], metrics
    assert not metrics["collision"], metrics
    assert metrics["time_outside_corridor_s"] == 0.0, metrics


@pytest.mark.parametrize("name", NEW_SCENARIOS)
def test_smoothness_metrics_are_reported_and_within_the_robot_limits(name):
    episode = _episode(name)
    metrics = episode.metrics
    limits = load_scenario(name).robot.limits
    assert metrics["max_abs_accel_mps2"] <= limits.max_accel_mps2 + 1e-9
    assert metrics["max_abs_turn_rate_radps"] <= limits.max_turn_rate_radps + 1e-9
    for key in ("max_abs_jerk_mps3", "steering_reversals", "plan_switches", "plan_side_flips"):
        assert metrics[key] >= 0


def test_overtaking_robot_passes_the_slow_walker():
    """The planner (0.25 m/s nominal) must get ahead of the 0.1 m/s walker, not trail it to the goal."""
    episode = run_episode(load_scenario("overtaking"), shield=False)
    trace = episode.trace
    lead = float(np.max(trace.robot_poses[:, 0] - trace.obstacle_positions[:, 0, 0]))
    assert lead > 0.5, (
        f"the robot never got ahead of the walker (best lead {lead:.2f} m; "
        f"time to goal {episode.metrics['time_to_goal_s']} s)"
    )


def test_overtaking_behind_the_shield_reaches_the_goal_without_being_the_one_moving_into_the_walker():
    # Known cost of the shield's defaults (person_accel_mps2 = 1 m/s²): passing a walker at the
    # corridor's width is not admissible, so the robot trails it (~70 s instead of ~29 s; with
    # person_accel_mps2 = 0.5 it passes in ~30 s). Kept visible here rather than tuned away.
    metrics = _episode("overtaking").metrics
    assert metrics["reached_goal"] and not metrics["at_fault_collision"], metrics
    assert metrics["shield"] is True and metrics["time_to_goal_s"] < load_scenario("overtaking").duration_s


def test_robot_outside_the_corridor_facing_outwards_turns_back_instead_of_standing():
    # After an escape (group-0194 of the mixed suite) the robot stood 0.13 m outside the corridor,
    # facing 0.05 rad outwards, with everyone gone: every roll-out of the way back first swung
    # further out, so the planner stopped for the rest of the episode.
    from viapath import DesignatedPath, Observation, Obstacles, RobotState
    from viapath.planning import make_planner

    path = DesignatedPath([[0, 0], [7.8118, 0]], half_width_m=1.3622)
    planner = make_planner("viapath", path, nominal_speed_mps=0.2572)
    people_leaving = Obstacles(
        positions=[[-3.7, y] for y in (1.2, 0.5, -0.2, -0.9)], velocities=[[-0.43, 0.0]] * 4, radii_m=[0.25] * 4
    )
    robot = RobotState(position=np.array([1.33, -1.49]), heading_rad=-0.05, speed_mps=0.0)
    decision = planner.plan(Observation(time_s=0.0, robot=robot, obstacles=people_leaving))
    assert decision.plan.status != "stop"
    assert decision.command.turn_rate_radps > 0.0  # towards the corridor (left)


GROUP_ABREAST_Y = (1.1905, 0.4913, -0.2078, -0.9069)
GROUP_ABREAST_HALF_WIDTH_M = 1.3622


@pytest.fixture(scope="module")
def group_abreast():
    from viapath.scenarios.loader import scenario_from_dict

    group = [{"start": [13.56, y], "velocity": [-0.4312, 0.0], "radius": 0.25} for y in GROUP_ABREAST_Y]
    scenario = scenario_from_dict(
        {
            "name": "group-abreast",
            "duration_s": 76.0,
            "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.2572, "radius": 0.25},
            "path": {"waypoints": [[0.0, 0.0], [7.8118, 0.0]], "half_width": GROUP_ABREAST_HALF_WIDTH_M},
            "obstacles": group,
        }
    )
    return run_episode(scenario)


def test_group_abreast_head_on_robot_reaches_the_goal_not_at_fault(group_abreast):
    metrics = group_abreast.metrics
    assert metrics["reached_goal"], metrics
    assert not metrics["at_fault_collision"], metrics


def test_group_abreast_filling_the_corridor_meets_the_robot_inside_it_and_at_rest(group_abreast):
    # The group (four abreast, 0.7 m apart) fills the corridor: wherever the robot's centre is across it,
    # some person's disc overlaps the robot's (checked on a fine grid). A robot that keeps to the corridor
    # (a hard constraint) cannot let it pass; the decision is that it is met inside the corridor and at rest.
    across = np.linspace(-GROUP_ABREAST_HALF_WIDTH_M, GROUP_ABREAST_HALF_WIDTH_M, 2001)
    gaps = np.min(np.abs(across[:, None] - np.array(GROUP_ABREAST_Y)[None]), axis=1)
    assert np.all(gaps < 0.25 + 0.25), "the premise: no centre in the corridor clears the group"
    metrics, trace = group_abreast.metrics, group_abreast.trace
    assert metrics["time_outside_corridor_s"] == 0.0, metrics
    assert not metrics["at_fault_collision"], metrics
    offsets = trace.robot_poses[:, None, :2] - trace.obstacle_positions
    touching = np.any(np.hypot(offsets[..., 0], offsets[..., 1]) < 0.5, axis=1)
    assert touching.any(), "the group must reach the robot (else the scenario no longer tests this)"
    onsets = np.flatnonzero(touching[1:] & ~touching[:-1]) + 1
    assert np.all(trace.robot_speeds_mps[onsets - 1] == 0.0), trace.robot_speeds_mps[onsets - 1]


def test_l_corner_bypasses_the_occupied_corner_and_keeps_the_junction_rule_without_the_person():
    from viapath.path import SubgoalPolicy

    scenario = load_scenario("l-corner")
    corner = np.asarray(scenario.path.waypoints[1])
    with_person = run_episode(scenario)
    alone = run_episode(scenario.model_copy(update={"obstacles": []}))
    for episode in (with_person, alone):
        assert episode.metrics["reached_goal"] and not episode.metrics["collision"], episode.metrics
        assert episode.metrics["time_outside_corridor_s"] == 0.0, episode.metrics
    closest = [np.hypot(*(e.trace.robot_poses[:, :2] - corner).T).min() for e in (with_person, alone)]
    assert closest[1] <= SubgoalPolicy().reach_threshold_m + 0.05  # drives to the corner, then turns
    assert closest[0] > 0.5  # gives the corner up to the person and cuts inside it
