"""One at-fault contact, cycle by cycle: what the robot was told, what it chose, what the shield did.

Usage: python benchmarks/contact_trace.py SCENARIO.yaml PERSON [--from STEP] [--to STEP] [--json]

Runs the scenario with the viapath planner (shield on, oracle perception), then prints one row per cycle
from the person's first appearance (:func:`viapath.sim.metrics.first_seen_steps`) to a few cycles after
their first at-fault onset: the robot's speed, the person's distance, whether the person is in the
observation, the velocity the robot was told against the person's motion over the next cycle (a
replay's velocity is a past-only estimate: the gap between the two is what the shield's forecast must
cover), the plan's status and command, the shield's verdict, and whether the hardest braking was
admissible then. Last, the avoidable search's verdicts (:func:`viapath.bench.avoidable.judge`).
PERSON is the column of the trace (the number in the bench's ``at_fault_detail``).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from viapath.bench.avoidable import judge
from viapath.observation import MotionLimits
from viapath.scenarios import load_scenario
from viapath.sim.loop import run_episode
from viapath.sim.metrics import at_fault_onsets, first_seen_steps


def cycle_row(record, person: int) -> dict:
    """What one cycle's planner and shield saw and did about ``person``."""
    shown = np.asarray(record.observation.obstacles.positions)
    where = record.world.obstacle_positions[person]
    told = bool(len(shown)) and bool(np.any(np.all(np.isclose(shown, where, atol=1e-9), axis=-1)))
    extras = record.decision.plan.extras.get("shield", {})
    brake_ok = None
    shield = getattr(record.planner, "shield", None)
    if shield is not None:
        brake_ok = bool(shield.evaluate(record.observation, np.zeros((1, 2)))["admissible"][0])
    command = record.decision.command
    return {
        "step": record.step,
        "time_s": round(record.time_s, 2),
        "speed_mps": round(record.state.speed_mps, 3),
        "in_observation": told,
        "status": record.decision.plan.status,
        "command": [round(command.speed_mps, 3), round(command.turn_rate_radps, 3)],
        "shield": extras.get("reason"),
        "braking_admissible": brake_ok,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", type=Path)
    parser.add_argument("person", type=int)
    parser.add_argument("--from", dest="first", type=int, default=None, help="first step (default: appearance)")
    parser.add_argument("--to", dest="last", type=int, default=None, help="last step (default: onset + 3)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    scenario = load_scenario(args.scenario)
    records: dict[int, dict] = {}
    episode = run_episode(
        scenario, planner="viapath", on_step=lambda r: records.update({r.step: cycle_row(r, args.person)})
    )
    trace = episode.trace
    appeared = int(first_seen_steps(trace.obstacle_positions)[args.person])
    onsets = np.flatnonzero(at_fault_onsets(trace)[:, args.person])
    first = appeared if args.first is None else args.first
    last = (int(onsets[0]) + 3 if len(onsets) else appeared + 30) if args.last is None else args.last
    rows = []
    for k in range(first, min(last, len(trace.times_s) - 2) + 1):
        row = dict(records.get(k, {"step": k}))
        here, after = trace.obstacle_positions[k, args.person], trace.obstacle_positions[k + 1, args.person]
        row["distance_m"] = round(float(np.hypot(*(here - trace.robot_poses[k, :2]))), 3)
        row["told_velocity_mps"] = np.round(trace.obstacle_velocities[k, args.person], 3).tolist()
        row["next_cycle_velocity_mps"] = np.round((after - here) / trace.dt_s, 3).tolist()
        rows.append(row)
    limits = MotionLimits(**scenario.robot.limits.model_dump())
    verdicts = [
        {"person": v.person, "onset_s": round(v.onset_s, 2), "appeared_s": round(v.appeared_s, 2), "reason": v.reason}
        for v in judge(trace, limits)
    ]
    if args.json:
        print(
            json.dumps({"appeared_step": appeared, "onset_steps": onsets.tolist(), "cycles": rows, "search": verdicts})
        )
        return
    print(f"person {args.person}: first seen at step {appeared}, at-fault onsets at steps {onsets.tolist()}")
    for row in rows:
        print(" ".join(f"{key}={value}" for key, value in row.items()))
    for verdict in verdicts:
        print("search:", verdict)


if __name__ == "__main__":
    main()
