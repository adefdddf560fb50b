"""The vectorised roll-out the planner uses must move exactly like the simulated robot."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from viapath.kinematics import UnicycleState, rollout, step
from viapath.observation import Command, MotionLimits

finite = lambda a, b: st.floats(a, b, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    heading=finite(-3.2, 3.2),
    speed=finite(0, 0.6),
    turn=finite(-2, 2),
    commands=st.lists(st.tuples(finite(-0.2, 0.8), finite(-3, 3)), min_size=1, max_size=6),
)
def test_rollout_equals_stepping_the_robot(heading, speed, turn, commands):
    limits = MotionLimits()
    start = UnicycleState(0.3, -0.2, heading, speed, turn)
    positions = rollout(start, np.array(commands), limits, 0.1, 15)
    for k, (v, w) in enumerate(commands):
        state = start
        for s in range(15):
            state = step(state, Command(v, w), limits, 0.1)
            np.testing.assert_allclose(positions[k, s], [state.x, state.y], atol=1e-9)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    heading=finite(-3.2, 3.2),
    speed=finite(0, 0.6),
    turn=finite(-2, 2),
    tx=finite(-3, 3),
    ty=finite(-3, 3),
    planned_speed=finite(0, 0.7),
)
def test_tracking_rollout_equals_the_closed_loop(heading, speed, turn, tx, ty, planned_speed):
    from viapath.kinematics import steer_towards, track

    limits = MotionLimits()
    start = UnicycleState(0.0, 0.0, heading, speed, turn)
    positions = track(start, (tx, ty), planned_speed, limits, 0.1, 20)
    state = start
    for k in range(20):
        command = Command(*steer_towards(state.x, state.y, state.heading_rad, tx, ty, planned_speed, limits))
        state = step(state, command, limits, 0.1)
        np.testing.assert_allclose(positions[k], [state.x, state.y], atol=1e-9)


def test_track_is_bit_for_bit_the_closed_loop():
    """``track`` inlines steer_towards and the arcs for speed: every position must be exactly what the
    controller and :func:`step` give (2 000 seeded cases: headings all round, targets near and far,
    the target at the robot, planned speeds 0 and above the limit, other limits, steps of other sizes)."""
    from viapath.kinematics import steer_towards, track

    rng = np.random.default_rng(16)
    for case in range(2000):
        limits = MotionLimits() if case % 4 else MotionLimits(*rng.uniform([0.2, 0.2, 0.5, 1.0], [1.5, 2.0, 3.0, 9.0]))
        start = UnicycleState(
            *rng.uniform(-2, 2, 2),
            rng.uniform(-3.3, 3.3),
            rng.uniform(0, limits.max_speed_mps),
            rng.uniform(-limits.max_turn_rate_radps, limits.max_turn_rate_radps),
        )
        kind = case % 10
        target = (start.x, start.y) if kind == 0 else (start.x + 1e-10, start.y) if kind == 1 else rng.uniform(-4, 4, 2)
        planned = 0.0 if kind == 2 else rng.uniform(0.6, 1.2) if kind == 3 else rng.uniform(0, 0.6)
        dt, steps, gain = (
            (0.1, 20, 2.5) if case % 3 else (rng.uniform(0.02, 0.3), int(rng.integers(1, 40)), rng.uniform(0.5, 5))
        )
        positions = track(start, target, planned, limits, dt, steps, gain)
        state, expected = start, []
        for _ in range(steps):
            command = Command(
                *steer_towards(
                    state.x, state.y, state.heading_rad, float(target[0]), float(target[1]), planned, limits, gain
                )
            )
            state = step(state, command, limits, dt)
            expected.append((state.x, state.y))
        assert positions.shape == (steps, 2)
        assert np.array_equal(positions.view(np.int64), np.array(expected).view(np.int64)), f"case {case}"


def _rollout_reference(state, commands, limits, dt_s, steps):
    """:func:`rollout` as it was written first (np.clip, every sine and cosine taken where it is used)."""
    commands = np.asarray(commands, dtype=float).reshape(-1, 2)
    v_cmd = np.clip(commands[:, 0], 0.0, limits.max_speed_mps)
    w_cmd = np.clip(commands[:, 1], -limits.max_turn_rate_radps, limits.max_turn_rate_radps)
    ramp = np.arange(1, steps + 1)
    speed0, turn0 = float(state.speed_mps), float(state.turn_rate_radps)
    dv, dw = limits.max_accel_mps2 * dt_s * ramp, limits.max_turn_accel_radps2 * dt_s * ramp
    speed = speed0 + np.clip((v_cmd - speed0)[:, None], -dv, dv)
    turn = turn0 + np.clip((w_cmd - turn0)[:, None], -dw, dw)
    heading_after = float(state.heading_rad) + np.cumsum(turn * dt_s, axis=1)
    heading_before = np.concatenate(
        [np.full((len(commands), 1), float(state.heading_rad)), heading_after[:, :-1]], axis=1
    )
    straight = np.abs(turn) < 1e-9
    radius = speed / np.where(straight, 1.0, turn)
    dx = np.where(
        straight, speed * dt_s * np.cos(heading_before), radius * (np.sin(heading_after) - np.sin(heading_before))
    )
    dy = np.where(
        straight, speed * dt_s * np.sin(heading_before), -radius * (np.cos(heading_after) - np.cos(heading_before))
    )
    positions = np.empty((len(commands), steps, 2))
    positions[..., 0] = float(state.x) + np.cumsum(dx, axis=1)
    positions[..., 1] = float(state.y) + np.cumsum(dy, axis=1)
    return positions


def test_rollout_is_bit_for_bit_its_first_form():
    """:func:`rollout` takes each sine and cosine once and clamps with two ufuncs: the positions must be
    exactly those of its first form (1 000 seeded cases: the escape's fan and random commands, commands
    outside the limits, standing and turning on the spot, other limits and step counts)."""
    rng = np.random.default_rng(6)
    fan = np.stack([grid.ravel() for grid in np.meshgrid([0.0, 0.1, 0.2, 0.3, 0.4, 0.5], np.linspace(-2, 2, 9))], 1)
    for case in range(1000):
        limits = MotionLimits() if case % 3 else MotionLimits(*rng.uniform([0.2, 0.2, 0.5, 1.0], [1.5, 2.0, 3.0, 9.0]))
        start = UnicycleState(
            *rng.uniform(-5, 5, 2),
            rng.uniform(-3.3, 3.3),
            rng.uniform(0, limits.max_speed_mps),
            rng.uniform(-limits.max_turn_rate_radps, limits.max_turn_rate_radps) if case % 5 else 0.0,
        )
        commands = fan if case % 2 else rng.uniform([-0.3, -3.0], [1.0, 3.0], (int(rng.integers(1, 60)), 2))
        dt, steps = (0.1, 30) if case % 4 else (rng.uniform(0.02, 0.3), int(rng.integers(1, 50)))
        got = rollout(start, commands, limits, dt, steps)
        expected = _rollout_reference(start, commands, limits, dt, steps)
        assert np.array_equal(got.view(np.int64), expected.view(np.int64)), f"case {case}"


def test_rollout_per_turn_command_is_bit_for_bit_per_command():
    """With ``turns`` (the escape's fan) the headings, sines and cosines are made once per distinct turn
    command: the positions must be exactly those made per command (600 seeded cases: the fan, random
    commands sharing a few turn rates, turn rates outside the limits)."""
    rng = np.random.default_rng(16)
    fan = np.stack([grid.ravel() for grid in np.meshgrid([0.0, 0.1, 0.2, 0.3, 0.4, 0.5], np.linspace(-2, 2, 9))], 1)
    for case in range(600):
        limits = MotionLimits() if case % 3 else MotionLimits(*rng.uniform([0.2, 0.2, 0.5, 1.0], [1.5, 2.0, 3.0, 9.0]))
        start = UnicycleState(
            *rng.uniform(-5, 5, 2),
            rng.uniform(-3.3, 3.3),
            rng.uniform(0, limits.max_speed_mps),
            rng.uniform(-limits.max_turn_rate_radps, limits.max_turn_rate_radps) if case % 5 else 0.0,
        )
        if case % 2:
            commands = fan
        else:
            count = int(rng.integers(1, 60))
            commands = np.stack([rng.uniform(-0.3, 1.0, count), rng.choice(rng.uniform(-3.0, 3.0, 4), count)], 1)
        row_turns, turn_rows = np.unique(commands[:, 1], return_inverse=True)
        dt, steps = (0.1, 30) if case % 4 else (rng.uniform(0.02, 0.3), int(rng.integers(1, 50)))
        got = rollout(start, commands, limits, dt, steps, (row_turns, turn_rows.reshape(-1)))
        expected = rollout(start, commands, limits, dt, steps)
        assert np.array_equal(got.view(np.int64), expected.view(np.int64)), f"case {case}"
