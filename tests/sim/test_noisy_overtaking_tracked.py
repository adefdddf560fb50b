"""The built-in overtaking (a walker at 0.1 m/s 1.5 m ahead of the robot) with tracker-shaped noise: detections
with σ 0.03 m through the Kalman tracker (perception mode ``tracked``), seeds 0-7. The same runs as
``python benchmarks/noisy_overtaking.py --modes tracked``."""

import pytest

from viapath.scenarios.loader import load_scenario
from viapath.sim.loop import run_episode

SEEDS = range(8)


@pytest.fixture(scope="module")
def tracked_runs():
    scenario = load_scenario("overtaking")
    return [
        run_episode(scenario, perception="tracked", seed=seed, position_noise_m=0.03, velocity_noise_mps=0.0).metrics
        for seed in SEEDS
    ]


def test_tracked_noise_leaves_the_overtaking_safe_inside_the_corridor_and_at_the_goal(tracked_runs):
    for seed, metrics in zip(SEEDS, tracked_runs):
        assert metrics["perception"] == "tracked"
        assert not metrics["collision"], (seed, metrics)
        assert metrics["time_outside_corridor_s"] == 0.0, (seed, metrics)
        assert metrics["reached_goal"], (seed, metrics)
        assert metrics["track_samples"] > 0  # the planner was fed the tracker's estimates


@pytest.mark.xfail(
    strict=True,
    reason=(
        "known: with tracker-shaped noise the planner alternates between passing and trailing the walker, "
        "39-72 command flips per run (mostly turn reversals between 'avoid' and 'straight'), trailing to the "
        "goal in ~73 s against 0 flips and 31 s clean (python benchmarks/noisy_overtaking.py --modes tracked)"
    ),
)
def test_tracked_noise_does_not_make_the_overtaking_flip(tracked_runs):
    # Trailing a walker when no pass fits is correct; flipping between trailing and passing is not.
    assert max(m["command_flips"] for m in tracked_runs) <= 12, [m["command_flips"] for m in tracked_runs]
