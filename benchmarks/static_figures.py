"""The static world's figures on a generated ``static`` suite (every planner, oracle and laser).

    python benchmarks/static_figures.py --count 50 --seed 11 [--planners viapath,dwa] [--json]

For each planner and perception mode it prints: static contacts (episodes with one, and in all), other
collisions, reachable goals reached, median time ratio of the ``walls`` scenes (time to goal over
length / nominal speed), and for each ``door`` scene the robot's gap to the door where it stood waiting
for it to open (None: it never had to wait).
A door scene whose description says "unreachable" counts as unreachable; every other goal is reachable.
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from viapath.bench.suites import generate_suite
from viapath.scenarios.loader import scenario_from_dict
from viapath.sim.loop import run_episode
from viapath.sim.metrics import static_clearance_per_step
from viapath.static import point_segment_distances


def door_gap_m(scenario: dict, trace) -> float | None:
    """The robot's surface distance to the closed door where it stood waiting (the last wall of a door
    scene; at rest = below 0.02 m/s while the door is closed), the smallest if it waited more than once;
    None when it never had to wait (the door opened before it came near)."""
    door = scenario["walls"][-1]
    points = np.array(door["points"], dtype=float)
    until = door.get("until_s", math.inf)
    waiting = (trace.times_s < until) & (trace.robot_speeds_mps < 0.02) & (trace.times_s > 1.0)
    if not waiting.any():
        return None
    gap = point_segment_distances(trace.robot_poses[waiting, :2], points[None])[:, 0] - trace.robot_radius_m
    return float(gap.min())


def run(planners: list[str], modes: list[str], count: int, seed: int) -> dict:
    scenarios = generate_suite("static", count, seed)
    out: dict = {}
    for planner in planners:
        for mode in modes:
            started = time.perf_counter()
            rows = []
            for spec in scenarios:
                episode = run_episode(scenario_from_dict(spec), planner=planner, perception=mode)
                metrics, trace = episode.metrics, episode.trace
                kind = spec["description"].split(":")[1].strip().split(",")[0].rstrip(".")
                reachable = "unreachable" not in spec["description"]
                length = spec["path"]["waypoints"][-1][0]
                ratio = (
                    metrics["time_to_goal_s"] / (length / spec["robot"]["speed"]) if metrics["time_to_goal_s"] else None
                )
                static_clearance = static_clearance_per_step(trace)
                rows.append(
                    dict(
                        name=spec["name"],
                        kind=kind,
                        reachable=reachable,
                        reached=metrics["reached_goal"],
                        static_contact=metrics["static_contact"],
                        collision=metrics["collision"],
                        min_static_clearance_m=float(static_clearance.min()) if len(static_clearance) else None,
                        time_ratio=ratio,
                        door_gap_m=door_gap_m(spec, trace) if kind == "door" else None,
                    )
                )
            reachable = [r for r in rows if r["reachable"]]
            walls = [r["time_ratio"] for r in rows if r["kind"] == "walls" and r["time_ratio"] is not None]
            doors = [r for r in rows if r["kind"] == "door"]
            out[f"{planner}/{mode}"] = {
                "episodes": len(rows),
                "episodes_with_static_contact": sum(r["static_contact"] > 0 for r in rows),
                "static_contacts": sum(r["static_contact"] for r in rows),
                "collisions": sum(bool(r["collision"]) for r in rows),
                "reachable": len(reachable),
                "reachable_reached": sum(bool(r["reached"]) for r in reachable),
                "walls_median_time_ratio": float(np.median(walls)) if walls else None,
                "walls_unreached": sum(1 for r in rows if r["kind"] == "walls" and not r["reached"]),
                "door_gaps_m": [None if r["door_gap_m"] is None else round(r["door_gap_m"], 3) for r in doors],
                "min_static_clearance_m": min(
                    (r["min_static_clearance_m"] for r in rows if r["min_static_clearance_m"] is not None), default=None
                ),
                "failed": [r["name"] for r in reachable if not r["reached"]],
                "wall_s": round(time.perf_counter() - started, 1),
            }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=50)
    parser.add_argument("--seed", type=int, default=11)
    parser.add_argument("--planners", default="viapath")
    parser.add_argument("--modes", default="oracle,laser")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    figures = run(args.planners.split(","), args.modes.split(","), args.count, args.seed)
    if args.json:
        print(json.dumps(figures, indent=2))
        return
    for key, f in figures.items():
        print(
            f"{key}: static contact in {f['episodes_with_static_contact']}/{f['episodes']} episodes "
            f"({f['static_contacts']} contacts), collisions {f['collisions']}, reachable goals reached "
            f"{f['reachable_reached']}/{f['reachable']}, walls median time ratio {f['walls_median_time_ratio']}, "
            f"door gaps [m] {f['door_gaps_m']}, min static clearance {f['min_static_clearance_m']}, "
            f"failed {f['failed']} ({f['wall_s']} s)"
        )


if __name__ == "__main__":
    main()
