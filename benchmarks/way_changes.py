"""Why viapath changes its way round under perception noise: each cycle's change, by reason.

Usage: python benchmarks/way_changes.py [--scenario overtaking] [--seeds 4] [--position-noise 0.03]
                                        [--velocity-noise 0.05] [--json]

Each run is the built-in scenario with oracle perception noise (fresh Gaussian noise every cycle, σ per
axis, as ``viapath run --position-noise/--velocity-noise``), seeds 0..N-1. The planner marks a cycle
whose way round differs from the previous cycle's in ``plan.extras``: ``way_change`` is ``cost`` (the
previous way was still among the candidates and cost more), ``gone`` (it was not, and there was no
uncertainty inflation to relax), ``gone_relaxed_too`` (not even with ``keep_previous_inflation`` of the
inflation: the forecast itself moved, not only its inflation), ``relaxed_costs_more`` (found relaxed,
dearer); ``kept_previous_way`` marks the cycles the relaxed search kept it. Cycles without a free
candidate (stop, escape) are counted by status. Printed per seed and in total, with the side flips,
command flips and time to the goal the bench reports.
"""

from __future__ import annotations

import argparse
import json
from collections import Counter

from viapath.scenarios.loader import load_scenario
from viapath.sim.loop import run_episode
from viapath.sim.step_record import StepRecord

REASONS = ("cost", "gone", "gone_relaxed_too", "relaxed_costs_more", "kept_previous_way")
NO_CHOICE = ("stop", "escape")


def count_changes(scenario_name: str, seed: int, position_noise_m: float, velocity_noise_mps: float) -> dict:
    """One noisy run: its way changes by reason, the cycles without a free candidate, and its metrics."""
    changes: Counter[str] = Counter()

    def on_step(record: StepRecord) -> None:
        plan = record.decision.plan
        if plan.extras.get("kept_previous_way"):
            changes["kept_previous_way"] += 1
        reason = plan.extras.get("way_change")
        if reason is not None:
            changes[reason] += 1
        if plan.status in NO_CHOICE:
            changes[plan.status] += 1
        changes["cycles"] += 1

    episode = run_episode(
        load_scenario(scenario_name),
        seed=seed,
        position_noise_m=position_noise_m,
        velocity_noise_mps=velocity_noise_mps,
        on_step=on_step,
    )
    metrics = episode.metrics
    return {
        "seed": seed,
        **{key: changes[key] for key in ("cycles", *REASONS, *NO_CHOICE)},
        "plan_side_flips": metrics["plan_side_flips"],
        "command_flips": metrics["command_flips"],
        "reached_goal": metrics["reached_goal"],
        "time_to_goal_s": metrics["time_to_goal_s"],
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="overtaking", help="a built-in scenario or a YAML file")
    parser.add_argument("--seeds", type=int, default=4, help="runs, seeds 0..N-1")
    parser.add_argument("--position-noise", type=float, default=0.03, help="σ of reported positions, m")
    parser.add_argument("--velocity-noise", type=float, default=0.05, help="σ of reported velocities, m/s")
    parser.add_argument("--json", action="store_true", help="print the rows as JSON")
    args = parser.parse_args(argv)
    rows = [count_changes(args.scenario, seed, args.position_noise, args.velocity_noise) for seed in range(args.seeds)]
    total = {key: sum(row[key] for row in rows) for key in ("cycles", *REASONS, *NO_CHOICE)}
    if args.json:
        print(json.dumps({"scenario": args.scenario, "runs": rows, "total": total}, indent=2))
        return
    columns = ("seed", "cycles", *REASONS, *NO_CHOICE, "plan_side_flips", "command_flips", "time_to_goal_s")
    widths = [max(len(name), 6) for name in columns]
    print(" ".join(f"{name:>{width}}" for name, width in zip(columns, widths)))
    for row in rows:
        print(" ".join(f"{row[name]!s:>{width}}" for name, width in zip(columns, widths)))
    print(
        " ".join(
            f"{total.get(name, 'total' if name == 'seed' else '')!s:>{width}}" for name, width in zip(columns, widths)
        )
    )


if __name__ == "__main__":
    main()
