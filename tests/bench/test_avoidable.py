"""viapath.bench.avoidable, the search that says whether any command sequence from a person's appearance
avoids an at-fault contact: its drive model and at-fault rule replay real episodes exactly, and on
constructed cases it finds the braking that avoids a contact and proves one that no robot could avoid."""

from types import SimpleNamespace

import numpy as np
import pytest

from viapath.bench.avoidable import check_replay, contact_speeds, judge, search
from viapath.kinematics import UnicycleState, step
from viapath.observation import Command, MotionLimits
from viapath.sim.metrics import at_fault_onsets


def _head_on_trace(appear_distance_m, robot_speed_mps=0.3, person_speed_mps=1.6, steps=60, appear_step=10, brake=True):
    """The robot drives along x at ``robot_speed_mps``; a person appears ``appear_distance_m`` ahead at
    ``appear_step`` and walks straight at it. ``brake``: the robot brakes hard from the appearance;
    otherwise it drives on."""
    dt, limits = 0.1, MotionLimits()
    state = UnicycleState(0.0, 0.0, 0.0, robot_speed_mps, 0.0)
    poses, speeds, turns = [], [], []
    person = np.full((steps + 1, 1, 2), np.nan)
    start_x = None
    for k in range(steps + 1):
        poses.append((state.x, state.y, state.heading_rad))
        speeds.append(state.speed_mps)
        turns.append(state.turn_rate_radps)
        if k == appear_step:
            start_x = state.x + appear_distance_m
        if start_x is not None:
            person[k, 0] = start_x - person_speed_mps * dt * (k - appear_step), 0.05
        command = Command(0.0, 0.0) if (brake and start_x is not None) else Command(robot_speed_mps, 0.0)
        state = step(state, command, limits, dt)
    return SimpleNamespace(
        dt_s=dt,
        robot_poses=np.array(poses),
        robot_speeds_mps=np.array(speeds),
        robot_turn_rates_radps=np.array(turns),
        obstacle_positions=person,
        obstacle_radii_m=np.array([0.3]),
        robot_radius_m=0.25,
        times_s=dt * np.arange(steps + 1),
        walls=np.zeros((0, 2, 2)),
    )


def test_a_contact_that_braking_at_the_appearance_avoids_is_avoidable():
    # A slow walker appears 4 m ahead; the robot drives on into them at 0.6 m/s: at fault.
    trace = _head_on_trace(4.0, robot_speed_mps=0.6, person_speed_mps=0.3, brake=False)
    assert at_fault_onsets(trace).any()
    (verdict,) = judge(trace, MotionLimits())
    assert verdict.avoidable and verdict.reason.startswith("braking 0.0 s after")
    assert verdict.appeared_before_onset_s > 3.0


def test_a_person_who_appears_inside_the_braking_distance_and_runs_in_is_unavoidable():
    trace = _head_on_trace(1.0)
    assert at_fault_onsets(trace).any()  # the hard-braking robot itself is at fault
    (verdict,) = judge(trace, MotionLimits())
    assert not verdict.avoidable and verdict.reason == "no sequence avoids it"
    assert verdict.appeared_before_onset_s < 0.5
    # The same person 2 m away leaves time to be at rest when they arrive; a slow robot avoids it at 1 m.
    assert search(_head_on_trace(2.0, brake=False), MotionLimits(), 10, 13)[0] is True
    assert search(_head_on_trace(1.0, robot_speed_mps=0.12), MotionLimits(), 10, 12)[0] is True


def test_a_search_over_budget_counts_as_avoidable():
    trace = _head_on_trace(1.0)
    (verdict,) = judge(trace, MotionLimits(), max_branches=10)
    assert verdict.avoidable and verdict.reason.startswith("budget")


def test_reactive_people_count_as_avoidable():
    (verdict,) = judge(_head_on_trace(1.0), MotionLimits(), reactive=True)
    assert verdict.avoidable and "reactive" in verdict.reason


def test_the_search_replays_constructed_traces_and_agrees_with_the_metric():
    for distance in (0.9, 1.0, 1.4, 4.0):
        for brake in (True, False):
            trace = _head_on_trace(distance, brake=brake)
            for first in (0, 10, 12):
                check_replay(trace, MotionLimits(), first)  # raises if poses or onsets differ


def test_a_model_off_the_trace_is_caught():
    trace = _head_on_trace(1.0)
    trace.robot_poses = trace.robot_poses.copy()
    trace.robot_poses[20, 0] += 0.01
    with pytest.raises(ValueError, match="drive model"):
        check_replay(trace, MotionLimits(), 10)


def test_the_search_replays_a_simulated_episode_with_contacts():
    from viapath.scenarios import scenario_from_dict
    from viapath.sim.loop import run_episode

    scenario = scenario_from_dict(
        {
            "name": "walk-in",
            "dt_s": 0.1,
            "duration_s": 12.0,
            "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.5, "radius": 0.25},
            "path": {"waypoints": [[0.0, 0.0], [10.0, 0.0]], "half_width": 1.0},
            "obstacles": [
                {"start": [6.0, 0.0], "velocity": [-1.2, 0.0], "radius": 0.3},
                {"start": [3.0, 2.5], "velocity": [0.0, -0.9], "radius": 0.3, "start_time_s": 1.0},
            ],
        }
    )
    episode = run_episode(scenario, planner="follow", shield=False)
    trace = episode.trace
    assert episode.metrics["collision"]
    limits = MotionLimits(**scenario.robot.limits.model_dump())
    for first in (0, 7, 30):
        check_replay(trace, limits, first)
    speeds = contact_speeds(trace)
    assert speeds and all(s >= 0.0 for _, _, s in speeds)
    onset = np.nonzero(at_fault_onsets(trace))[0]
    assert {round(float(trace.times_s[k]), 6) for k in onset} <= {round(t, 6) for t, _, _ in speeds}


def test_the_report_sums_the_verdicts_and_lists_the_at_fault_episodes():
    from viapath.bench.report import at_fault_lines, summarize

    base = {"planner": "viapath", "shield": "on", "error": "", "reached_goal": True, "collision": True}
    base["at_fault_collision_seen_1s"] = False
    rows = [
        {
            **base,
            "scenario": "a",
            "at_fault_collision": True,
            "at_fault_avoidable": 1,
            "at_fault_unavoidable": 1,
            "contact_speeds": "1.0s:person3:0.30 2.0s:person4:0.06",
            "at_fault_detail": "person 3 ...",
        },
        {
            **base,
            "scenario": "b",
            "at_fault_collision": False,
            "at_fault_avoidable": 0,
            "at_fault_unavoidable": 0,
            "contact_speeds": "4.0s:static:0.50",
            "at_fault_detail": "",
        },
    ]
    (entry,) = summarize(rows)
    assert entry["at_fault_avoidable"] == 1 and entry["at_fault_unavoidable"] == 1
    assert entry["contact_speed_max_mps"] == 0.5 and entry["contact_speed_median_mps"] == 0.3
    (line,) = at_fault_lines(rows)
    assert " a: 1 avoidable, 1 unavoidable; person 3" in line
