"""Contact kinds (viapath.bench.contact_kinds) on people whose course is known: walking straight at a standing
robot, turning towards it 1.5 s before and 0.5 s before the contact."""

import numpy as np
import pytest

from viapath.bench.contact_kinds import KINDS, classify_onset, forecast_gap, heading_change_deg

DT = 0.1
RADIUS_SUM = 0.5  # robot 0.25 + person 0.25
ROBOT = np.array([0.0, 0.0])


def walk(turn_before_s: float | None, steps: int = 60, speed: float = 1.0):
    """A person reaching the robot's disc at the last step: walking along -x and, ``turn_before_s`` before the
    contact, turning to walk straight down (-y) onto the robot, so the course before the turn passes
    ``speed * turn_before_s`` clear of touching; or (None) walking at the robot along the x axis all along.
    Positions and velocities (steps + 1, 2), the contact's step."""
    velocities = np.zeros((steps + 1, 2))
    positions = np.zeros((steps + 1, 2))
    if turn_before_s is None:
        end = np.array([RADIUS_SUM - 0.01, 0.0])  # overlapping by 1 cm at the last step
        velocities[:] = [-speed, 0.0]
    else:
        end = np.array([0.0, RADIUS_SUM - 0.01])
        turn_step = steps - int(round(turn_before_s / DT))
        velocities[:turn_step] = [-speed, 0.0]
        velocities[turn_step:] = [0.0, -speed]
    # integrate backwards from the end so the contact is at the last step exactly
    positions[steps] = end
    for k in range(steps - 1, -1, -1):
        positions[k] = positions[k + 1] - velocities[k] * DT
    return positions, velocities, steps


def test_the_forecast_gap_is_the_distance_of_closest_approach_less_the_radii():
    # Passing 1.5 m to the side of the robot: the gap is 1.5 - 0.5 = 1.0 m, at the sample nearest x = 0.
    gap = forecast_gap(np.array([2.0, 1.5]), np.array([-1.0, 0.0]), ROBOT, RADIUS_SUM, DT)
    assert gap == pytest.approx(1.0, abs=1e-9)
    assert np.isnan(forecast_gap(np.array([np.nan, 0.0]), np.array([-1.0, 0.0]), ROBOT, RADIUS_SUM, DT))
    assert heading_change_deg(np.array([1.0, 0.0]), np.array([0.0, 1.0])) == pytest.approx(90.0)
    assert heading_change_deg(np.array([0.0, 0.0]), np.array([0.0, 1.0])) == 0.0


def test_a_person_walking_straight_at_the_robot_is_a_contact_the_forecast_saw():
    positions, velocities, step = walk(None)
    kind, turn, gap_1, gap_2 = classify_onset(positions, velocities, ROBOT, step, DT, RADIUS_SUM)
    assert kind == KINDS[0]
    assert turn == pytest.approx(0.0)
    assert gap_1 < 0 and gap_2 < 0


def test_a_person_turning_at_the_robot_1_5_s_before_is_seen_by_the_forecast_of_1_s_before_only():
    positions, velocities, step = walk(1.5)
    kind, turn, gap_1, gap_2 = classify_onset(positions, velocities, ROBOT, step, DT, RADIUS_SUM)
    assert kind == KINDS[1]
    assert gap_1 < 0.05 < gap_2
    assert turn > 15.0


def test_a_person_turning_at_the_robot_0_5_s_before_is_missed_by_the_forecast():
    positions, velocities, step = walk(0.5)
    kind, _, gap_1, _ = classify_onset(positions, velocities, ROBOT, step, DT, RADIUS_SUM)
    assert kind == KINDS[2]
    assert gap_1 == pytest.approx(0.5 - 0.01, abs=1e-9)  # the forecast of 1 s before walks by 0.5 m above
