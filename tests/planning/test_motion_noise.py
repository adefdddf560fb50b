"""A small version of benchmarks/bench_noise.py: the paper's side-crossing and head-on cases with
oracle perception noise (position σ 0.03 m, velocity σ 0.05 m/s), 4 seeds each."""

from __future__ import annotations

import pytest

from tests._scripts import load_benchmark


def _bench_module():
    return load_benchmark("bench_noise")


@pytest.fixture(scope="module")
def noisy_runs():
    bench = _bench_module()
    grouped = bench.run_noise(("paper-side", "paper-front"), seeds=4, position_noise_m=0.03, velocity_noise_mps=0.05)
    return bench, grouped


@pytest.mark.parametrize("scenario", ["paper-side", "paper-front"])
def test_noisy_runs_reach_goal_without_collision(noisy_runs, scenario):
    bench, grouped = noisy_runs
    summary = bench.summarise(grouped[scenario])
    assert summary["runs"] == 4
    assert summary["collisions"] == 0, f"collided seeds {summary['collided_seeds']}: {summary}"
    assert summary["reached_goal"] == 4, f"seeds not reaching the goal {summary['failed_seeds']}: {summary}"


def test_noise_changes_the_runs_and_seeds_are_reproducible():
    bench = _bench_module()
    a = bench.run_one("paper-side", 1, 0.03, 0.05)
    b = bench.run_one("paper-side", 1, 0.03, 0.05)
    clean = bench.run_one("paper-side", 1, 0.0, 0.0)
    assert a["min_clearance_m"] == b["min_clearance_m"] and a["plan_switches"] == b["plan_switches"]
    assert a["plan_switches"] > clean["plan_switches"]


def test_bench_noise_command_prints_a_row_per_scenario(capsys):
    bench = _bench_module()
    bench.main(["--seeds", "1", "--scenarios", "paper-side"])
    out = capsys.readouterr().out
    assert "paper-side" in out and "clr min" in out


def _noisy_overtaking_flips() -> dict:
    import numpy as np

    from viapath.scenarios.loader import load_scenario
    from viapath.sim.loop import run_episode

    flips = {}
    for keep in (False, True):
        scenario = load_scenario("overtaking")
        # The paper's way back to the path (no lookahead), where keeping the way was measured: with the
        # default lookahead the noisy overtaking flips as often either way (84.5 and 82.5 on these seeds).
        params = {**scenario.planner.params, "keep_previous_way": keep, "return_lookahead_m": 0.0}
        scenario = scenario.model_copy(update={"planner": scenario.planner.model_copy(update={"params": params})})
        runs = [
            run_episode(scenario, seed=seed, position_noise_m=0.03, velocity_noise_mps=0.05).metrics
            for seed in range(4)
        ]
        for metrics in runs:
            assert metrics["reached_goal"] and not metrics["collision"], (keep, metrics)
        flips[keep] = float(np.median([m["plan_side_flips"] for m in runs]))
    return flips


@pytest.fixture(scope="module")
def noisy_overtaking_flips():
    return _noisy_overtaking_flips()


def test_keeping_the_previous_way_cuts_side_flips_and_stays_safe(noisy_overtaking_flips):
    # Under white velocity noise last cycle's way round looks blocked now and then only because its
    # cone grew with the error; re-checking it with less inflation keeps it (hysteresis on the
    # constraint). Overtaking a slow walker flips most; same seeds with and without it.
    flips = noisy_overtaking_flips
    assert flips[True] <= flips[False], flips


def test_a_previous_way_that_only_lost_on_cost_is_not_searched_again_with_less_inflation(monkeypatch):
    # Relaxing the inflation is for a way that vanished; a way still there that simply costs more
    # must not come back in a tighter, less inflated form.
    import numpy as np

    from viapath import DesignatedPath, Observation, Obstacles, RobotState
    from viapath.planning import make_planner
    from viapath.planning.viapath.candidates import Choice, Way
    from viapath.planning.viapath.planner import ViaPathPlanner

    path = DesignatedPath([[0.0, 0.0], [8.0, 0.0]], half_width_m=1.5)
    planner = make_planner("viapath", path, nominal_speed_mps=0.25)
    head_on = Obstacles(
        positions=[[3.0, 0.05]],
        velocities=[[-0.3, 0.0]],
        radii_m=[0.25],
        position_sigma_m=[0.03],
        velocity_sigma_mps=[0.05],
    )
    observation = Observation(0.0, RobotState(np.zeros(2), 0.0, 0.25), head_on)

    searches = []
    original_choose = ViaPathPlanner._choose

    def recording_choose(self, checks, speeds, nominal_index, previous, only_way=None):
        result = original_choose(self, checks, speeds, nominal_index, previous, only_way)
        # a relaxed search: the obstacle's velocity σ cut below the observed 0.05 m/s
        searches.append((bool(checks.obstacles.velocity_sigma_mps[0] < 0.05 - 1e-12), result))
        return result

    monkeypatch.setattr(ViaPathPlanner, "_choose", recording_choose)
    first = planner.plan(observation)
    assert first.plan.status == "avoid"
    candidates, costs = searches[-1][1].candidates, first.plan.candidate_costs
    dearest = int(np.argmax(np.where(np.isfinite(costs), costs, -np.inf)))
    worst = Way(*(int(v) for v in candidates.ways[dearest]))
    assert worst != planner._previous.way
    # Last cycle went the dearest way, which is still available now.
    planner._previous = Choice(worst, int(candidates.speed_mmps[dearest]))
    searches.clear()
    second = planner.plan(observation)
    assert planner._previous.way != worst  # it switched ...
    assert not any(relaxed for relaxed, _ in searches)  # ... with no relaxed re-run
    assert "kept_previous_way" not in second.plan.extras
    assert second.plan.extras["way_change"] == "cost"


