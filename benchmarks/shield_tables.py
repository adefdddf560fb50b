"""Tables of docs/explanation/passive-safety.md from ``viapath bench`` results: each planner with and without the shield.

Usage: python benchmarks/shield_tables.py OUT_DIR [OUT_DIR ...] [--merge] [--json]

Reads OUT_DIR/episodes.csv (rows of every shield setting side by side) and prints one Markdown table
per folder: at-fault collision, collision, success, reached goal, median time ratio, shield
interventions per episode (cycles in which the shield replaced the command), plan time p50.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from viapath.bench.report import markdown_table, summarize
from viapath.bench.runner import read_rows

COLUMNS = [
    ("planner", "planner", "{}"),
    ("episodes", "episodes", "{}"),
    ("at_fault_collision_rate", "at-fault", "{:.1%}"),
    ("at_fault_seen_1s_rate", "at-fault, seen ≥ 1 s", "{:.1%}"),
    ("collision_rate", "collision", "{:.1%}"),
    ("success_rate", "success", "{:.1%}"),
    ("reached_goal_rate", "reached goal", "{:.1%}"),
    ("time_ratio_median", "time ratio (median)", "{:.2f}"),
    ("time_outside_corridor_s", "outside corridor [s/ep]", "{:.2f}"),
    ("shield_interventions_per_episode", "interventions/ep", "{:.1f}"),
    ("plan_time_p50_ms", "plan p50 [ms]", "{:.2f}"),
]
ORDER = ["viapath", "follow", "stop", "dwa", "vo", "nav-orca", "nav-hl", "nav-hrvo", "nav-sf"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--merge", action="store_true", help="one table of the rows of all folders")
    args = parser.parse_args()
    everything = {}
    if args.merge:  # an episode (scenario, planner, perception, seed, shield) found in two folders counts once
        seen, merged = set(), []
        for folder in args.folders:
            for row in read_rows(folder / "episodes.csv"):
                key = (row["scenario"], row["planner"], row["perception"], row["seed"], row["shield"])
                if key not in seen:
                    seen.add(key)
                    merged.append(row)
        groups = [(" + ".join(map(str, args.folders)), merged)]
    else:
        groups = [(str(f), read_rows(f / "episodes.csv")) for f in args.folders]
    for folder, rows in groups:
        summary = summarize(rows, order=ORDER)
        everything[folder] = summary
        if not args.json:
            print(f"\n### {folder}\n")
            print(markdown_table(summary, columns=COLUMNS))
    if args.json:
        print(json.dumps(everything, indent=1))


if __name__ == "__main__":
    main()
