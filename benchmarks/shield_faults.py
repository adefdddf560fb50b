"""Look at the contacts left with the shield on: per at-fault onset, what the robot and the shield did.

Usage: python benchmarks/shield_faults.py OUT_DIR [--planner viapath] [--shield on] [--limit 10] [--suite DIR]

Reads OUT_DIR/episodes.csv and the suite OUT_DIR/suite/*.yaml of a ``viapath bench`` run, re-runs
each episode with an at-fault contact (same seed) and prints, for the step where that contact
begins and the few before it: robot speed, command, whether the shield intervened and why, the
person's speed and whether it had been seen (present in the scene) for long.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path
from typing import ClassVar

import numpy as np

from viapath.safety import shielded as shielded_factory
from viapath.safety.shielded import ShieldedPlanner
from viapath.scenarios import load_scenario
from viapath.sim import loop
from viapath.sim.metrics import at_fault_onsets, present_for


class _Recording(ShieldedPlanner):
    log: ClassVar[list] = []

    def plan(self, observation):
        decision = super().plan(observation)
        _Recording.log.append(
            dict(decision.plan.extras.get("shield", {}), status=decision.plan.status, time_s=observation.time_s)
        )
        return decision


def _recording_shielded(planner, shield, dt_s, options=None, planner_name=None):
    wrapped = shielded_factory(planner, shield, dt_s, options, planner_name)
    if isinstance(wrapped, ShieldedPlanner):
        return _Recording(wrapped.inner, dt_s, wrapped.shield.config)
    return wrapped


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--planner", default="viapath")
    parser.add_argument("--shield", default="on")
    parser.add_argument("--limit", type=int, default=10)
    parser.add_argument("--suite", type=Path, default=None, help="scenario folder (default OUT_DIR/suite)")
    args = parser.parse_args()
    with open(args.out / "episodes.csv") as handle:
        rows = [
            r
            for r in csv.DictReader(handle)
            if r["planner"] == args.planner and r["shield"] == args.shield and r["at_fault_collision"] == "True"
        ]
    print(f"{len(rows)} at-fault episodes for {args.planner} with shield {args.shield}")
    loop.shielded = _recording_shielded
    mode = "passive-friendly" if args.shield == "friendly" else "passive"
    for row in rows[: args.limit]:
        scenario = load_scenario((args.suite or args.out / "suite") / f"{row['scenario']}.yaml")
        _Recording.log = []
        episode = loop.run_episode(
            scenario,
            planner=args.planner,
            seed=int(row["seed"]),
            shield=args.shield != "off",
            shield_options={"mode": mode},
        )
        trace = episode.trace
        onsets = at_fault_onsets(trace)
        seen = present_for(trace, 1.0)
        for k, person in zip(*np.nonzero(onsets)):
            rel = trace.obstacle_positions[k, person] - trace.robot_poses[k, :2]
            person_speed = float(np.hypot(*trace.obstacle_velocities[k, person]))
            print(
                f"\n{row['scenario']} seed {row['seed']}: onset at t={trace.times_s[k]:.1f} s with person {person} "
                f"(speed {person_speed:.2f} m/s, seen >= 1 s: {bool(seen[k, person])}, "
                f"distance {np.hypot(*rel):.2f} m)"
            )
            for j in range(max(0, k - 5), k + 1):
                entry = _Recording.log[j] if j < len(_Recording.log) else {}
                first_seen = np.flatnonzero(np.isfinite(trace.obstacle_positions[: j + 1, person, 0]))
                print(
                    f"  t={trace.times_s[j]:5.1f} v={trace.robot_speeds_mps[j]:.2f} cmd=({trace.commands[j, 0]:.2f},"
                    f"{trace.commands[j, 1]:+.2f}) {entry.get('status', '')} shield: "
                    f"{'INTERVENED ' if entry.get('intervened') else ''}{entry.get('reason', '')} "
                    f"[person present since t={trace.times_s[first_seen[0]] if len(first_seen) else float('nan'):.1f}]"
                )


if __name__ == "__main__":
    main()
