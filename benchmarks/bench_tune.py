"""How long one ``viapath tune`` trial takes, and how that scales with workers (issue 15).

Usage: python benchmarks/bench_tune.py [SUITE] [--count 9] [--seed 303] [--workers 1,2] [--runs 3] [--json]

A trial is one run of the suite through the benchmark runner with the paper's weights
(:func:`viapath.bench.tune.evaluate`). For each worker count, ``--runs`` trials are timed; the rows
give the wall time, the sum of the episodes' own wall times (the CPU work), the longest episode (the
floor no number of workers goes below) and the machine's load average, so a figure taken on a shared
machine can be read. Estimate for N trials with W workers: N · max(sum / W, longest) + overhead.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from viapath.bench.runner import load_suite, run_bench
from viapath.bench.tune import PAPER_WEIGHTS, PLANNER


def one_trial(scenarios, workers: int, seed: int) -> dict:
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="viapath-bench-tune-") as folder:
        rows = run_bench(
            scenarios,
            [PLANNER],
            Path(folder),
            workers=workers,
            seed=seed,
            progress=False,
            planner_options={PLANNER: dict(PAPER_WEIGHTS)},
        )["rows"]
    wall = time.perf_counter() - started
    episodes = [r["episode_wall_s"] for r in rows]
    return {
        "workers": workers,
        "wall_s": round(wall, 2),
        "episodes_sum_s": round(sum(episodes), 2),
        "longest_episode_s": round(max(episodes), 2),
        "load_average_1min": round(os.getloadavg()[0], 2),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("suite", nargs="?", default="mixed")
    parser.add_argument("--count", type=int, default=9)
    parser.add_argument("--seed", type=int, default=303)
    parser.add_argument("--workers", default="1,2")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    scenarios = load_suite(args.suite, None, count=args.count, seed=args.seed)
    rows = [one_trial(scenarios, int(w), args.seed) for w in args.workers.split(",") for _ in range(args.runs)]
    if args.json:
        print(json.dumps({"scenarios": len(scenarios), "rows": rows}, indent=1))
        return
    print(f"{len(scenarios)} scenarios; one trial = one run of the suite")
    print(f"{'workers':>7} {'wall [s]':>9} {'episodes sum [s]':>17} {'longest [s]':>12} {'load':>6}")
    for r in rows:
        print(
            f"{r['workers']:7d} {r['wall_s']:9.1f} {r['episodes_sum_s']:17.1f} {r['longest_episode_s']:12.1f} "
            f"{r['load_average_1min']:6.2f}"
        )


if __name__ == "__main__":
    main()
