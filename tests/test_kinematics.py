"""The vectorised roll-out the planner uses must move exactly like the simulated robot."""

import numpy as np
from hypothesis import given, settings, strategies as st

from viapath.kinematics import UnicycleState, rollout, step
from viapath.observation import Command, MotionLimits

finite = lambda a, b: st.floats(a, b, allow_nan=False, allow_infinity=False)  # noqa: E731


@settings(max_examples=60, deadline=None, derandomize=True)
@given(heading=finite(-3.2, 3.2), speed=finite(0, 0.6), turn=finite(-2, 2),
       commands=st.lists(st.tuples(finite(-0.2, 0.8), finite(-3, 3)), min_size=1, max_size=6))
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
@given(heading=finite(-3.2, 3.2), speed=finite(0, 0.6), turn=finite(-2, 2), tx=finite(-3, 3), ty=finite(-3, 3),
       planned_speed=finite(0, 0.7))
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
