"""The contacts of bench runs by kind: family, robot at rest or moving, whether the person's forecast saw it
coming (viapath.bench.contact_kinds), and what the planner was doing in the second before.

Usage: python benchmarks/classify_contacts.py OUT [OUT ...] [--workers 2] [--top-speed V [--cell M] [--clearance M]]
       [--options JSON] [--detail] [--json]

Each OUT is a ``viapath bench`` results folder (episodes.csv and the suite's YAML files in OUT/suite). Every
episode with a contact is run again (same scenario, seed and perception; the planner's defaults, so run it with
the tree that wrote OUT) and each contact with a person is classified. ``--options '{"name": value}'``: the planner options the runs were made with (a ``--weights`` preset's).
``--detail`` prints one line per contact. For each contact with the robot at rest it also gives how long the
robot had stood (below 0.05 m/s, the at-fault rule's threshold) and the room the corridor left beside it (half
width less the distance to the path: 0 when it stands on the corridor's edge), summed up after the table.
The table counts contacts (a group walking into the robot counts once per person) and, per family, the episodes
with a contact among the feasible ones (the bench's ``feasible`` column, when present). ``--top-speed V``: also
whether each episode with a contact is feasible for the reachable set (viapath.bench.feasibility) grown at V m/s
instead of the drive's top speed (e.g. the top of the planner's speed set, which its plans and escapes keep to), on
a grid of ``--cell`` m (the bench's 0.1 m; a finer grid over-approximates the free space less), with
``--clearance`` m added to every person's radius (a pass that fits only by a few cm is no pass for a planner
that keeps a safety margin).
"""

from __future__ import annotations

import argparse
import collections
import csv
import json
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed

AT_REST_MPS = 0.05  # the at-fault rule's threshold
EDGE_M = 0.1  # a robot with less room than this to the corridor's edge stands on it


def _feasible_at(scenario, top_speed_mps: float, cell_m: float, clearance_m: float = 0.0) -> bool:
    from viapath.bench.feasibility import scenario_reach

    return bool(scenario_reach(scenario, cell_m, top_speed_mps=top_speed_mps, clearance_m=clearance_m).feasible)


def _episode_kinds(
    yaml_path: str,
    seed: int,
    perception: str,
    top_speed_mps: float | None,
    cell_m: float,
    clearance_m: float,
    options: dict | None = None,
) -> dict:
    from viapath.bench.contact_kinds import contact_kinds
    from viapath.scenarios.loader import load_scenario
    from viapath.sim.loop import run_episode

    scenario = load_scenario(yaml_path)
    feasible_at = "" if top_speed_mps is None else str(_feasible_at(scenario, top_speed_mps, cell_m, clearance_m))
    trace = run_episode(scenario, seed=seed, perception=perception, planner_overrides=options).trace
    out = []
    for contact in contact_kinds(trace):
        step = int(round(contact.time_s / trace.dt_s))
        last_second = trace.plan_status[max(step - int(round(1.0 / trace.dt_s)), 0) : step + 1]
        doing = collections.Counter(last_second).most_common(1)[0][0]
        moving = np.nonzero(trace.robot_speeds_mps[: step + 1] > AT_REST_MPS)[0]
        rest_s = (step - (moving[-1] if len(moving) else -1)) * trace.dt_s
        room_m = -float(trace.path.corridor_excess(trace.robot_poses[step, :2]))
        out.append(
            {
                **contact.__dict__,
                "planner_doing": doing,
                "feasible_at_top_speed": feasible_at,
                "rest_s": rest_s,
                "corridor_room_m": room_m,
            }
        )
    return {"contacts": out}


