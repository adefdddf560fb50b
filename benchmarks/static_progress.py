"""Progress through the static world: the built-in scenarios with a box before a door or past a corner.

    python benchmarks/static_progress.py [--perception oracle,laser] [--json]

For ``box-before-door``, ``box-beside-door`` and ``l-corridor-box``, each with the oracle and the laser, it
prints: whether the goal was reached and when, static contacts, the smallest gap between the robot's
surface and static geometry, the time with status ``blocked``, and, for the two door scenes, the robot's
gap to the door where it stood waiting for it (at rest while the door was closed; the largest gap over
that time, so every waiting position is within it) and when it first stood there.
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from viapath.scenarios.loader import load_scenario
from viapath.sim.loop import run_episode
from viapath.static import point_segment_distances

SCENES = ("box-before-door", "box-beside-door", "l-corridor-box")


def waiting_at_door(scenario, trace) -> tuple[float | None, float | None]:
    """(largest gap to the door while at rest before it opened, when the robot first stood there); (None,
    None) without a door or when it never stood still before it. The door is the scene's first wall."""
    door = scenario.walls[0]
    points = np.asarray(door.points, dtype=float)
    until = door.until_s if door.until_s is not None else math.inf
    resting = (trace.times_s < until) & (trace.robot_speeds_mps < 0.02) & (trace.times_s > 1.0)
    gap = point_segment_distances(trace.robot_poses[:, :2], points[None])[:, 0] - trace.robot_radius_m
    at_door = resting & (gap < 1.0)
    if not at_door.any():
        return None, None
    return float(gap[at_door].max()), float(trace.times_s[np.argmax(at_door)])


def run(perceptions: list[str]) -> list[dict]:
    rows = []
    for name in SCENES:
        for perception in perceptions:
            scenario = load_scenario(name)
            episode = run_episode(scenario, perception=perception)
            m = episode.metrics
            gap, since = waiting_at_door(scenario, episode.trace) if name != "l-corridor-box" else (None, None)
            rows.append(
                {
                    "scenario": name,
                    "perception": perception,
                    "reached_goal": bool(m["reached_goal"]),
                    "time_to_goal_s": m["time_to_goal_s"],
                    "static_contact": int(m["static_contact"]),
                    "collision": bool(m["collision"]),
                    "min_static_clearance_m": m["min_static_clearance_m"],
                    "blocked_s": m["blocked_s"],
                    "door_gap_m": gap,
                    "waiting_from_s": since,
                }
            )
    return rows


def _show(value) -> str:
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.2f}"
    return str(value)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--perception", default="oracle,laser", help="comma-separated: oracle, laser")
    parser.add_argument("--json", action="store_true", help="print the rows as JSON")
    args = parser.parse_args(argv)
    rows = run([p.strip() for p in args.perception.split(",") if p.strip()])
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    columns = list(rows[0])
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    for row in rows:
        print("| " + " | ".join(_show(row[c]) for c in columns) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
