"""The slowest cycles of ``bench_planner.py``'s scenes, one by one: what its p99 is made of, and where their time goes.

Usage: python benchmarks/slow_cycles.py [--obstacles 10] [--repeats 25] [--top 6] [--sections]

``bench_planner.py`` times 300 cycles over 40 scenes, so each scene comes up 7-8 times and its p99 is
about the time of its slowest scene. Here every scene is timed ``--repeats`` times (thread CPU time)
and its fastest cycle kept, which a shared machine disturbs far less than a percentile; printed: the
median over the scenes, the slowest ``--top`` with their status, and the sum. ``--sections`` then
times the parts of the slowest scenes' cycles (the functions below, wrapped; thread CPU time, with
the wrappers' own cost) as shares of the cycle.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_planner

from viapath import DesignatedPath


def scenes(n_obstacles: int, seed: int = 0):
    """``bench_planner.py``'s scenes for one obstacle count (the same generator, seed and order)."""
    path = DesignatedPath([[0.0, 0.0], [10.0, 0.0]], half_width_m=1.5)
    chooser = bench_planner.build("viapath", path)
    rng = np.random.default_rng(seed)
    return path, [bench_planner.random_scene(rng, n_obstacles, path, chooser) for _ in range(40)]


def fastest_cycles(planner, observations, repeats: int) -> np.ndarray:
    best = np.full(len(observations), np.inf)
    for _ in range(repeats):
        for i, observation in enumerate(observations):
            planner.reset()
            start = time.thread_time()
            planner.plan(observation)
            best[i] = min(best[i], time.thread_time() - start)
    return best * 1e3


SECTIONS = [  # (module, owner in it or None, function, label): the parts of a cycle
    ("viapath.planning.viapath.planner", None, "way_back", "the way back"),
    ("viapath.planning.viapath.planner", None, "outrun_held", "the outrun hold"),
    ("viapath.planning.viapath.planner", None, "choose_compiled", "the choice (paper steps 1-4)"),
    ("viapath.planning.viapath.packing", None, "choose", "  packing.choose"),
    ("viapath.planning.viapath.choice", None, "_first_admitted", "  the ranks after the first that follows"),
    ("viapath.planning.viapath.planner", "ViaPathPlanner", "_inside_shield", "the shield's check of candidates"),
    ("viapath.planning.viapath.planner", None, "keep_previous_way", "the kept way"),
    ("viapath.planning.viapath.planner", None, "stop_or_escape", "stop or escape"),
]


def section_shares(planner, observations, repeats: int) -> tuple[float, dict[str, float]]:
    import importlib

    spent: dict[str, float] = collections.defaultdict(float)

    def timed(function, label):
        def wrapper(*args, **kwargs):
            start = time.thread_time()
            try:
                return function(*args, **kwargs)
            finally:
                spent[label] += time.thread_time() - start

        return wrapper

    for module_name, owner, name, label in SECTIONS:
        module = importlib.import_module(module_name)
        holder = getattr(module, owner) if owner else module
        if hasattr(holder, name):  # (code of an earlier wave may not have it)
            setattr(holder, name, timed(getattr(holder, name), label))
    total = 0.0
    for _ in range(repeats):
        for observation in observations:
            planner.reset()
            start = time.thread_time()
            planner.plan(observation)
            total += time.thread_time() - start
    cycles = repeats * len(observations)
    return total / cycles * 1e3, {label: spent[label] / total for _, _, _, label in SECTIONS}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--obstacles", type=int, default=10)
    parser.add_argument("--repeats", type=int, default=25)
    parser.add_argument("--top", type=int, default=6)
    parser.add_argument("--sections", action="store_true", help="time the parts of the slowest scenes' cycles")
    args = parser.parse_args()
    path, observations = scenes(args.obstacles)
    planner = bench_planner.build("viapath", path)
    best = fastest_cycles(planner, observations, args.repeats)
    slowest = [int(i) for i in np.argsort(best)[::-1][: args.top]]
    statuses = {}
    for i in slowest:
        planner.reset()
        statuses[i] = planner.plan(observations[i]).plan.status
    report = {
        "load_average": os.getloadavg()[0],
        "median_ms": float(np.median(best)),
        "sum_ms": float(best.sum()),
        "slowest": [{"scene": i, "ms": round(float(best[i]), 4), "status": statuses[i]} for i in slowest],
    }
    if args.sections:
        per_cycle, shares = section_shares(planner, [observations[i] for i in slowest], max(1, args.repeats * 8))
        report["sections"] = {
            "cycle_ms": per_cycle,
            **{label.strip(): round(share, 3) for label, share in shares.items()},
        }
    print(json.dumps(report))


if __name__ == "__main__":
    main()
