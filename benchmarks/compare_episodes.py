"""Compare two benchmark ``episodes.csv`` files row by row: the check that a refactor changed nothing.

    python benchmarks/compare_episodes.py before/episodes.csv after/episodes.csv [--ignore-added]
        [--ignore COLUMN,...] [--json]

Rows are matched on (scenario, planner, perception, seed). Timing columns (plan times, wall time) are
ignored; every other column must be equal to the letter (numbers are compared as written, so a change
in the last printed digit counts). Exit code 0 when both files hold the same rows with the same
values, 1 otherwise; the differences are listed. ``--ignore-added``: columns that only the after file
has (new metrics) are not compared; ``--ignore``: these columns are not compared either.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys

KEY = ("scenario", "planner", "perception", "seed")
IGNORED = {"plan_time_p50_ms", "plan_time_p99_ms", "episode_wall_s"}


def read(path: str) -> dict[tuple, dict[str, str]]:
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    table = {}
    for row in rows:
        key = tuple(row.get(name, "") for name in KEY)
        if key in table:
            raise SystemExit(f"{path}: row {key} appears twice")
        table[key] = row
    return table


def compare(before: dict, after: dict, ignored: set[str] = frozenset(), ignore_added: bool = False) -> dict:
    skipped = IGNORED | set(ignored)
    if ignore_added and before and after:
        skipped |= set(next(iter(after.values()))) - set(next(iter(before.values())))
    only_before = sorted(set(before) - set(after))
    only_after = sorted(set(after) - set(before))
    changed = []
    for key in sorted(set(before) & set(after)):
        a, b = before[key], after[key]
        for column in sorted((set(a) | set(b)) - skipped - set(KEY)):
            if a.get(column) != b.get(column):
                changed.append({"row": list(key), "column": column, "before": a.get(column), "after": b.get(column)})
    return {
        "rows_compared": len(set(before) & set(after)),
        "only_before": [list(k) for k in only_before],
        "only_after": [list(k) for k in only_after],
        "differences": changed,
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--ignore-added", action="store_true", help="skip columns only the after file has")
    parser.add_argument("--ignore", default="", help="comma-separated columns not compared")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    args = parser.parse_args(argv)
    ignored = {c.strip() for c in args.ignore.split(",") if c.strip()}
    result = compare(read(args.before), read(args.after), ignored, args.ignore_added)
    same = not (result["only_before"] or result["only_after"] or result["differences"])
    if args.json:
        print(json.dumps({**result, "identical": same}, indent=2))
    else:
        print(
            f"{result['rows_compared']} rows compared; {len(result['differences'])} differing values; "
            f"{len(result['only_before'])} rows only before, {len(result['only_after'])} only after"
        )
        for item in result["differences"][:50]:
            print(f"  {'/'.join(item['row'])}: {item['column']}: {item['before']} -> {item['after']}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
