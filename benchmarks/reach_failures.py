"""Why the robot missed the goal in feasible episodes: where it was and what it did at the time limit, and
whether a stricter reachable set (the planner's top speed, a clearance) still reaches the goal.

Usage: python benchmarks/reach_failures.py OUT [OUT ...] [--workers 2] [--longer S] [--json]

Each OUT is a ``viapath bench`` results folder (episodes.csv and the suite's YAML files in OUT/suite). Every
episode with ``feasible`` True and ``reach_feasible`` False is run again (same scenario, seed and perception;
the planner's defaults, so run it with the tree that wrote OUT) and described:

* ``left_m``: how far along the path the goal still was at the time limit; ``along_every_5s``,
  ``lateral_every_5s``: where the robot was along and across the path every 5 s; ``back_m``: how far it went
  backwards along the path in all; ``rest_last10``: the share of the last 10 s it stood (below 0.02 m/s);
  ``mean_speed``: its mean speed over the episode;
* ``statuses``: the plan statuses of the episode by share; ``switches``: how often the status changed;
* ``contact_s``: seconds in contact with someone; ``first_contact_s``;
* ``feasible_at``: the earliest arrival (None: infeasible) of the reachable set (viapath.bench.feasibility) at the
  drive's top speed (the bench's ``feasible``), at the planner's top speed (the top of its speed set), the same
  with the people's radii grown by the planner's safety margin and by 0.3 m, and at the nominal speed, bare and
  grown by 0.3 m: how many failures the relaxation's generosity (speed, narrow gaps) explains;
* with ``--longer S``: when the same episode with S s more reaches the goal (None: not either).

Then the windows per class (:func:`classify`), how many each stricter set still reaches, and per plan status its
share of the cycles and the progress along the path made in it (:func:`status_table`).
"""

from __future__ import annotations

import argparse
import collections
import csv
import json
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed

STAND_MPS = 0.02  # below this the robot stands


def _reach(scenario, top_speed_mps, clearance_m=0.0) -> float | None:
    from viapath.bench.feasibility import scenario_reach

    reach = scenario_reach(scenario, top_speed_mps=top_speed_mps, clearance_m=clearance_m)
    return reach.arrival_s if reach.feasible else None


def describe(yaml_path: str, seed: int, perception: str, longer_s: float, options: dict | None = None) -> dict:
    from viapath.planning.viapath.options import VIAPATH_OPTIONS
    from viapath.scenarios.build import scenario_limits
    from viapath.scenarios.loader import load_scenario
    from viapath.sim.loop import run_episode

    scenario = load_scenario(yaml_path)
    episode = run_episode(scenario, seed=seed, perception=perception, planner_overrides=options)
    trace = episode.trace
    dt = trace.dt_s
    speeds = np.asarray(trace.robot_speeds_mps)
    last = int(round(10.0 / dt))
    _, along, lateral = trace.path.project(trace.robot_poses[:, :2])
    every = int(round(5.0 / dt))
    statuses = collections.Counter(trace.plan_status)
    n = max(len(trace.plan_status), 1)
    switches = sum(a != b for a, b in zip(trace.plan_status, trace.plan_status[1:]))
    gaps = _gaps(trace)
    contact = gaps < 0.0
    planner_top = float(max(VIAPATH_OPTIONS["speeds"].default))
    margin = float(VIAPATH_OPTIONS["safety_margin_m"].default)
    steps = np.diff(along)
    by_status: dict[str, list[float]] = {}
    for status, metres in zip(trace.plan_status, steps):
        entry = by_status.setdefault(status, [0, 0.0])
        entry[0] += 1
        entry[1] += float(metres)
    row = {
        "scenario": scenario.name,
        "dt_s": dt,
        "nominal_mps": float(scenario.robot.speed),
        "by_status": by_status,
        "reached": bool(trace.reached_goal),
        "left_m": float(trace.path.length_m - float(along[-1])),
        "along_every_5s": [round(float(a), 1) for a in along[::every]],
        "lateral_every_5s": [round(float(a), 1) for a in lateral[::every]],
        "back_m": float(-np.sum(np.minimum(np.diff(along), 0.0))),
        "rest_last10": float(np.mean(speeds[-last:] < STAND_MPS)),
        "rest_all": float(np.mean(speeds < STAND_MPS)),
        "mean_speed": float(np.mean(speeds)),
        "statuses": {k: round(v / n, 2) for k, v in statuses.most_common()},
        "statuses_last10": dict(collections.Counter(trace.plan_status[-last:]).most_common()),
        "switches": int(switches),
        "contact_s": float(np.sum(contact) * dt),
        "first_contact_s": float(np.argmax(contact) * dt) if contact.any() else None,
        "feasible_at": {
            f"drive {scenario_limits(scenario).max_speed_mps}": _reach(scenario, None),
            f"planner {planner_top}": _reach(scenario, planner_top),
            f"planner {planner_top} + margin {margin}": _reach(scenario, planner_top, margin),
            f"planner {planner_top} + 0.3 m": _reach(scenario, planner_top, 0.3),
            f"nominal {scenario.robot.speed}": _reach(scenario, scenario.robot.speed),
            f"nominal {scenario.robot.speed} + 0.3 m": _reach(scenario, scenario.robot.speed, 0.3),
        },
    }
    if longer_s > 0:
        longer = scenario.model_copy(update={"duration_s": scenario.duration_s + longer_s})
        again = run_episode(longer, seed=seed, perception=perception, planner_overrides=options)
        row["longer_reached_s"] = again.metrics["time_to_goal_s"] if again.trace.reached_goal else None
    return row


