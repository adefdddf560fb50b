"""The ETH and hotel replays with and without their obstacle maps: figures from two ``viapath bench`` runs.

    viapath suite eth-ucy --count 200 --seed 0 --out S/suite-eth-ucy
    viapath suite eth-ucy-maps --count 200 --seed 0 --out S/suite-eth-ucy-maps
    (delete every file but the *-eth-* and *-hotel-* ones in both folders)
    viapath bench S/suite-eth-ucy -p viapath -w 1 --no-plots --seed 0 --out S/bench-eth-ucy
    viapath bench S/suite-eth-ucy-maps -p viapath -w 1 --no-plots --seed 0 --out S/bench-eth-ucy-maps
    python benchmarks/eth_maps_figures.py S          # prints the markdown table (--json: the numbers)
    python benchmarks/eth_maps_figures.py --alignment   # where the maps land, against the walkers and map.xml

Per scene and variant: episodes, scenarios with map walls, success (goal reached, no contact), reached,
collisions (any contact, people or static), at-fault collisions, episodes with a static contact and their number, median time
ratio (time to goal over the obstacle-free time, with the walls), length of the map walls per scenario that
has some, smallest path-to-wall distance, how
many windows got another path (an end within 0.35 m of the map: placed again), and how many episodes'
outcome (reached, collision) differs from the same window without the map.
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


def _wall_length_m(file: Path) -> float:
    walls = yaml.safe_load(file.read_text()).get("walls") or []
    return float(sum(np.hypot(*np.diff(np.asarray(wall["points"], dtype=float), axis=0).T).sum() for wall in walls))


def _path(file: Path) -> list:
    return yaml.safe_load(file.read_text())["path"]["waypoints"]


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
        lengths = [
            _wall_length_m(root / "suite-eth-ucy-maps" / f"{name.replace('eth-ucy-', 'eth-ucy-maps-', 1)}.yaml")
            for name in names
            if distances[name] is not None
        ]
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
                "at_fault": sum(r["at_fault_collision"] == "True" for r in rows),
                "episodes_with_static_contact": sum(s > 0 for s in static),
                "static_contacts": sum(static),
                "median_time_ratio": round(float(np.median(ratios)), 3) if ratios else None,
                "wall_length_m_median_max": (
                    [round(float(np.median(lengths)), 1), round(max(lengths), 1)] if index and lengths else None
                ),
                "min_path_to_wall_m": (
                    round(min(d for d in distances.values() if d is not None), 2)
                    if index and any(d is not None for d in distances.values())
                    else None
                ),
                "path_placed_again": (
                    sum(
                        _path(root / "suite-eth-ucy" / f"{a['scenario']}.yaml")
                        != _path(root / "suite-eth-ucy-maps" / f"{b['scenario']}.yaml")
                        for a, b in pairs
                    )
                    if index
                    else None
                ),
                "outcome_differs": (
                    sum((a["reached_goal"], a["collision"]) != (b["reached_goal"], b["collision"]) for a, b in pairs)
                    if index
                    else None
                ),
            }
    return out


def alignment() -> dict:
    """Per sequence and image-point order fed to H: walker positions (the 4-column file) inside an obstacle,
    the fewest positions within 1 m outside any one outline, and how far every 10 cm of OpenTraj's map.xml
    lines lie from the obstacles (0 inside)."""
    import re

    from viapath.bench.suites import data_root
    from viapath.io.ewap_map import ObstacleMap, obstacle_map, read_homography, read_obstacle_image
    from viapath.static import point_segment_distances

    root = data_root()
    out: dict = {}
    for sequence, file in (("seq_eth", "biwi_eth.txt"), ("seq_hotel", "biwi_hotel.txt")):
        folder = root / "eth_ewap_original" / sequence
        image, homography = read_obstacle_image(folder / "map.png"), read_homography(folder / "H.txt")
        walkers = np.loadtxt(root / "eth_ucy_trajectron" / file, ndmin=2)[:, 2:4]
        text = (folder / "map.xml").read_text()
        lines = np.array(re.findall(r'<Line x1="([^"]+)" y1="([^"]+)" x2="([^"]+)" y2="([^"]+)"', text), dtype=float)
        steps = np.linspace(0.0, 1.0, 50)[:, None]
        samples = np.concatenate([line[:2] * (1 - steps) + line[2:] * steps for line in lines.reshape(-1, 4)])
        for order, obstacles in (
            ("(row, column)", obstacle_map(image, homography)),
            ("(column, row)", obstacle_map(image.T, homography)),
        ):
            inside = obstacles.contains(walkers)
            around = [
                int(
                    np.count_nonzero(
                        (point_segment_distances(walkers, ObstacleMap((ring,)).segments()).min(axis=1) < 1.0) & ~inside
                    )
                )
                for ring in obstacles.outlines
            ]
            off = np.where(
                obstacles.contains(samples), 0.0, point_segment_distances(samples, obstacles.segments()).min(axis=1)
            )
            out[f"{sequence} {order}"] = {
                "outlines": len(obstacles.outlines),
                "walkers_inside": f"{int(inside.sum())}/{len(walkers)}",
                "outline_centres_m": [np.round(ring[:-1].mean(axis=0), 1).tolist() for ring in obstacles.outlines],
                "inside_per_outline": [
                    int(ObstacleMap((ring,)).contains(walkers).sum()) for ring in obstacles.outlines
                ],
                "fewest_within_1m_of_an_outline": min(around),
                "map_xml_off_m_median_max": [round(float(np.median(off)), 3), round(float(off.max()), 3)],
            }
    return out


def differing(root: Path) -> list[str]:
    """One line per window whose (reached, collision) changed with the map."""
    plain, mapped = _rows(root / "bench-eth-ucy"), _rows(root / "bench-eth-ucy-maps")
    lines = []
    for name, a in sorted(plain.items()):
        b = mapped.get(name.replace("eth-ucy-", "eth-ucy-maps-", 1))
        if b is None or (a["reached_goal"], a["collision"]) == (b["reached_goal"], b["collision"]):
            continue
        again = _path(root / "suite-eth-ucy" / f"{name}.yaml") != _path(
            root / "suite-eth-ucy-maps" / f"{b['scenario']}.yaml"
        )
        lines.append(
            f"{b['scenario']}: collision {a['collision']} -> {b['collision']}, min clearance "
            f"{float(a['min_clearance_m']):.2f} -> {float(b['min_clearance_m']):.2f} m, "
            f"path placed again: {again}; {b['at_fault_detail'] or 'no at-fault contact'}"
        )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "root", type=Path, nargs="?", help="folder holding suite-eth-ucy[-maps] and bench-eth-ucy[-maps]"
    )
    parser.add_argument("--alignment", action="store_true", help="print where the maps land instead")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.alignment:
        for key, value in alignment().items():
            print(key, json.dumps(value))
        return
    if args.root is None:
        parser.error("give the folder of the two bench runs, or --alignment")
    table = figures(args.root)
    if args.json:
        print(json.dumps(table, indent=2))
        return
    print(
        "| scene | episodes | with map walls | success | reached | collisions | at-fault | static contact"
        " (episodes / contacts) | time ratio (median) | wall length per scenario (median, max) [m]"
        " | path to nearest wall [m] | path placed again | outcome differs |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for key, f in table.items():
        n = f["episodes"]
        print(
            f"| {key} | {n} | {f['with_walls']} | {f['success'] / n:.1%} | {f['reached'] / n:.1%} | "
            f"{f['collisions'] / n:.1%} | {f['at_fault'] / n:.1%} | {f['episodes_with_static_contact']} / {f['static_contacts']} | "
            f"{f['median_time_ratio']} | {'–' if f['wall_length_m_median_max'] is None else f['wall_length_m_median_max']} | "
            f"{'–' if f['min_path_to_wall_m'] is None else f['min_path_to_wall_m']} | "
            f"{'–' if f['path_placed_again'] is None else f['path_placed_again']} | "
            f"{'–' if f['outcome_differs'] is None else f['outcome_differs']} |"
        )
    print()
    for line in differing(args.root):
        print(line)


if __name__ == "__main__":
    main()
