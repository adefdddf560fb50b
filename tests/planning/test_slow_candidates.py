"""The slow/wait candidates against their definition (candidates.py, "Slow / wait"), on the paper's side case:
each slow leg (standing, the creep speed or a speed of the set below nominal, for each slow time) goes on at the
nominal speed, or at the slowest faster speed of the set whose leg is free when the nominal one's is not; and in
the closed loop the robot slows down rather than standing, oracle and laser."""

from __future__ import annotations

import numpy as np
import pytest

from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.planning import make_planner
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.critics import Critic
from viapath.scenarios import load_scenario
from viapath.sim.loop import run_episode


class _Recorder(Critic):
    """A critic that costs nothing and keeps the candidates it is shown (the planner's own tree of the cycle)."""

    name = "recorder"

    def __init__(self) -> None:
        self.seen: list = []

    def score(self, candidates, context):
        self.seen.append(candidates)
        return np.zeros(len(candidates))


def _side_case(x_m: float, person_y_m: float):
    path = DesignatedPath([[0.0, 0.0], [5.0, 0.0]], half_width_m=1.0)
    planner = make_planner("viapath", path, nominal_speed_mps=0.2)
    recorder = _Recorder()
    planner.critics = (*planner.critics, recorder)
    people = Obstacles(np.array([[1.0, person_y_m]]), np.array([[0.0, 0.3]]), np.array([0.25]))
    observation = Observation(0.0, RobotState(np.array([x_m, 0.0]), 0.0, 0.1, 0.0, 0.25), people)
    situation = planner.situation(observation)
    checks = LegChecks.of(situation, planner.config, planner.subgoals, planner.subgoal_policy, 0.25)
    speeds, nominal_index = planner.speed_set(0.1)
    planner.plan(observation)
    (candidates,) = recorder.seen
    planner.reset()
    planner.critics = planner.critics[:-1]  # without the recorder again
    return planner, checks, speeds, nominal_index, candidates, observation


@pytest.mark.parametrize(("x_m", "person_y_m"), [(0.0, -1.0), (0.2, -0.5), (0.3, -0.1)])
def test_a_slow_leg_goes_on_at_the_slowest_free_speed_from_the_nominal_one_up(x_m, person_y_m):
    planner, checks, speeds, nominal_index, candidates, _ = _side_case(x_m, person_y_m)
    slow = np.flatnonzero(candidates.slow_s > 0)
    assert len(slow) > 0
    after_speeds = speeds[speeds >= speeds[nominal_index] - 1e-9]
    direction = (checks.subgoal - checks.position) / np.hypot(*(checks.subgoal - checks.position))
    legs = [(float(candidates.slow_s[k]), float(candidates.slow_speed_mps[k])) for k in slow]
    assert len(set(legs)) == len(legs)  # one candidate per slow leg
    for k, (slow_s, slow_speed) in zip(slow, legs):
        end = checks.position + direction * slow_speed * slow_s
        n = len(after_speeds)
        free = checks.goal_legs(end[None].repeat(n, axis=0), np.full(n, slow_s), after_speeds, np.inf)[2]
        assert candidates.speed_mps[k] == after_speeds[np.argmax(free)], (slow_s, slow_speed)
    # The slow speeds: standing, the creep speed and the set's speeds below nominal (0.1 m/s and the current).
    assert {round(v, 6) for _, v in legs} <= {0.0, planner.config.creep_speed_mps, 0.1}
    assert planner.config.creep_speed_mps in {round(v, 6) for _, v in legs}


@pytest.mark.parametrize("perception", ["oracle", "laser"])
def test_the_side_case_slows_to_a_creep_and_never_stands(perception):
    # The paper: the robot slows to about 0.1 m/s, lets the person cross, and resumes 0.2 m/s.
    episode = run_episode(load_scenario("paper-side"), perception=perception, seed=0)
    metrics, speeds = episode.metrics, episode.trace.robot_speeds_mps
    assert metrics["reached_goal"] and not metrics["collision"]
    before_goal = speeds[:-1]
    assert before_goal.min() >= 0.05 - 1e-9 and before_goal.min() <= 0.15
    assert speeds[-20:-1].max() >= 0.19


def test_without_the_creep_and_the_standing_cost_the_side_case_stands():
    # What the two options change: Eq. 1 ties standing with slowing down and the stand comes first.
    scenario = load_scenario("paper-side")
    params = {**scenario.planner.params, "creep_speed_mps": 0.0, "standing_cost": 0.0}
    scenario = scenario.model_copy(update={"planner": scenario.planner.model_copy(update={"params": params})})
    speeds = run_episode(scenario, seed=0).trace.robot_speeds_mps
    assert speeds[:-1].min() == 0.0
