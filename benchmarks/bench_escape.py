"""The calm escape (issue 11, item 6), measured: the same episodes with ``calm_escape`` off (the
escape before: up to the limits' top speed, no continuity) and on.

    python benchmarks/bench_escape.py out/suite-eth-ucy-100 --workers 2 [--json]

Prints, per setting: episodes, contacts, at-fault contacts, escape cycles, command flips (a speed jump
of >= 0.25 m/s or a turn reversal between |ω| >= 0.5 rad/s from one cycle to the next; summed over the
episodes, and per escape cycle), the top speed driven, the largest distance outside the corridor.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed


def _episode(file: str, calm: bool) -> dict:
    from viapath.scenarios import load_scenario
    from viapath.sim.loop import run_episode

    scenario = load_scenario(file)
    episode = run_episode(scenario, planner="viapath", planner_overrides={"calm_escape": calm})
    trace, m = episode.trace, episode.metrics
    excess = trace.path.corridor_excess(trace.robot_poses[:, :2])
    return {
        "collision": m["collision"],
        "at_fault": m["at_fault_collision"],
        "reached": m["reached_goal"],
        "escape_cycles": m["escape_cycles"],
        "command_flips": m["command_flips"],
        "max_speed_mps": m["max_speed_mps"],
        "max_excess_m": float(np.max(excess)),
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("suite", help="a folder of scenario YAML files")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--limit", type=int, default=0, help="only the first N files (0: all)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    files = sorted(str(f) for f in Path(args.suite).glob("*.yaml"))
    if args.limit:
        files = files[: args.limit]
    if not files:
        print(f"{args.suite}: no scenario files", file=sys.stderr)
        return 2
    results = {}
    for calm in (False, True):
        rows = Parallel(n_jobs=args.workers)(delayed(_episode)(f, calm) for f in files)
        escape = sum(r["escape_cycles"] for r in rows)
        flips = sum(r["command_flips"] for r in rows)
        results["calm" if calm else "before"] = {
            "episodes": len(rows),
            "collision": sum(r["collision"] for r in rows),
            "at_fault_collision": sum(r["at_fault"] for r in rows),
            "reached_goal": sum(r["reached"] for r in rows),
            "escape_cycles": escape,
            "command_flips": flips,
            "flips_per_escape_cycle": flips / escape if escape else 0.0,
            "max_speed_mps": max(r["max_speed_mps"] for r in rows),
            "max_excess_m": max(r["max_excess_m"] for r in rows),
        }
    if args.json:
        print(json.dumps(results, indent=2))
    else:
        for name, r in results.items():
            print(
                f"{name:>7}: " + ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in r.items())
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
