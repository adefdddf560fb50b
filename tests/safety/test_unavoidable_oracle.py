"""benchmarks/unavoidable.py, the oracle that says whether any command sequence avoids an at-fault
contact: its drive model and at-fault rule agree with the simulator and the metric, and its verdict
turns from unavoidable to avoidable as a head-on person appears further away."""

import importlib.util
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from viapath.kinematics import UnicycleState, step
from viapath.observation import Command, MotionLimits
from viapath.sim.metrics import at_fault_onsets

_TOOL = Path(__file__).resolve().parents[2] / "benchmarks" / "unavoidable.py"


@pytest.fixture(scope="module")
def oracle():
    spec = importlib.util.spec_from_file_location("unavoidable", _TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _head_on_trace(
    appear_distance_m: float, robot_speed_mps=0.3, person_speed_mps=1.6, steps=40, appear_step=10, brake=True
):
    """The robot drives along x at ``robot_speed_mps`` and brakes hard (``brake``) from the step a person
    appears ``appear_distance_m`` ahead, walking straight at it (eth-0020's shape)."""
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
    )


def test_the_oracle_replays_the_trace_and_agrees_with_the_metric(oracle):
    for distance in (0.9, 1.0, 1.4):
        trace = _head_on_trace(distance)
        oracle.check_replay(trace, MotionLimits(), 10, 5)  # raises if poses or onsets differ
    trace = _head_on_trace(1.0)
    assert at_fault_onsets(trace).any()  # the hard-braking robot itself is at fault at 1.0 m


def test_a_person_appearing_close_is_unavoidable_and_one_further_away_is_not(oracle):
    limits = MotionLimits()
    near, tried = oracle.search(_head_on_trace(1.0), 10, 4, limits)
    far, _ = oracle.search(_head_on_trace(2.0), 10, 4, limits)
    assert tried == 15**4
    assert near == 0  # eth-0020's shape: braking from 0.3 m/s cannot reach 0.05 m/s in time
    assert far > 0  # 2 m leaves time to be at rest when the person arrives
    # The hard braking the trace itself did is among the sequences searched, and at 2 m it is not at fault.
    assert not at_fault_onsets(_head_on_trace(2.0)).any()


def test_a_slow_robot_avoids_what_a_fast_one_cannot(oracle):
    limits = MotionLimits()
    fast, _ = oracle.search(_head_on_trace(1.0, robot_speed_mps=0.3), 10, 4, limits)
    slow, _ = oracle.search(_head_on_trace(1.0, robot_speed_mps=0.12), 10, 4, limits)
    assert fast == 0 and slow > 0
