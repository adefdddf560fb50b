"""Noise robustness: the paper's crossing and head-on cases under tracker-level perception noise.

Usage: python benchmarks/bench_noise.py [--seeds 20] [--position-noise 0.03] [--velocity-noise 0.05]
                                        [--scenarios paper-side paper-front] [--planner viapath] [--jobs 1]

Each run is the built-in scenario with oracle perception whose reported positions and velocities
get fresh Gaussian noise every cycle (σ per axis, as ``viapath run --position-noise/--velocity-noise``),
seeds 0..N-1. Printed per scenario: runs, how many reach the goal, collide (any overlap) and leave
the corridor, min clearance (smallest and median over runs), plan switches (median; changes of the
chosen side or speed between cycles) and left/right flips (median), and the seeds that collided.
docs/design.md §2 measured 15 of 20 noisy side-crossing runs colliding for a plain re-derivation.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from viapath.scenarios.loader import load_scenario
from viapath.sim.loop import run_episode

DEFAULT_SCENARIOS = ("paper-side", "paper-front")


def run_one(
    scenario_name: str, seed: int, position_noise_m: float, velocity_noise_mps: float, planner: str | None = None
) -> dict:
    episode = run_episode(
        load_scenario(scenario_name),
        planner=planner,
        perception="oracle",
        seed=seed,
        position_noise_m=position_noise_m,
        velocity_noise_mps=velocity_noise_mps,
    )
    return {**episode.metrics, "seed": seed}


def run_noise(
    scenarios=DEFAULT_SCENARIOS,
    seeds: int = 20,
    position_noise_m: float = 0.03,
    velocity_noise_mps: float = 0.05,
    planner: str | None = None,
    jobs: int = 1,
) -> dict[str, list[dict]]:
    """Metrics of every (scenario, seed) run, grouped by scenario."""
    tasks = [(name, seed) for name in scenarios for seed in range(seeds)]
    if jobs != 1:
        from joblib import Parallel, delayed

        results = Parallel(n_jobs=jobs)(
            delayed(run_one)(name, seed, position_noise_m, velocity_noise_mps, planner) for name, seed in tasks
        )
    else:
        results = [run_one(name, seed, position_noise_m, velocity_noise_mps, planner) for name, seed in tasks]
    grouped: dict[str, list[dict]] = {name: [] for name in scenarios}
    for (name, _), metrics in zip(tasks, results):
        grouped[name].append(metrics)
    return grouped


def summarise(runs: list[dict]) -> dict:
    clearance = np.array([m["min_clearance_m"] if m["min_clearance_m"] is not None else np.inf for m in runs])
    return {
        "runs": len(runs),
        "reached_goal": sum(bool(m["reached_goal"]) for m in runs),
        "collisions": sum(bool(m["collision"]) for m in runs),
        "outside_corridor": sum(m["time_outside_corridor_s"] > 0 for m in runs),
        "min_clearance_min_m": float(clearance.min()),
        "min_clearance_median_m": float(np.median(clearance)),
        "plan_switches_median": float(np.median([m["plan_switches"] for m in runs])),
        "side_flips_median": float(np.median([m["plan_side_flips"] for m in runs])),
        "collided_seeds": [m["seed"] for m in runs if m["collision"]],
        "failed_seeds": [m["seed"] for m in runs if not m["reached_goal"]],
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="runs per scenario, seeds 0..N-1")
    parser.add_argument("--position-noise", type=float, default=0.03, help="σ of reported positions, m")
    parser.add_argument("--velocity-noise", type=float, default=0.05, help="σ of reported velocities, m/s")
    parser.add_argument("--scenarios", nargs="+", default=list(DEFAULT_SCENARIOS))
    parser.add_argument("--planner", default=None, help="planner name (default: the scenario's)")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes (joblib); -1 = all cores")
    args = parser.parse_args(argv)
    if args.seeds < 1 or args.position_noise < 0 or args.velocity_noise < 0:
        parser.error("--seeds must be >= 1 and the noise levels >= 0")
    started = time.perf_counter()
    grouped = run_noise(args.scenarios, args.seeds, args.position_noise, args.velocity_noise, args.planner, args.jobs)
    print(
        f"oracle perception, position σ {args.position_noise} m, velocity σ {args.velocity_noise} m/s, "
        f"seeds 0..{args.seeds - 1}, planner {args.planner or 'from scenario'}"
    )
    header = (
        f"{'scenario':<16} {'runs':>4} {'goal':>4} {'coll':>4} {'out':>4} {'clr min':>8} {'clr med':>8} "
        f"{'switch med':>10} {'flips med':>9}  collided seeds"
    )
    print(header)
    for name, runs in grouped.items():
        s = summarise(runs)
        print(
            f"{name:<16} {s['runs']:>4} {s['reached_goal']:>4} {s['collisions']:>4} {s['outside_corridor']:>4} "
            f"{s['min_clearance_min_m']:>8.3f} {s['min_clearance_median_m']:>8.3f} "
            f"{s['plan_switches_median']:>10.1f} {s['side_flips_median']:>9.1f}  {s['collided_seeds']}"
        )
    print(f"({time.perf_counter() - started:.1f} s)")


if __name__ == "__main__":
    main()
