"""The ETH and hotel replays with and without their obstacle maps: figures from two ``viapath bench`` runs.

    viapath suite eth-ucy --count 200 --seed 0 --out S/suite-eth-ucy
    viapath suite eth-ucy-maps --count 200 --seed 0 --out S/suite-eth-ucy-maps
    (delete every file but the *-eth-* and *-hotel-* ones in both folders)
    viapath bench S/suite-eth-ucy -p viapath -w 1 --no-plots --seed 0 --out S/bench-eth-ucy
    viapath bench S/suite-eth-ucy-maps -p viapath -w 1 --no-plots --seed 0 --out S/bench-eth-ucy-maps
    python benchmarks/eth_maps_figures.py S          # prints the markdown table (--json: the numbers)

Per scene and variant: episodes, scenarios with map walls, success (goal reached, no contact), reached,
collisions (any contact, people or static), episodes with a static contact and their number, median time
ratio (time to goal over the obstacle-free time, with the walls), smallest path-to-wall distance, and how
many episodes' outcome (reached, collision) differs from the same window without the map.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np
import yaml

from viapath.static import polyline_edges, segment_distances


def _rows(folder: Path) -> dict[str, dict]:
    with open(folder / "episodes.csv", newline="") as stream:
        return {row["scenario"]: row for row in csv.DictReader(stream)}


def _path_to_walls_m(file: Path) -> float | None:
    scenario = yaml.safe_load(file.read_text())
    walls = scenario.get("walls") or []
    if not walls:
        return None
    segments = np.concatenate([polyline_edges(wall["points"]) for wall in walls])
    waypoints = np.asarray(scenario["path"]["waypoints"], dtype=float)
    return float(segment_distances(waypoints[:-1], waypoints[1:], segments).min())


def figures(root: Path) -> dict:
    plain, mapped = _rows(root / "bench-eth-ucy"), _rows(root / "bench-eth-ucy-maps")
    out: dict = {}
    for scene in ("eth", "hotel"):
        names = sorted(name for name in plain if name.startswith(f"eth-ucy-{scene}-"))
        pairs = [(plain[name], mapped[name.replace("eth-ucy-", "eth-ucy-maps-", 1)]) for name in names]
        distances = {
            name: _path_to_walls_m(root / "suite-eth-ucy-maps" / f"{name.replace('eth-ucy-', 'eth-ucy-maps-', 1)}.yaml")
            for name in names
        }
        for variant, index in (("without map", 0), ("with map", 1)):
            rows = [pair[index] for pair in pairs]
            ratios = [float(r["time_ratio"]) for r in rows if r["time_ratio"]]
            static = [int(r["static_contact"]) for r in rows]
            out[f"{scene} {variant}"] = {
                "episodes": len(rows),
                "with_walls": sum(d is not None for d in distances.values()) if index else 0,
                "success": sum(r["reached_goal"] == "True" and r["collision"] == "False" for r in rows),
                "reached": sum(r["reached_goal"] == "True" for r in rows),
                "collisions": sum(r["collision"] == "True" for r in rows),
                "episodes_with_static_contact": sum(s > 0 for s in static),
                "static_contacts": sum(static),
                "median_time_ratio": round(float(np.median(ratios)), 3) if ratios else None,
                "min_path_to_wall_m": (
                    round(min(d for d in distances.values() if d is not None), 2)
                    if index and any(d is not None for d in distances.values())
                    else None
                ),
                "outcome_differs": (
                    sum((a["reached_goal"], a["collision"]) != (b["reached_goal"], b["collision"]) for a, b in pairs)
                    if index
                    else None
                ),
            }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("root", type=Path, help="folder holding suite-eth-ucy[-maps] and bench-eth-ucy[-maps]")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    table = figures(args.root)
    if args.json:
        print(json.dumps(table, indent=2))
        return
    print(
        "| scene | episodes | with map walls | success | reached | collisions | static contact (episodes / contacts)"
        " | time ratio (median) | path to nearest wall [m] | outcome differs |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for key, f in table.items():
        n = f["episodes"]
        print(
            f"| {key} | {n} | {f['with_walls']} | {f['success'] / n:.1%} | {f['reached'] / n:.1%} | "
            f"{f['collisions'] / n:.1%} | {f['episodes_with_static_contact']} / {f['static_contacts']} | "
            f"{f['median_time_ratio']} | {'–' if f['min_path_to_wall_m'] is None else f['min_path_to_wall_m']} | "
            f"{'–' if f['outcome_differs'] is None else f['outcome_differs']} |"
        )


if __name__ == "__main__":
    main()
