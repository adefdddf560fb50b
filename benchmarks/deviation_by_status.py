"""Where a planner's lateral deviation accrues: each episode's mean |lateral deviation| split by what
the viapath planner was doing in each step (plan status: ``avoid`` = heading for a via point,
``straight`` = heading for the subgoal or the way back with no via point, ``slow``, ``wait``,
``escape``, ...). docs/howto/tune-weights.md §6.

    python benchmarks/deviation_by_status.py SUITE_FOLDER PRESET[,PRESET...] [FAMILY ...] [--seed 0]

A PRESET is a preset name or file, optionally with options after ``+``:
``passing+return_lookahead_m=0.5``. Episodes run as ``viapath bench`` runs them (same episode seeds,
shield on). Prints, per family and preset, the mean over episodes of each status's share of the
episode's mean deviation (the shares add up to the episode's mean deviation).
"""

from __future__ import annotations

import argparse
import collections
from pathlib import Path

import numpy as np
import yaml

from viapath.bench.runner import episode_seed, family_of
from viapath.presets import preset_values
from viapath.scenarios import scenario_from_dict
from viapath.sim.loop import run_episode


def options_of(spec: str) -> dict:
    name, *extra = spec.split("+")
    options = dict(preset_values(name))
    for item in extra:
        key, value = item.split("=", 1)
        options[key] = yaml.safe_load(value)
    return options


def shares(episode) -> dict[str, float]:
    """Each plan status's part of the episode's mean |lateral deviation| (m)."""
    trace = episode.trace
    lateral = np.abs(trace.path.lateral_deviation(trace.robot_poses[:, :2]))
    status = list(trace.plan_status) + ["end"] * (len(lateral) - len(trace.plan_status))
    parts = collections.Counter()
    for value, name in zip(lateral, status):
        parts[name] += value / len(lateral)
    return dict(parts)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("suite", type=Path)
    parser.add_argument("presets")
    parser.add_argument("families", nargs="*")
    parser.add_argument("--seed", type=int, default=0, help="bench seed (episode seeds as viapath bench)")
    args = parser.parse_args()
    files = sorted(args.suite.glob("*.yaml"))
    if args.families:
        files = [f for f in files if family_of(f.stem) in args.families]
    totals: dict[tuple, collections.Counter] = collections.defaultdict(collections.Counter)
    counts: collections.Counter = collections.Counter()
    for file in files:
        data = yaml.safe_load(file.read_text())
        name = data.get("name", file.stem)
        for spec in args.presets.split(","):
            episode = run_episode(
                scenario_from_dict(data, name),
                planner="viapath",
                seed=episode_seed(args.seed, name),
                planner_overrides=options_of(spec),
            )
            key = (family_of(name), spec)
            totals[key].update(shares(episode))
            totals[key]["all"] += episode.metrics["mean_lateral_deviation_m"]
            counts[key] += 1
    for key in sorted(totals):
        parts = {status: value / counts[key] for status, value in totals[key].items()}
        listed = ", ".join(
            f"{status} {value:.3f}" for status, value in sorted(parts.items(), key=lambda kv: -kv[1]) if value >= 0.0005
        )
        print(f"{key[0]:12s} {key[1]:40s} episodes {counts[key]:3d}: {listed}")


if __name__ == "__main__":
    main()