def _gaps(trace) -> np.ndarray:
    """(K,) the smallest surface gap between the robot and anyone present, per step (inf with nobody)."""
    centres = trace.robot_poses[:, None, :2]
    distance = np.linalg.norm(trace.obstacle_positions - centres, axis=-1)
    gap = distance - trace.obstacle_radii_m[None, :] - trace.robot_radius_m
    return np.nanmin(np.where(np.isfinite(gap), gap, np.inf), axis=1)


def classify(row: dict) -> str:
    """The window's class, first match: ``escaping`` (a quarter of the episode or more in escape: no candidate
    free over the horizon and standing hit), ``standing`` (stood over half of the last 10 s), ``creeping``
    (mean speed under half the nominal speed), else ``detouring`` (moving, on plans that go round people)."""
    if row["statuses"].get("escape", 0.0) >= 0.25:
        return "escaping"
    if row["rest_last10"] > 0.5:
        return "standing"
    if row["mean_speed"] < 0.5 * row["nominal_mps"]:
        return "creeping"
    return "detouring"


def status_table(rows: list[dict]) -> list[str]:
    """Per plan status over all the windows: its share of the cycles, the progress along the path made in it
    and the rate of that progress."""
    cycles: collections.Counter = collections.Counter()
    progress: collections.Counter = collections.Counter()
    for row in rows:
        for status, (n, metres) in row["by_status"].items():
            cycles[status] += n
            progress[status] += metres
    total = max(sum(cycles.values()), 1)
    lines = ["| status | share of cycles | progress [m] | progress rate [m/s] |", "|---|---|---|---|"]
    for status, n in cycles.most_common():
        rate = progress[status] / (n * rows[0]["dt_s"])
        lines.append(f"| {status} | {n / total:.2f} | {progress[status]:.1f} | {rate:+.3f} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--workers", "-w", type=int, default=2)
    parser.add_argument("--longer", type=float, default=0.0, help="also run each episode this many s longer")
    parser.add_argument("--options", type=json.loads, default=None, help="planner options of the runs, as JSON")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    jobs = []
    for folder in args.folders:
        with open(folder / "episodes.csv", newline="") as file:
            rows = list(csv.DictReader(file))
        jobs += [
            (folder, row)
            for row in rows
            if row["planner"] == "viapath" and row["feasible"] == "True" and row["reach_feasible"] == "False"
        ]
    done = Parallel(n_jobs=args.workers)(
        delayed(describe)(
            str(folder / "suite" / f"{row['scenario']}.yaml"),
            int(row["seed"]),
            row["perception"],
            args.longer,
            args.options,
        )
        for folder, row in jobs
    )
    for (folder, _), row in zip(jobs, done):
        row["run"] = str(folder)
        row["class"] = classify(row)
    if args.json:
        print(json.dumps(done, indent=1))
    else:
        for row in done:
            print(json.dumps(row))
    print("classes:", dict(collections.Counter(row["class"] for row in done)))
    strict = collections.Counter(
        name for row in done for name, arrival in row["feasible_at"].items() if arrival is not None
    )
    print(f"of {len(done)} windows, still feasible for the reachable set at:", dict(strict))
    print("\n".join(status_table(done)) if done else "")


if __name__ == "__main__":
    main()
