"""Smoothness metrics (issue 4) against hand-built traces with known acceleration, jerk and reversals."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from viapath.path import DesignatedPath
from viapath.sim.metrics import (
    accel_jerk,
    compute_metrics,
    plan_side,
    plan_switches,
    side_flips,
    smoothness_metrics,
    steering_reversals,
)

DT = 0.1


def _trace(speeds, turns, plan_speeds=None, sides=None):
    """A straight-line trace along +x with the given speed and turn-rate samples (one per step)."""
    speeds = np.asarray(speeds, dtype=float)
    k = len(speeds)
    x = np.concatenate([[0.0], np.cumsum(speeds[:-1] * DT)])
    cycles = k - 1
    plan_speeds = np.zeros(cycles) if plan_speeds is None else np.asarray(plan_speeds, dtype=float)
    sides = np.zeros(cycles, dtype=int) if sides is None else np.asarray(sides, dtype=int)
    return SimpleNamespace(
        scenario_name="synthetic",
        planner_name="none",
        perception_mode="oracle",
        dt_s=DT,
        path=DesignatedPath([[0.0, 0.0], [100.0, 0.0]], half_widths_m=[1.0]),
        robot_radius_m=0.25,
        times_s=np.arange(k) * DT,
        robot_poses=np.column_stack([x, np.zeros(k), np.zeros(k)]),
        robot_speeds_mps=speeds,
        robot_turn_rates_radps=np.asarray(turns, dtype=float),
        commands=np.zeros((k, 2)),
        obstacle_positions=np.zeros((k, 0, 2)),
        obstacle_velocities=np.zeros((k, 0, 2)),
        obstacle_radii_m=np.zeros(0),
        plan_speeds_mps=np.append(plan_speeds, 0.0),
        plan_status=["straight"] * cycles + ["end"],
        plan_sides=np.append(sides, 0),
        plan_times_ms=np.append(np.full(cycles, 0.1), np.nan),
        reached_goal=True,
    )


def test_constant_speed_has_no_acceleration_jerk_or_turning():
    m = smoothness_metrics(_trace(np.full(50, 0.2), np.zeros(50)))
    assert m == {
        "max_abs_accel_mps2": 0.0,
        "max_abs_jerk_mps3": 0.0,
        "max_abs_turn_rate_radps": 0.0,
        "steering_reversals": 0,
        "plan_switches": 0,
        "plan_side_flips": 0,
        "command_flips": 0,
        "escape_cycles": 0,
    }


def test_command_flips_count_speed_jumps_and_turn_reversals_against_brute_force():
    from viapath.sim.metrics import command_flips

    rng = np.random.default_rng(3)
    commands = np.column_stack([rng.choice([0.0, 0.1, 0.5, 0.6], 200), rng.choice([-2.0, -0.3, 0.0, 0.4, 2.0], 200)])
    expected = 0
    for (v0, w0), (v1, w1) in zip(commands[:-1], commands[1:]):
        expected += abs(v1 - v0) >= 0.25 or (w0 * w1 < 0 and abs(w0) >= 0.5 and abs(w1) >= 0.5)
    assert command_flips(commands) == expected > 0
    assert command_flips(np.tile([[0.3, 1.0]], (20, 1))) == 0


def test_linear_ramp_has_constant_accel_and_jerk_only_at_its_ends():
    # 0.2 m/s for 1 s, ramp up at 0.5 m/s² for 0.4 s (to 0.4 m/s), hold.
    speeds = np.concatenate([np.full(10, 0.2), 0.2 + 0.05 * np.arange(1, 5), np.full(10, 0.4)])
    accel, jerk = accel_jerk(speeds, DT)
    assert np.abs(accel).max() == pytest.approx(0.5)
    assert np.count_nonzero(np.abs(accel) > 1e-9) == 4
    # The acceleration switches 0 -> 0.5 and 0.5 -> 0 within one step each: |jerk| = 5 m/s³ twice.
    assert np.abs(jerk).max() == pytest.approx(5.0)
    assert np.count_nonzero(np.abs(jerk) > 1e-9) == 2
    m = smoothness_metrics(_trace(speeds, np.zeros(len(speeds))))
    assert m["max_abs_accel_mps2"] == pytest.approx(0.5)
    assert m["max_abs_jerk_mps3"] == pytest.approx(5.0)


def test_braking_counts_as_absolute_acceleration_and_bang_bang_jerk():
    # +0.8 m/s² then immediately -0.8 m/s²: jerk of 1.6 / 0.1 = 16 m/s³.
    speeds = [0.2, 0.28, 0.2, 0.2]
    m = smoothness_metrics(_trace(speeds, np.zeros(4)))
    assert m["max_abs_accel_mps2"] == pytest.approx(0.8)
    assert m["max_abs_jerk_mps3"] == pytest.approx(16.0)


def test_sinusoidal_speed_matches_analytic_accel_and_jerk():
    t = np.arange(0, 20, DT)
    amplitude, omega = 0.05, 1.0
    speeds = 0.3 + amplitude * np.sin(omega * t)
    m = smoothness_metrics(_trace(speeds, np.zeros(len(t))))
    assert m["max_abs_accel_mps2"] == pytest.approx(amplitude * omega, rel=0.01)
    assert m["max_abs_jerk_mps3"] == pytest.approx(amplitude * omega**2, rel=0.02)


def test_steering_reversals_ignore_small_values_between_signs():
    assert steering_reversals([0.0, 0.5, 0.5, -0.5, -0.5, 0.5]) == 2
    # Small wobble around zero between two left turns: no reversal.
    assert steering_reversals([0.5, 0.02, -0.04, 0.01, 0.6]) == 0
    # Left, a stretch of (almost) straight driving, then right: one reversal.
    assert steering_reversals([0.5, 0.0, 0.0, -0.03, 0.0, -0.5]) == 1
    # Noise below the threshold never counts.
    rng = np.random.default_rng(1)
    assert steering_reversals(rng.uniform(-0.049, 0.049, 200)) == 0
    assert steering_reversals([]) == 0
    assert steering_reversals([0.3, -0.3], threshold_radps=0.5) == 0


def test_weaving_turn_rate_counts_each_reversal_and_the_peak():
    t = np.arange(0, 10, DT)
    turns = 0.8 * np.sin(2 * np.pi * 0.3 * t + 0.1)  # 3 periods in 10 s: 6 zero crossings
    m = smoothness_metrics(_trace(np.full(len(t), 0.2), turns))
    assert m["steering_reversals"] == 5  # crossings at t = 1.61, 3.28, 4.94, 6.61, 8.28 s
    expected = int(np.count_nonzero(np.diff(np.sign(turns[np.abs(turns) > 0.05])) != 0))
    assert m["steering_reversals"] == expected
    assert m["max_abs_turn_rate_radps"] == pytest.approx(np.abs(turns).max())


def test_plan_side_of_a_chosen_polyline():
    assert plan_side([[0, 0], [5, 0]]) == 0  # straight to the subgoal
    assert plan_side([[0, 0], [2, 0.5], [5, 0]]) == 1  # via point to the left of robot -> subgoal
    assert plan_side([[0, 0], [2, -0.5], [5, 0]]) == -1
    assert plan_side([[0, 0], [2, 0.0], [5, 0]]) == 0
    # Relative to the line to the subgoal, not to the world x axis: subgoal north, via point west = left.
    assert plan_side([[1, 1], [0.5, 3], [1, 5]]) == 1
    assert plan_side(np.zeros((0, 2))) == 0


def test_plan_switches_count_side_and_speed_changes():
    sides = [0, 0, 1, 1, 1, 0, 0, -1, -1, 0]
    speeds = [0.2, 0.2, 0.2, 0.3, 0.3, 0.3, 0.2, 0.2, 0.2, 0.2]
    # changes at 2 (side), 3 (speed), 5 (side), 6 (speed), 7 (side), 9 (side); 5 and 6 separate cycles.
    assert plan_switches(sides, speeds) == 6
    # A change of side and speed in the same cycle is one switch.
    assert plan_switches([0, 1], [0.2, 0.3]) == 1
    # Sub-millimetre-per-second differences (the planner's resolution) are not switches.
    assert plan_switches([0, 0, 0], [0.2, 0.2004, 0.2]) == 0
    assert side_flips(sides) == 1  # left ... right, straight cycles in between ignored
    assert side_flips([1, -1, 1, -1]) == 3


def test_compute_metrics_includes_smoothness_and_ignores_the_final_row():
    sides = [0, 1, 1, -1, 0]
    plan_speeds = [0.2, 0.2, 0.3, 0.3, 0.2]
    trace = _trace([0.2, 0.2, 0.28, 0.3, 0.3, 0.3], [0.0, 0.4, 0.4, -0.4, 0.0, 0.0], plan_speeds, sides)
    m = compute_metrics(trace)
    for name in ("reached_goal", "collision", "min_clearance_m", "max_lateral_deviation_m"):
        assert name in m
    assert m["max_abs_accel_mps2"] == pytest.approx(0.8)
    assert m["max_abs_jerk_mps3"] == pytest.approx(8.0)  # 0 -> 0.8 -> 0.2 -> 0: largest step 0.8/0.1
    assert m["max_abs_turn_rate_radps"] == pytest.approx(0.4)
    assert m["steering_reversals"] == 1
    assert m["plan_switches"] == 4  # the "end" row (speed 0) is not a planning cycle
    assert m["plan_side_flips"] == 1


def test_trace_without_recorded_sides_counts_speed_changes_only():
    trace = _trace(np.full(5, 0.2), np.zeros(5), [0.2, 0.3, 0.3, 0.2])
    del trace.plan_sides
    assert smoothness_metrics(trace)["plan_switches"] == 2


def test_a_real_episode_records_the_chosen_side():
    from viapath.presets import preset_values
    from viapath.scenarios.loader import load_scenario
    from viapath.sim.loop import run_episode

    episode = run_episode(load_scenario("paper-front"), planner_overrides=preset_values("paper"))
    trace = episode.trace
    assert len(trace.plan_sides) == len(trace.plan_status)
    # Head-on: the paper's robot passes on the left (the preferred side), never on the right.
    assert 1 in trace.plan_sides and -1 not in trace.plan_sides
    assert episode.metrics["plan_side_flips"] == 0
    assert episode.metrics["max_abs_accel_mps2"] <= 0.8 + 1e-9
