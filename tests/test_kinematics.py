"""The roll-outs of the planner (the compiled track, the escape's roll-out as the tests specify it) move exactly
like the simulated robot."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from tests._core_helpers import rollout
from viapath.kinematics import UnicycleState, step
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
    from viapath.kinematics import steer_towards

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
    from viapath.kinematics import steer_towards

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


def track(state, target, speed_mps, limits, dt_s, steps, heading_gain=2.5):
    """The compiled roll-out's positions (:func:`viapath.planning.viapath.rollout.track`) of steering from ``state``."""
    from viapath.planning.viapath import rollout

    return rollout.track(
        float(state.x), float(state.y), float(state.heading_rad), float(state.speed_mps), float(state.turn_rate_radps),
        float(target[0]), float(target[1]), float(speed_mps), float(limits.max_speed_mps),
        float(limits.max_turn_rate_radps), float(limits.max_accel_mps2), float(limits.max_turn_accel_radps2),
        float(dt_s), int(steps), float(heading_gain),
    )  # fmt: skip
