"""Progress through the static world: the built-in scenarios with a box before a door or past a corner.

    python benchmarks/static_progress.py [--perception oracle,laser] [--json] [--cost]

For ``box-before-door``, ``box-beside-door`` and ``l-corridor-box``, each with the oracle and the laser, it
prints: whether the goal was reached and when, static contacts, the smallest gap between the robot's
surface and static geometry, the time with status ``blocked``, and, for the two door scenes, the robot's
gap to the door where it stood waiting for it (at rest while the door was closed; the largest gap over
that time, so every waiting position is within it) and when it first stood there.

With ``--cost`` it prints instead what the flood costs on each scene's corridor (the planner's own static
discs at the robot's start): the cells of the grid, the time to make the free space (corridor cells,
free cells, components), a route, and a cycle that finds it kept (the median of 20 of each; speed
figures belong on a quiet machine).
"""

from __future__ import annotations

import argparse
import json
import math
import time

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


def _timed(call, repeats: int) -> float:
    """The median time (ms) of ``repeats`` calls."""
    spans = []
    for _ in range(repeats):
        began = time.perf_counter()
        call()
        spans.append(time.perf_counter() - began)
    return float(np.median(spans) * 1e3)


def scene_flood_cost(name: str, repeats: int = 20) -> dict:
    """What the flood costs on one scene (see the module docstring); times in ms."""
    from viapath import DesignatedPath, Observation, Obstacles, RobotState
    from viapath.guard import with_static_rows
    from viapath.planning.base import Inflation
    from viapath.planning.viapath.flood import FloodCache
    from viapath.planning.viapath.options import VIAPATH_OPTIONS
    from viapath.static import StaticLayer

    settings = VIAPATH_OPTIONS.validate({}, where="viapath")
    scenario = load_scenario(name)
    path = DesignatedPath(scenario.path.waypoints, half_width_m=scenario.path.half_width)
    start = np.asarray(scenario.robot.start, dtype=float)
    layer = StaticLayer.of_shapes([edges for edges, _ in scenario.static_shapes()])
    robot = RobotState(start, 0.0, 0.0, 0.0, scenario.robot.radius)
    obstacles = with_static_rows(Observation(0.0, robot, Obstacles.empty(), layer)).obstacles
    radii = Inflation.of(obstacles, scenario.robot.radius, settings).check_radii
    rest = radii + settings["blocked_gap_m"]
    built = _timed(lambda: FloodCache().free_space(path, start, obstacles.positions, radii, rest), repeats)
    cache = FloodCache()
    space = cache.free_space(path, start, obstacles.positions, radii, rest)
    begin = None if space is None else space.seed(start)
    goal = None if space is None or begin is None else space.farthest(begin)
    if space is None or begin is None or goal is None:
        raise SystemExit(f"{name}: no flood from the robot's start")

    def routed() -> None:
        space._distances.clear()
        space.route(begin, goal)

    return {
        "scenario": name,
        "cells": int(space.free.size),
        "static_discs": len(obstacles),
        "build_ms": built,
        "route_ms": _timed(routed, repeats),
        "kept_ms": _timed(lambda: cache.free_space(path, start, obstacles.positions.copy(), radii, rest), repeats),
    }


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
        return f"{value:.2f}" if value >= 0.01 or value == 0 else f"{value:.4f}"
    return str(value)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--perception", default="oracle,laser", help="comma-separated: oracle, laser")
    parser.add_argument("--json", action="store_true", help="print the rows as JSON")
    parser.add_argument("--cost", action="store_true", help="what the flood costs instead (times)")
    args = parser.parse_args(argv)
    rows = (
        [scene_flood_cost(name) for name in SCENES]
        if args.cost
        else run([p.strip() for p in args.perception.split(",") if p.strip()])
    )
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
