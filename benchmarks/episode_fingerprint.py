"""Fingerprints of closed-loop episodes, to show that a change leaves episodes bit for bit the same.

    python benchmarks/episode_fingerprint.py [--suite eth-ucy] [--count 10] [--planners viapath,stop,dwa] [--json]

For each (scenario, planner): a SHA-256 of the metrics (all but the wall-clock plan times) and of the
trace's robot poses, commands, obstacle positions and velocities (exact bytes). Run it on two
versions of the code (e.g. ``git stash`` / another checkout on ``PYTHONPATH``) and compare the
output: equal digests mean identical episodes.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys

import numpy as np

from viapath.bench.suites import generate_suite
from viapath.scenarios.models import Scenario
from viapath.sim.loop import run_episode


def fingerprint(episode) -> str:
    digest = hashlib.sha256()
    metrics = {k: v for k, v in episode.metrics.items() if "plan_time" not in k}
    digest.update(json.dumps(metrics, sort_keys=True, default=float).encode())
    trace = episode.trace
    for array in (trace.robot_poses, trace.commands, trace.obstacle_positions, trace.obstacle_velocities):
        digest.update(np.ascontiguousarray(array, dtype=float).tobytes())
    return digest.hexdigest()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="eth-ucy")
    parser.add_argument("--count", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--planners", default="viapath,stop,dwa")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    out = {}
    for data in generate_suite(args.suite, args.count, args.seed):
        scenario = Scenario.model_validate(data)
        for planner in args.planners.split(","):
            out[f"{scenario.name}/{planner}"] = fingerprint(run_episode(scenario, planner=planner))
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        for key, value in out.items():
            print(value[:16], key)
    return 0


if __name__ == "__main__":
    sys.exit(main())
