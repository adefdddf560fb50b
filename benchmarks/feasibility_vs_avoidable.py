"""The reachable set (viapath.bench.feasibility) beside the avoidable search (viapath.bench.avoidable) on real
contacts: for every contact with a person in a bench's episodes, does any run keep clear of everyone from
the cycle that person was first seen?

Usage: python benchmarks/feasibility_vs_avoidable.py OUT_DIR [--suite FOLDER] [--planner viapath] [--json]

Re-runs each episode of OUT_DIR/episodes.csv with a contact (its scenario from the suite folder, by
default OUT_DIR/suite, as ``viapath bench`` ran it; oracle perception), then for each contact onset with a person: the search's
verdict where the contact was at fault, and the reachable set swept from the robot's position at the
person's first-seen step to the onset plus 3 s. The set empties only when no run, even relaxed, keeps
clear of everyone: then the contact could not be avoided by any robot on this drive at all (by the
search's rule it may still be the robot's fault only if the robot had to be moving). Prints one line per
contact and the counts.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from viapath.bench.avoidable import judge
from viapath.bench.feasibility import forward_reachable, reacts_to_robot
from viapath.bench.runner import load_suite, read_rows
from viapath.scenarios import scenario_from_dict
from viapath.scenarios.build import scenario_limits, scenario_path
from viapath.sim.loop import run_episode
from viapath.sim.metrics import first_seen_steps
from viapath.sim.static_world import StaticWorld

AFTER_ONSET_S = 3.0


def contact_onsets(trace) -> list[tuple[int, int]]:
    """(step, person) of every contact onset with a person, in time order."""
    poses, people = trace.robot_poses[:, :2], trace.obstacle_positions
    reach = trace.obstacle_radii_m + trace.robot_radius_m
    with np.errstate(invalid="ignore"):
        touching = np.hypot(*(poses[:, None] - people).transpose(2, 0, 1)) < reach
    onset = touching & ~np.vstack([np.zeros((1, touching.shape[1]), dtype=bool), touching[:-1]])
    return [(int(k), int(n)) for k, n in zip(*np.nonzero(onset))]


def judge_episode(scenario, planner: str, seed: int) -> list[dict]:
    episode = run_episode(scenario, planner=planner, seed=seed)
    trace = episode.trace
    limits = scenario_limits(scenario)
    verdicts = {(round(v.onset_s / trace.dt_s), v.person): v for v in judge(trace, limits)}
    static = StaticWorld.of_scenario(scenario)
    first_seen = first_seen_steps(trace.obstacle_positions)
    dt = scenario.dt_s
    times = np.arange(int(round(scenario.duration_s / dt)) + 1) * dt
    from viapath.sim.obstacles import scenario_obstacle_states

    people, _, radii = scenario_obstacle_states(scenario, times)
    out = []
    for step, person in contact_onsets(trace):
        seen = int(first_seen[person])
        last = min(step + int(round(AFTER_ONSET_S / dt)), len(people) - 1)
        reach = forward_reachable(
            people[seen : last + 1],
            radii,
            scenario.robot.radius,
            scenario_path(scenario),
            trace.robot_poses[seen, :2],
            limits.max_speed_mps,
            dt,
            walls=static.segments,
            wall_until_s=static.until_s,
            start_time_s=seen * dt,
        )
        verdict = min(
            (v for (k, n), v in verdicts.items() if n == person and abs(k - step) <= 1),
            key=lambda v: abs(v.onset_s - step * dt),
            default=None,
        )
        out.append(
            {
                "scenario": scenario.name,
                "person": person,
                "onset_s": step * dt,
                "seen_before_s": (step - seen) * dt,
                "robot_speed_mps": float(trace.robot_speeds_mps[step]),
                "at_fault": verdict is not None,
                "search": None if verdict is None else ("avoidable" if verdict.avoidable else "unavoidable"),
                "set_emptied_after_s": None if reach.emptied_s is None else reach.emptied_s,
            }
        )
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir", type=Path)
    parser.add_argument("--suite", type=Path, help="the scenario files (default: OUT_DIR/suite)")
    parser.add_argument("--planner", default="viapath")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    rows = [r for r in read_rows(args.out_dir / "episodes.csv") if r["planner"] == args.planner and r["collision"]]
    scenarios = {s["name"]: s for s in load_suite(str(args.suite or args.out_dir / "suite"))}
    contacts = []
    for row in rows:
        scenario = scenario_from_dict(scenarios[row["scenario"]], row["scenario"])
        if reacts_to_robot(scenario):
            continue
        contacts += judge_episode(scenario, args.planner, int(row["seed"]))
    counts: dict[str, int] = {}
    for c in contacts:
        key = f"{c['search'] or 'not at fault'} / {'set emptied' if c['set_emptied_after_s'] is not None else 'a clear run exists'}"
        counts[key] = counts.get(key, 0) + 1
    if args.json:
        print(json.dumps({"contacts": contacts, "counts": counts}, indent=2))
        return
    for c in contacts:
        emptied = c["set_emptied_after_s"]
        print(
            f"{c['scenario']} person {c['person']} at {c['onset_s']:.1f} s (seen {c['seen_before_s']:.1f} s before, "
            f"robot {c['robot_speed_mps']:.2f} m/s): search {c['search'] or 'not at fault'}; "
            + ("a clear run exists" if emptied is None else f"every run touches someone within {emptied:.1f} s")
        )
    print(f"{len(contacts)} contacts: " + ", ".join(f"{k}: {v}" for k, v in sorted(counts.items())))


if __name__ == "__main__":
    main()
