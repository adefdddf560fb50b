"""The built-in overtaking (a walker at 0.1 m/s 1.5 m ahead of the robot) with tracker-shaped noise, seeds 0-7:
detections with σ 0.03 m through the Kalman tracker (perception mode ``tracked``) and the simulated scanners with
the whole laser chain (``laser``). The same runs as ``python benchmarks/noisy_overtaking.py --modes tracked,laser``.

Trailing a walker when no pass fits is correct; flipping between trailing and passing is not: at most 12 command
flips (viapath.sim.metrics.command_flips) per run, no contact, never outside the corridor, at the goal."""

import pytest

from viapath.scenarios.loader import load_scenario
from viapath.sim.loop import run_episode

SEEDS = range(8)
MODES = ("tracked", "laser")


@pytest.fixture(scope="module")
def runs():
    scenario = load_scenario("overtaking")
    out = {}
    for mode in MODES:
        noise = {"position_noise_m": 0.03, "velocity_noise_mps": 0.0} if mode == "tracked" else {}
        out[mode] = [run_episode(scenario, perception=mode, seed=seed, **noise).metrics for seed in SEEDS]
    return out


@pytest.mark.parametrize("mode", MODES)
def test_tracker_noise_leaves_the_overtaking_safe_inside_the_corridor_and_at_the_goal(runs, mode):
    for seed, metrics in zip(SEEDS, runs[mode]):
        assert metrics["perception"] == mode
        assert not metrics["collision"], (seed, metrics)
        assert metrics["time_outside_corridor_s"] == 0.0, (seed, metrics)
        assert metrics["reached_goal"], (seed, metrics)
        assert metrics["track_samples"] > 0  # the planner was fed the tracker's estimates


@pytest.mark.parametrize("mode", MODES)
def test_tracker_noise_does_not_make_the_overtaking_flip(runs, mode):
    flips = [m["command_flips"] for m in runs[mode]]
    assert max(flips) <= 12, flips
