"""Plan time with the passive-safety shield: p50/p99 for 1, 10, 50 and 100 people (docs/design.md §7).

Usage: python benchmarks/bench_shield.py [--cycles 300] [--seed 0] [--runs 3] [--json]

Scenes as in bench_planner.py (robot at the start of a 10 m path, people within 8 m walking at
0.3-1.5 m/s in random directions, none overlapping the robot), but the robot moves at 0.4 m/s and
a third of the people are placed within 2 m, so the shield has work to do. Rows:
* ``viapath``: the planner alone; ``viapath+shield``: ShieldedPlanner(viapath), what runs each cycle;
* ``shield``: the filter alone on viapath's command (mostly the one-command fast path);
* ``shield-search``: the filter on a command it must replace (full speed straight at the nearest
  person), i.e. the whole dynamic-window search: the worst case per cycle.
The shield has one implementation, compiled (``--compute`` / ``--backend`` are still read and do nothing).
Single thread; each run redraws nothing (same seed), so the runs differ by machine load only.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.observation import Command, MotionLimits
from viapath.planning import make_planner
from viapath.safety import ShieldConfig, ShieldedPlanner


def random_scene(rng, n_people: int) -> Observation:
    near = n_people // 3
    distance = np.concatenate([rng.uniform(0.8, 2.0, near), rng.uniform(0.8, 8.0, n_people - near)])
    bearing = rng.uniform(-np.pi, np.pi, n_people)
    positions = np.stack([distance * np.cos(bearing), distance * np.sin(bearing)], 1)
    speed = rng.uniform(0.3, 1.5, n_people)
    direction = rng.uniform(-np.pi, np.pi, n_people)
    velocities = np.stack([speed * np.cos(direction), speed * np.sin(direction)], 1)
    people = Obstacles(positions, velocities, np.full(n_people, 0.25), velocity_sigma_mps=np.full(n_people, 0.05))
    return Observation(0.0, RobotState(np.zeros(2), 0.0, 0.4, 0.0, 0.25), people)


def _time(function, scenes, cycles) -> list[float]:
    for scene in scenes[:5]:  # warm-up
        function(scene)
    samples = []
    for i in range(cycles):
        scene = scenes[i % len(scenes)]
        start = time.perf_counter()
        function(scene)
        samples.append((time.perf_counter() - start) * 1e3)
    return samples


def one_run(cycles: int, seed: int) -> list[dict]:
    rng = np.random.default_rng(seed)
    path = DesignatedPath([[0.0, 0.0], [10.0, 0.0]], half_width_m=1.5)
    limits = MotionLimits()
    bare = make_planner("viapath", path, nominal_speed_mps=0.2, limits=limits)
    guarded = ShieldedPlanner(
        make_planner("viapath", path, nominal_speed_mps=0.2, limits=limits),
        dt_s=0.1,
        config=ShieldConfig(),
    )
    shield = guarded.shield
    rows = []
    for n_people in (1, 10, 50, 100):
        scenes = [random_scene(rng, n_people) for _ in range(40)]
        commands = {id(s): bare.plan(s).command for s in scenes}

        def at_nearest(scene):
            nearest = scene.obstacles.positions[np.argmin(np.hypot(*scene.obstacles.positions.T))]
            return Command(limits.max_speed_mps, float(np.clip(2.5 * np.arctan2(nearest[1], nearest[0]), -2, 2)))

        forced = {id(s): at_nearest(s) for s in scenes}

        def run_bare(scene):
            bare.reset()
            bare.plan(scene)

        def run_guarded(scene):
            guarded.reset()
            guarded.plan(scene)

        cases = {
            "viapath": run_bare,
            "viapath+shield": run_guarded,
            "shield": lambda scene, commands=commands: shield.filter(scene, commands[id(scene)]),
            "shield-search": lambda scene, forced=forced: shield.filter(scene, forced[id(scene)]),
        }
        intervened = np.mean([shield.filter(s, commands[id(s)]).intervened for s in scenes])
        searched = np.mean([shield.filter(s, forced[id(s)]).intervened for s in scenes])
        for name, function in cases.items():
            samples = _time(function, scenes, cycles)
            p50, p99 = np.percentile(samples, [50, 99])
            rows.append(
                {
                    "people": n_people,
                    "case": name,
                    "p50_ms": float(p50),
                    "p99_ms": float(p99),
                    "max_ms": float(max(samples)),
                    "intervened_fraction": float(
                        intervened
                        if name in ("shield", "viapath+shield")
                        else searched
                        if name == "shield-search"
                        else 0.0
                    ),
                }
            )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument(
        "--compute",
        "--backend",
        dest="compute",
        choices=("auto", "numpy", "numba", "both"),
        default="auto",
        help="no longer does anything (the shield has one implementation, compiled)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object (all runs)")
    args = parser.parse_args()
    runs = [one_run(args.cycles, args.seed) for _ in range(args.runs)]
    if args.json:
        print(
            json.dumps(
                {"cycles": args.cycles, "seed": args.seed, "compute": args.compute, "pid": os.getpid(), "runs": runs},
                indent=1,
            )
        )
        return
    for number, rows in enumerate(runs, 1):
        print(f"run {number}: {args.cycles} cycles per row, pid {os.getpid()}, single thread")
        print(f"{'people':>6} {'case':>15} {'p50 ms':>8} {'p99 ms':>8} {'max ms':>8} {'replaced':>8}")
        for row in rows:
            print(
                f"{row['people']:>6} {row['case']:>15} {row['p50_ms']:>8.3f} {row['p99_ms']:>8.3f} "
                f"{row['max_ms']:>8.3f} {row['intervened_fraction']:>8.0%}"
            )


if __name__ == "__main__":
    main()
