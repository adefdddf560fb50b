"""What the bench's feasibility sweep (viapath.bench.feasibility) costs per episode, and what it finds.

Usage: python benchmarks/feasibility_cost.py [--suite mixed|FOLDER] [--count 50] [--seed 5] [--cell 0.1]
       [--episodes episodes.csv] [--json]

Generates the suite's scenarios (as ``viapath suite`` does; or reads a folder of scenario files), sweeps each one's reachable set from the
robot's start over its people's recorded future (people who react to the robot are skipped), and prints
the wall and CPU time per scenario (median, mean, max; the first sweep, which compiles or loads the compiled
code, is timed apart), the grid sizes, the share of infeasible scenarios and the set's earliest arrival
over the obstacle-free straight-line time. With ``--episodes`` (a bench's episodes.csv over the same
scenarios, e.g. one written before these columns existed): success and reach among the feasible
episodes of each planner there.
"""

from __future__ import annotations

import argparse
import csv
import json
import time
from pathlib import Path

import numpy as np

from viapath.bench.feasibility import reacts_to_robot, scenario_reach
from viapath.bench.runner import load_suite
from viapath.scenarios import scenario_from_dict


def measure(suite: str, count: int, seed: int, cell_m: float, episodes: str | None = None) -> dict:
    scenarios = [scenario_from_dict(data, data["name"]) for data in load_suite(suite, None, count, seed)]
    started = time.perf_counter()
    scenario_reach(scenarios[0], cell_m=cell_m)  # compiles, or loads numba's cache
    first_s = time.perf_counter() - started
    walls, cpus, cells, steps, infeasible, emptied, arrivals, skipped = [], [], [], [], [], [], [], 0
    feasible_names = set()
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
        if reach.feasible:
            feasible_names.add(scenario.name)
        emptied.append(reach.emptied_s is not None)
        if reach.feasible:
            waypoints = np.asarray(scenario.path.waypoints, dtype=float)
            length = float(np.sum(np.hypot(*np.diff(waypoints, axis=0).T)))
            arrivals.append(reach.arrival_s / (length / scenario.robot.limits.max_speed_mps))
    walls_ms = 1e3 * np.asarray(walls)
    among_feasible = {}
    if episodes:
        judged = {s.name for s in scenarios if not reacts_to_robot(s)}
        with Path(episodes).open(newline="") as handle:  # any version's columns: only these few are read
            for row in csv.DictReader(handle):
                if row["error"] or row["scenario"] not in judged or row["scenario"] not in feasible_names:
                    continue
                name = row["planner"] + ("" if row.get("shield", "off") in ("off", "") else " +shield")
                entry = among_feasible.setdefault(name, [0, 0, 0])
                entry[0] += 1
                entry[1] += row["reached_goal"] == "True" and row["collision"] != "True"
                entry[2] += row["reached_goal"] == "True"
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
        "among_feasible": {
            name: {"episodes": n, "success_rate": ok / n, "reach_rate": reached / n}
            for name, (n, ok, reached) in among_feasible.items()
        },
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="mixed")
    parser.add_argument("--count", type=int, default=50)
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument("--cell", type=float, default=0.1, help="cell size, m")
    parser.add_argument("--episodes", help="a bench's episodes.csv over the same scenarios")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    result = measure(args.suite, args.count, args.seed, args.cell, args.episodes)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    print(
        (
            result["suite"]
            if Path(result["suite"]).is_dir()
            else f"{result['suite']} {result['count']} seed {result['seed']}"
        )
        + f", cell {result['cell_m']} m: "
        f"{result['swept']} swept ({result['skipped_reactive']} reactive skipped); per scenario "
        f"median {result['wall_ms_median']:.1f} ms, mean {result['wall_ms_mean']:.1f} ms, max "
        f"{result['wall_ms_max']:.1f} ms; CPU median {result['cpu_ms_median']:.1f} ms, max "
        f"{result['cpu_ms_max']:.1f} ms (first sweep {result['first_sweep_s']:.2f} s); median grid "
        f"{result['cells_median']:.0f} cells x {result['steps_median']:.0f} steps; infeasible "
        f"{result['infeasible']} ({result['infeasible_share']:.1%}), set emptied {result['emptied']}; "
        f"earliest arrival / straight-line time at top speed, median {result['arrival_over_straight_time_median']:.2f}"
    )
    for name, entry in result["among_feasible"].items():
        print(
            f"{name}: {entry['episodes']} feasible episodes, success {entry['success_rate']:.1%}, "
            f"reach {entry['reach_rate']:.1%}"
        )


if __name__ == "__main__":
    main()