@pytest.mark.parametrize("noisy", [True, False])
def test_a_previous_way_no_search_finds_is_marked_gone(noisy):
    # Last cycle went round an obstacle that is not there now: with uncertainty the relaxed search
    # runs and finds nothing ("gone_relaxed_too"); without, there is nothing to relax ("gone").
    import numpy as np

    from viapath import DesignatedPath, Observation, Obstacles, RobotState
    from viapath.planning import make_planner
    from viapath.planning.viapath.candidates import Choice, Way

    path = DesignatedPath([[0.0, 0.0], [8.0, 0.0]], half_width_m=1.5)
    planner = make_planner("viapath", path, nominal_speed_mps=0.25)
    sigma = 1.0 if noisy else 0.0
    head_on = Obstacles(
        positions=[[3.0, 0.05]],
        velocities=[[-0.3, 0.0]],
        radii_m=[0.25],
        position_sigma_m=[0.03 * sigma],
        velocity_sigma_mps=[0.05 * sigma],
    )
    observation = Observation(0.0, RobotState(np.zeros(2), 0.0, 0.25), head_on)
    first = planner.plan(observation)
    assert first.plan.status == "avoid"
    planner._previous = Choice(Way(7, 1, 7), 250)  # round obstacle 7, which left the scene
    second = planner.plan(observation)
    assert second.plan.status == "avoid"
    assert second.plan.extras["way_change"] == ("gone_relaxed_too" if noisy else "gone")
    assert "kept_previous_way" not in second.plan.extras


def _count_way_changes(scenario_name: str, seed: int, position_noise_m: float, velocity_noise_mps: float) -> dict:
    """One noisy run: the cycles whose way round changed, by the reason the planner marks in
    ``plan.extras`` (``way_change``: cost, gone, gone_relaxed_too, relaxed_costs_more; ``kept_previous_way``),
    the cycles, and the run's side flips."""
    from collections import Counter

    from viapath.scenarios.loader import load_scenario
    from viapath.sim.loop import run_episode

    changes: Counter[str] = Counter()

    def on_step(record) -> None:
        extras = record.decision.plan.extras
        changes["kept_previous_way"] += bool(extras.get("kept_previous_way"))
        if extras.get("way_change") is not None:
            changes[extras["way_change"]] += 1
        changes["cycles"] += 1

    episode = run_episode(
        load_scenario(scenario_name),
        seed=seed,
        position_noise_m=position_noise_m,
        velocity_noise_mps=velocity_noise_mps,
        on_step=on_step,
    )
    return {**changes, "plan_side_flips": episode.metrics["plan_side_flips"]}


def test_relaxed_searches_happen_only_under_noise():
    clean = _count_way_changes("overtaking", 0, 0.0, 0.0)
    noisy = _count_way_changes("overtaking", 0, 0.03, 0.05)
    relaxed = ("gone_relaxed_too", "relaxed_costs_more", "kept_previous_way")
    assert all(clean.get(key, 0) == 0 for key in relaxed), clean
    assert sum(noisy.get(key, 0) for key in relaxed) > 0, noisy
    assert noisy["cycles"] > clean["cycles"] and noisy["plan_side_flips"] > clean["plan_side_flips"]


def _trailing_then(walker_y_m: float, switch_inflation: float, sigmas=(0.02, 0.1)):
    """The robot trailed a walker (0.1 m/s, 1 m ahead, ``walker_y_m`` off the path in a ±1 m corridor) last
    cycle; this cycle's plan (status, way change)."""
    import numpy as np

    from viapath import DesignatedPath, Observation, Obstacles, RobotState
    from viapath.planning import make_planner
    from viapath.planning.viapath.candidates import STRAIGHT, Choice, Way

    path = DesignatedPath([[0.0, 0.0], [8.0, 0.0]], half_width_m=1.0)
    options = {"switch_inflation": switch_inflation, "weights": {"k1": 0.1, "k2": 0.01, "k3": 0.08, "k4": 0.3}}
    planner = make_planner("viapath", path, nominal_speed_mps=0.25, options=options)
    walker = Obstacles(
        positions=[[1.0, walker_y_m]],
        velocities=[[0.1, 0.0]],
        radii_m=[0.25],
        position_sigma_m=[sigmas[0]],
        velocity_sigma_mps=[sigmas[1]],
    )
    observation = Observation(0.0, RobotState(np.zeros(2), 0.0, 0.1), walker)
    planner._previous = Choice(Way(STRAIGHT, 0, 0), 100)  # trailing at 0.1 m/s
    decision = planner.plan(observation)
    return decision.plan.status, decision.plan.extras.get("way_change")


@pytest.mark.parametrize("walker_y_m", [-0.3, -0.4, -0.5])
def test_a_pass_that_fits_only_just_does_not_replace_trailing(walker_y_m):
    # Free with the usual inflation (taken without the switch hysteresis), not with twice it: the robot trails on.
    assert _trailing_then(walker_y_m, 1.0) == ("avoid", "cost")
    assert _trailing_then(walker_y_m, 2.0) == ("straight", "held_new_way_too_tight")


def test_a_pass_with_room_replaces_trailing_and_exact_estimates_are_not_held():
    assert _trailing_then(-0.6, 2.0) == ("avoid", "cost")  # the walker 0.6 m aside: room to pass
    # exact estimates (no σ: no inflation to multiply) switch as without the hysteresis
    assert (
        _trailing_then(-0.4, 2.0, sigmas=(0.0, 0.0))
        == _trailing_then(-0.4, 1.0, sigmas=(0.0, 0.0))
        == ("avoid", "cost")
    )
