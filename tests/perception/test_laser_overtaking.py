"""The built-in overtaking (a walker at 0.1 m/s 1.5 m ahead) seen through the simulated lasers and the whole
laser chain, seeds 0-7: the planner does not flip between passing and trailing. The same runs as
``python benchmarks/noisy_overtaking.py --modes laser``."""

import pytest

from viapath.scenarios.loader import load_scenario
from viapath.sim.loop import run_episode

SEEDS = range(8)


@pytest.fixture(scope="module")
def laser_runs():
    scenario = load_scenario("overtaking")
    return [run_episode(scenario, perception="laser", seed=seed).metrics for seed in SEEDS]


def test_the_laser_overtaking_flips_at_most_12_times_without_contact_inside_the_corridor(laser_runs):
    flips = [m["command_flips"] for m in laser_runs]
    assert max(flips) <= 12, flips
    for seed, metrics in zip(SEEDS, laser_runs):
        assert metrics["perception"] == "laser"
        assert not metrics["collision"], (seed, metrics)
        assert metrics["time_outside_corridor_s"] == 0.0, (seed, metrics)
        assert metrics["reached_goal"], (seed, metrics)
