"""The escape's progress (``escape_progress_s``): when several escape commands stay clear of everyone over their
roll-out and progress counts for more than the calm escape's continuity, the one that gets the robot on towards its
subgoal wins over keeping last cycle's command; by default progress is a tie-break and last cycle's command wins.

The situation: the robot stands on the path 4 m short of its subgoal, a person walks straight at it from the left
(standing is hit within the horizon, so the robot escapes), and last cycle's escape command was a sharp right turn
(back the way it came). Driving on along the path and turning right both stay clear; the calm escape's continuity
keeps the turn unless progress counts for more than a tie-break. Each verdict of "clear" is checked here by dense
sampling of the drive's roll-out against the person's straight walk, independently of the planner's geometry.
"""

from __future__ import annotations

import math

import numpy as np

from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.observation import Command
from viapath.planning import make_planner
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.escape import stop_or_escape

PATH = DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0)
ROBOT = np.array([2.0, 0.0])
PERSON, PERSON_VELOCITY, PERSON_RADIUS = np.array([2.0, 2.6]), np.array([0.0, -0.8]), 0.25
PREVIOUS = Command(0.3, -2.0)  # last cycle's escape: a sharp right turn


def _escape(**options):
    planner = make_planner("viapath", PATH, nominal_speed_mps=0.3, options=options)
    observation = Observation(
        0.0,
        RobotState(ROBOT, 0.0, 0.0, 0.0),
        Obstacles(PERSON[None], PERSON_VELOCITY[None], np.array([PERSON_RADIUS])),
    )
    situation = planner.situation(observation)
    checks = LegChecks.of(situation, planner.config, planner.subgoals, planner.subgoal_policy, 0.25)
    return stop_or_escape(checks, planner.limits, planner.config, PREVIOUS), planner


def _drive(command: Command, limits, seconds: float, dt: float = 0.005) -> np.ndarray:
    """The robot's centre (K, 2) driving ``command`` from rest at the drive's limits, sampled every ``dt``."""
    x, y, heading, speed, turn = *ROBOT, 0.0, 0.0, 0.0
    points = []
    for _ in range(int(round(seconds / dt))):
        speed += float(np.clip(command.speed_mps - speed, -limits.max_accel_mps2 * dt, limits.max_accel_mps2 * dt))
        turn += float(
            np.clip(
                command.turn_rate_radps - turn, -limits.max_turn_accel_radps2 * dt, limits.max_turn_accel_radps2 * dt
            )
        )
        heading += turn * dt
        x, y = x + speed * math.cos(heading) * dt, y + speed * math.sin(heading) * dt
        points.append((x, y))
    return np.array(points)


def test_an_escape_that_stays_clear_drives_on_towards_the_subgoal_when_progress_counts():
    """With escape_progress_s above the calm escape's continuity, the escape drives on along the path."""
    decision, planner = _escape(escape_progress_s=5.0)
    assert decision.plan.status == "escape"  # standing is hit: the person walks onto the robot's spot
    command = decision.command
    seconds = planner.config.escape_s
    points = _drive(command, planner.limits, seconds)
    times = np.arange(1, len(points) + 1) * 0.005
    person = PERSON[None] + times[:, None] * PERSON_VELOCITY[None]
    gap = np.hypot(*(points - person).T) - PERSON_RADIUS - planner.robot_radius_m
    assert gap.min() > planner.config.safety_margin_m  # clear of the person over the whole roll-out
    progress = points[-1, 0] - ROBOT[0]
    assert progress >= 0.6  # on along the path: at least 0.2 m/s of progress over the 3 s roll-out
    assert np.all(np.abs(points[:, 1]) <= PATH.half_widths_m[0])  # inside the corridor


def test_with_progress_a_tie_break_the_escape_keeps_turning_back():
    """The same situation with progress a mere tie-break (0.01 s per m/s, the default): the calm escape keeps
    last cycle's turn and the robot makes less than half the progress."""
    decision, planner = _escape()
    assert planner.config.escape_progress_s == 0.01
    assert decision.plan.status == "escape"
    points = _drive(decision.command, planner.limits, planner.config.escape_s)
    assert points[-1, 0] - ROBOT[0] < 0.3
