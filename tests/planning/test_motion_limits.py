"""Property: whatever the scene and the planner ask for, the simulated drive respects the robot's
limits every step (speed, acceleration, turn rate, turn acceleration), and planners ask for no more
than the speed and turn rate the robot has."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from viapath.observation import Command, MotionLimits
from viapath.scenarios.loader import scenario_from_dict
from viapath.sim import robot as kinematics
from viapath.sim.loop import run_episode

EPS = 1e-9

limits_strategy = st.fixed_dictionaries(
    {
        "max_speed_mps": st.floats(0.3, 1.0),
        "max_accel_mps2": st.floats(0.1, 2.0),
        "max_turn_rate_radps": st.floats(0.3, 3.0),
        "max_turn_accel_radps2": st.floats(0.5, 10.0),
    }
)


@st.composite
def small_scenarios(draw):
    limits = draw(limits_strategy)
    speed = draw(st.floats(0.1, 0.3)) * min(1.0, limits["max_speed_mps"] / 0.3)
    n = draw(st.integers(0, 3))
    obstacles = []
    for _ in range(n):
        # Anywhere around the 5 m path, but never on top of the robot at the start.
        x = draw(st.floats(-1.0, 6.0))
        y = draw(st.floats(-2.0, 2.0))
        if np.hypot(x, y) < 0.9:
            x += 1.5
        obstacles.append(
            {
                "start": [x, y],
                "velocity": [draw(st.floats(-0.6, 0.6)), draw(st.floats(-0.6, 0.6))],
                "radius": draw(st.floats(0.15, 0.35)),
            }
        )
    bend = draw(st.booleans())
    waypoints = [[0.0, 0.0], [3.0, 0.0], [3.0, 2.5]] if bend else [[0.0, 0.0], [5.0, 0.0]]
    data = {
        "name": "random-limits",
        "robot": {
            "start": [0.0, 0.0],
            "heading": draw(st.floats(-0.5, 0.5)),
            "speed": speed,
            "radius": 0.25,
            "limits": limits,
        },
        "path": {"waypoints": waypoints, "half_width": draw(st.floats(0.6, 1.5))},
        "obstacles": obstacles,
        "duration_s": 12.0,
    }
    return scenario_from_dict(data)


def _check_drive(trace, limits: MotionLimits) -> None:
    dt = trace.dt_s
    v = trace.robot_speeds_mps
    w = trace.robot_turn_rates_radps
    assert np.all(np.isfinite(v)) and np.all(np.isfinite(w))
    assert v.min() >= -EPS
    assert np.abs(v).max() <= limits.max_speed_mps + EPS
    assert np.abs(w).max() <= limits.max_turn_rate_radps + EPS
    assert (np.abs(np.diff(v)) / dt).max(initial=0.0) <= limits.max_accel_mps2 + EPS
    assert (np.abs(np.diff(w)) / dt).max(initial=0.0) <= limits.max_turn_accel_radps2 + EPS
    # The pose moves no further than the achieved speed allows.
    step = np.hypot(*np.diff(trace.robot_poses[:, :2], axis=0).T)
    assert np.all(step <= v[1:] * dt + EPS)


@settings(max_examples=30, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(
    scenario=small_scenarios(),
    planner=st.sampled_from(["viapath", "viapath", "viapath", "vo", "follow"]),
    noise=st.booleans(),
    seed=st.integers(0, 1000),
)
def test_every_step_respects_the_robot_limits(scenario, planner, noise, seed):
    episode = run_episode(
        scenario,
        planner=planner,
        seed=seed,
        position_noise_m=0.03 if noise else 0.0,
        velocity_noise_mps=0.05 if noise else 0.0,
    )
    trace = episode.trace
    limits = MotionLimits(**scenario.robot.limits.model_dump())
    _check_drive(trace, limits)
    # What the planner asked for: finite, forward, within speed and turn-rate limits.
    commands = trace.commands
    assert np.all(np.isfinite(commands))
    assert commands[:, 0].min() >= -EPS
    assert commands[:, 0].max() <= limits.max_speed_mps + EPS, f"{planner} commanded more than max speed"
    assert np.abs(commands[:, 1]).max() <= limits.max_turn_rate_radps + EPS, f"{planner} commanded too fast a turn"


finite = st.floats(-5.0, 5.0)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    limits=limits_strategy,
    speed=st.floats(0.0, 1.0),
    turn=finite,
    v_cmd=st.one_of(finite, st.just(np.nan)),
    w_cmd=st.one_of(finite, st.just(np.inf)),
    dt=st.floats(0.01, 0.5),
)
def test_limit_command_moves_by_at_most_one_step_of_acceleration(limits, speed, turn, v_cmd, w_cmd, dt):
    limits = MotionLimits(**limits)
    speed = min(speed, limits.max_speed_mps)
    turn = float(np.clip(turn, -limits.max_turn_rate_radps, limits.max_turn_rate_radps))
    state = kinematics.UnicycleState(0.0, 0.0, 0.0, speed, turn)
    new = kinematics.step(state, Command(v_cmd, w_cmd), limits, dt)
    assert 0.0 <= new.speed_mps <= limits.max_speed_mps + EPS
    assert abs(new.turn_rate_radps) <= limits.max_turn_rate_radps + EPS
    assert abs(new.speed_mps - speed) <= limits.max_accel_mps2 * dt + EPS
    assert abs(new.turn_rate_radps - turn) <= limits.max_turn_accel_radps2 * dt + EPS
    assert np.hypot(new.x, new.y) <= new.speed_mps * dt + EPS