def classify(
    folders: list[Path],
    workers: int,
    top_speed_mps: float | None = None,
    cell_m: float = 0.1,
    clearance_m: float = 0.0,
    options: dict | None = None,
) -> list[dict]:
    jobs = []
    for folder in folders:
        with open(folder / "episodes.csv", newline="") as file:
            rows = list(csv.DictReader(file))
        jobs += [(folder, row) for row in rows if row["planner"] == "viapath" and row["collision"] == "True"]
    done = Parallel(n_jobs=workers)(
        delayed(_episode_kinds)(
            str(folder / "suite" / f"{row['scenario']}.yaml"),
            int(row["seed"]),
            row["perception"],
            top_speed_mps,
            cell_m,
            clearance_m,
            options,
        )
        for folder, row in jobs
    )
    records = []
    for (folder, row), result in zip(jobs, done):
        for contact in result["contacts"]:
            records.append(
                {
                    "run": str(folder),
                    "scenario": row["scenario"],
                    "family": row["family"],
                    "feasible": row.get("feasible", ""),
                    **contact,
                }
            )
    return records


def resting_line(records: list[dict]) -> str:
    """The contacts at rest: how many on the corridor's edge, and how long the robot had stood (median)."""
    resting = [r for r in records if r["at_rest"]]
    if not resting:
        return "no contact at rest"
    edge = sum(r["corridor_room_m"] < EDGE_M for r in resting)
    stood = float(np.median([r["rest_s"] for r in resting]))
    return (
        f"{len(resting)} at rest: {edge} on the corridor's edge (room < {EDGE_M} m), "
        f"{len(resting) - edge} with room beside; the robot had stood a median {stood:.1f} s"
    )


def table(records: list[dict]) -> list[dict]:
    counts: collections.Counter = collections.Counter()
    for record in records:
        counts[(record["family"], "at rest" if record["at_rest"] else "moving", record["kind"])] += 1
    return [
        {"family": family, "robot": robot, "kind": kind, "contacts": n}
        for (family, robot, kind), n in sorted(counts.items())
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--workers", "-w", type=int, default=2)
    parser.add_argument("--top-speed", type=float, default=None)
    parser.add_argument("--cell", type=float, default=0.1, help="with --top-speed: the grid's cell (m)")
    parser.add_argument(
        "--clearance", type=float, default=0.0, help="with --top-speed: added to every person's radius (m)"
    )
    parser.add_argument(
        "--options", type=json.loads, default=None, help="planner options the runs were made with, as JSON (--weights)"
    )
    parser.add_argument("--detail", action="store_true")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    records = classify(args.folders, args.workers, args.top_speed, args.cell, args.clearance, args.options)
    rows = table(records)
    if args.json:
        print(json.dumps({"contacts": records, "table": rows}, indent=1))
        return
    if args.detail:
        for r in records:
            print(
                f"{r['run']} {r['scenario']} t={r['time_s']:.1f}s person {r['person']} v={r['robot_speed_mps']:.2f}"
                f" {r['kind']} (turn {r['turn_2s_deg']:.0f}°, forecast gap 1 s/2 s before "
                f"{r['forecast_gap_1s_m']:.2f}/{r['forecast_gap_2s_m']:.2f} m) doing {r['planner_doing']}"
                f" feasible={r['feasible']} at top speed={r['feasible_at_top_speed']}"
                f" stood {r['rest_s']:.1f} s, corridor room {r['corridor_room_m']:.2f} m"
            )
    print("| family | robot | kind | contacts |\n|---|---|---|---|")
    for row in rows:
        print(f"| {row['family']} | {row['robot']} | {row['kind']} | {row['contacts']} |")
    doing = collections.Counter(r["planner_doing"] for r in records)
    print(f"\n{len(records)} contacts; planner in the second before: {dict(doing.most_common())}")
    print(resting_line(records))
    episodes = {(r["run"], r["scenario"]): r for r in records}
    feasible = [r for r in episodes.values() if r["feasible"] == "True"]
    line = f"{len(episodes)} episodes with a contact, {len(feasible)} of them feasible"
    if args.top_speed is not None:
        still = sum(r["feasible_at_top_speed"] == "True" for r in feasible)
        line += (
            f", {still} of those feasible at {args.top_speed} m/s on a {args.cell} m grid"
            f" with {args.clearance} m clearance"
        )
    print(line)


if __name__ == "__main__":
    main()
