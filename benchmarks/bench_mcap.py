"""What writing the MCAP costs: a run's wall time with and without ``--mcap`` (target: at most +20 %).

Usage: python benchmarks/bench_mcap.py [--repeats 3] [--scenarios paper-front paper-side:laser zara01]
                                       [--json]

Each scenario runs once to warm up (imports, numba), then ``repeats`` times each way, interleaved:
``plain`` is ``run_episode`` as ``viapath run`` does it; ``mcap`` is the same run with the MCAP view
(the viapath planner then also keeps every candidate's polyline for display, part of the cost);
``cand.`` is the plain run with that planner option alone, to show which part of the cost is the
planner's.
A scenario ``NAME:laser`` runs with laser perception; ``zara01`` is 20 s among replayed ETH/UCY
people (crowds_zara01.txt; skipped when the data folder is absent). Printed: median wall time of
each, the overhead in per cent, the file size and the messages per second of simulated time.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import tempfile
import time
from pathlib import Path

from viapath.bench.suites import data_root
from viapath.scenarios import load_scenario, scenario_from_dict
from viapath.sim.loop import run_episode
from viapath.viz.foxglove import display_overrides, record_episode

DEFAULT = ("paper-front", "paper-side:laser", "zara01")


def _scenario(name: str):
    if name == "zara01":
        file = data_root() / "eth_ucy_trajectron" / "crowds_zara01.txt"
        if not file.exists():
            return None
        return scenario_from_dict({
            "name": "zara01-bench", "dt_s": 0.1, "duration_s": 20.0,
            "robot": {"start": [3.0, 5.0], "heading": 0.0, "speed": 0.3, "radius": 0.25},
            "path": {"waypoints": [[3.0, 5.0], [12.0, 5.0]], "half_width": 1.5},
            "obstacles": [{"replay": {"file": str(file), "dt_s": 0.4, "start_s": 120, "offset": [0, 0],
                                      "radius": 0.25}}],
        })
    return load_scenario(name)


def measure(name: str, repeats: int, folder: Path) -> dict | None:
    base, _, mode = name.partition(":")
    scenario = _scenario(base)
    if scenario is None:
        return None
    perception = mode or "oracle"
    run_episode(scenario, perception=perception)  # warm-up
    plain, candidates, mcap, cycles, size = [], [], [], 0, 0
    overrides = display_overrides(scenario, scenario.planner.name)
    for k in range(repeats):
        started = time.perf_counter()
        episode = run_episode(scenario, perception=perception)
        plain.append(time.perf_counter() - started)
        started = time.perf_counter()
        run_episode(scenario, perception=perception, planner_overrides=overrides)
        candidates.append(time.perf_counter() - started)
        file = folder / f"{base}-{k}.mcap"
        started = time.perf_counter()
        recorded = record_episode(scenario, file, perception=perception, force=True)
        mcap.append(time.perf_counter() - started)
        cycles, size = len(recorded.trace.times_s) - 1, file.stat().st_size
        assert len(episode.trace.times_s) == len(recorded.trace.times_s)
    p, m, c = statistics.median(plain), statistics.median(mcap), statistics.median(candidates)
    return {"scenario": name, "perception": perception, "cycles": cycles, "plain_s": plain, "mcap_s": mcap,
            "candidates_s": candidates, "plain_median_s": p, "mcap_median_s": m, "candidates_median_s": c,
            "overhead_percent": 100.0 * (m - p) / p, "candidates_overhead_percent": 100.0 * (c - p) / p,
            "mcap_ms_per_cycle": 1e3 * (m - p) / max(cycles, 1), "file_bytes": size}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scenarios", nargs="+", default=list(DEFAULT))
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()
    results = []
    with tempfile.TemporaryDirectory() as folder:
        for name in args.scenarios:
            result = measure(name, args.repeats, Path(folder))
            if result is None:
                print(f"{name}: skipped (data not found under {data_root()})") if not args.json else None
                continue
            results.append(result)
    if args.json:
        print(json.dumps({"python": platform.python_version(), "repeats": args.repeats, "results": results}))
        return
    print(f"python {platform.python_version()}, {platform.machine()}, {args.repeats} repeats each (medians)")
    print(f"{'scenario':20s} {'cycles':>6s} {'plain s':>8s} {'cand. s':>8s} {'mcap s':>8s} {'overhead':>9s} "
          f"{'of which cand.':>15s} {'ms/cycle':>9s} {'file':>9s}")
    for r in results:
        print(f"{r['scenario']:20s} {r['cycles']:6d} {r['plain_median_s']:8.2f} {r['candidates_median_s']:8.2f} "
              f"{r['mcap_median_s']:8.2f} {r['overhead_percent']:8.1f}% {r['candidates_overhead_percent']:14.1f}% "
              f"{r['mcap_ms_per_cycle']:9.2f} {r['file_bytes'] / 1e6:7.2f} MB")


if __name__ == "__main__":
    main()
