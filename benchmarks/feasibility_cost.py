"""What the bench's feasibility sweep (viapath.bench.feasibility) costs per episode, and what it finds.

Usage: python benchmarks/feasibility_cost.py [--suite mixed] [--count 50] [--seed 5] [--cell 0.1] [--json]

Generates the suite's scenarios (as ``viapath suite`` does), sweeps each one's reachable set from the
robot's start over its people's recorded future (people who react to the robot are skipped), and prints
the wall and CPU time per scenario (median, mean, max; the first sweep, which compiles or loads the compiled
code, is timed apart), the grid sizes, the share of infeasible scenarios and the set's earliest arrival
over the obstacle-free straight-line time.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from viapath.bench.feasibility import reacts_to_robot, scenario_reach
from viapath.bench.suites import generate_suite
from viapath.scenarios import scenario_from_dict


def measure(suite: str, count: int, seed: int, cell_m: float) -> dict:
    scenarios = [scenario_from_dict(data, data["name"]) for data in generate_suite(suite, count, seed)]
    started = time.perf_counter()
    scenario_reach(scenarios[0], cell_m=cell_m)  # compiles, or loads numba's cache
    first_s = time.perf_counter() - started
    walls, cpus, cells, steps, infeasible, emptied, arrivals, skipped = [], [], [], [], [], [], [], 0
    for scenario in scenarios:
        if reacts_to_robot(scenario):
            skipped += 1
            continue
        started, cpu = time.perf_counter(), time.process_time()
        reach = scenario_reach(scenario, cell_m=cell_m)
        walls.append(time.perf_counter() - started)
        cpus.append(time.process_time() - cpu)
        cells.append(reach.grid.rows * reach.grid.columns)
        steps.append(reach.steps)
        infeasible.append(not reach.feasible)
        emptied.append(reach.emptied_s is not None)
        if reach.feasible:
            waypoints = np.asarray(scenario.path.waypoints, dtype=float)
            length = float(np.sum(np.hypot(*np.diff(waypoints, axis=0).T)))
            arrivals.append(reach.arrival_s / (length / scenario.robot.limits.max_speed_mps))
    walls_ms = 1e3 * np.asarray(walls)
    return {
        "suite": suite,
        "count": count,
        "seed": seed,
        "cell_m": cell_m,
        "swept": len(walls),
        "skipped_reactive": skipped,
        "first_sweep_s": first_s,
        "wall_ms_median": float(np.median(walls_ms)) if len(walls) else None,
        "wall_ms_mean": float(np.mean(walls_ms)) if len(walls) else None,
        "wall_ms_max": float(np.max(walls_ms)) if len(walls) else None,
        "cpu_ms_median": float(np.median(cpus)) * 1e3 if cpus else None,
        "cpu_ms_max": float(np.max(cpus)) * 1e3 if cpus else None,
        "cells_median": float(np.median(cells)) if cells else None,
        "steps_median": float(np.median(steps)) if steps else None,
        "infeasible": int(np.sum(infeasible)),
        "infeasible_share": float(np.mean(infeasible)) if infeasible else None,
        "emptied": int(np.sum(emptied)),
        "arrival_over_straight_time_median": float(np.median(arrivals)) if arrivals else None,
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="mixed")
    parser.add_argument("--count", type=int, default=50)
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument("--cell", type=float, default=0.1, help="cell size, m")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    result = measure(args.suite, args.count, args.seed, args.cell)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    print(
        f"{result['suite']} {result['count']} seed {result['seed']}, cell {result['cell_m']} m: "
        f"{result['swept']} swept ({result['skipped_reactive']} reactive skipped); per scenario "
        f"median {result['wall_ms_median']:.1f} ms, mean {result['wall_ms_mean']:.1f} ms, max "
        f"{result['wall_ms_max']:.1f} ms; CPU median {result['cpu_ms_median']:.1f} ms, max "
        f"{result['cpu_ms_max']:.1f} ms (first sweep {result['first_sweep_s']:.2f} s); median grid "
        f"{result['cells_median']:.0f} cells x {result['steps_median']:.0f} steps; infeasible "
        f"{result['infeasible']} ({result['infeasible_share']:.1%}), set emptied {result['emptied']}; "
        f"earliest arrival / straight-line time at top speed, median {result['arrival_over_straight_time_median']:.2f}"
    )


if __name__ == "__main__":
    main()
