"""Could any command sequence have avoided an at-fault contact? The search of viapath.bench.avoidable, on a bench run.

Usage: python benchmarks/unavoidable.py OUT_DIR [--suite DIR] [--planner viapath] [--shield on]
           [--limit 20] [--weights PRESET] [--max-levels 4] [--max-hold 1.0] [--json]

Re-runs each at-fault episode of a ``viapath bench`` run (same seed, as ``benchmarks/shield_faults.py``
does), replays its real commands through the search's model first (``check_replay``: the trace's
poses and the metric's onsets must come back), then searches every at-fault onset with a person from
the robot's real state at the person's first appearance (see viapath.bench.avoidable for the search
and its budget). The bench itself writes the same verdicts into episodes.csv (at_fault_avoidable,
at_fault_unavoidable, at_fault_detail); this script shows them with other budgets.
"""

from __future__ import annotations

import argparse
import csv
import json
from dataclasses import asdict
from pathlib import Path

from viapath.bench.avoidable import check_replay, judge
from viapath.observation import MotionLimits
from viapath.presets import preset_values
from viapath.scenarios import load_scenario
from viapath.sim import loop


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--suite", type=Path, default=None, help="scenario folder (default OUT_DIR/suite)")
    parser.add_argument("--planner", default="viapath")
    parser.add_argument("--shield", default="on")
    parser.add_argument("--limit", type=int, default=20)
    parser.add_argument("--weights", default=None, help="the weights preset the bench ran with (--weights)")
    parser.add_argument("--max-levels", type=int, default=4, help="decisions between appearance and onset")
    parser.add_argument("--max-hold", type=float, default=1.0, help="longest a decision is held, s")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    with open(args.out / "episodes.csv") as handle:
        rows = [
            r
            for r in csv.DictReader(handle)
            if r["planner"] == args.planner and r["shield"] == args.shield and r["at_fault_collision"] == "True"
        ]
    overrides = preset_values(args.weights, args.planner) if args.weights else None
    results = []
    for row in rows[: args.limit]:
        scenario = load_scenario((args.suite or args.out / "suite") / f"{row['scenario']}.yaml")
        reactive = any(getattr(getattr(o, "replay", None), "react", False) for o in scenario.obstacles or [])
        episode = loop.run_episode(
            scenario,
            planner=args.planner,
            seed=int(row["seed"]),
            shield=args.shield != "off",
            planner_overrides=overrides,
            shield_options={"mode": "passive-friendly" if args.shield == "friendly" else "passive"},
        )
        limits = MotionLimits(**scenario.robot.limits.model_dump())
        check_replay(episode.trace, limits)
        verdicts = judge(episode.trace, limits, reactive=reactive, max_levels=args.max_levels, max_hold_s=args.max_hold)
        if not verdicts:
            print(
                f"{row['scenario']}: the re-run has no at-fault onset with a person (static, or other options: --weights)"
            )
        results += [{"scenario": row["scenario"], **asdict(v)} for v in verdicts]
    if args.json:
        print(json.dumps(results, indent=2))
        return
    for r in results:
        verdict = "avoidable" if r["avoidable"] else "UNAVOIDABLE"
        print(
            f"{r['scenario']} person {r['person']}: onset {r['onset_s']:.1f} s, appeared {r['appeared_s']:.1f} s "
            f"({r['onset_s'] - r['appeared_s']:.1f} s before, robot at {r['robot_speed_at_appearance_mps']:.2f} m/s): "
            f"{verdict}, {r['reason']} (decisions held {r['hold_s']:.1f} s, {r['branches']} branches)"
        )


if __name__ == "__main__":
    main()
