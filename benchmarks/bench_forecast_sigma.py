"""Does the heading-uncertainty σ of :mod:`viapath.forecast` lower at-fault contacts? A closed-loop check.

    python benchmarks/bench_forecast_sigma.py [--suite eth-ucy] [--count 50] [--planner viapath]
           [--sigma-heading 0.336] [--sigma-floor 0.05] [--json]

Runs each scenario twice with oracle perception: as today (replayed people reported with
``velocity_sigma_mps = 0``), and with ``velocity_sigma_mps = sigma_floor + sigma_heading |v|``
(:func:`viapath.forecast.velocity_sigma_mps`; the default ``sigma_heading`` is the value
``benchmarks/bench_forecast.py`` fits on the training-only files). Positions and velocities are the
same in both runs; only the σ the planner is told changes. Prints success, collision and at-fault
rates of both.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

import viapath.sim.loop as loop
from viapath.bench.suites import generate_suite
from viapath.forecast import velocity_sigma_mps
from viapath.observation import Obstacles
from viapath.perception.oracle import OraclePerception
from viapath.scenarios.models import Scenario


class HeadingSigmaOracle(OraclePerception):
    """True states; each person's velocity σ from the heading-uncertainty model."""

    def __init__(self, sigma_floor_mps: float, sigma_heading_rad: float):
        super().__init__()
        self.sigma_floor_mps, self.sigma_heading_rad = sigma_floor_mps, sigma_heading_rad

    def observe(self, world):
        seen = super().observe(world)
        sigma = velocity_sigma_mps(seen.velocities, self.sigma_floor_mps, self.sigma_heading_rad)
        return Obstacles(
            seen.positions,
            seen.velocities,
            seen.radii_m,
            position_sigma_m=seen.position_sigma_m,
            velocity_sigma_mps=sigma,
            ids=seen.ids,
        )


def run(scenarios, planner, perception_factory=None):
    original = loop.make_perception
    if perception_factory is not None:
        loop.make_perception = lambda *args, **kwargs: perception_factory()
    try:
        rows = []
        for data in scenarios:
            m = loop.run_episode(Scenario.model_validate(data), planner=planner).metrics
            rows.append(
                (
                    bool(m["reached_goal"]) and not m["collision"],
                    bool(m["collision"]),
                    bool(m["at_fault_collision"]),
                    bool(m["reached_goal"]),
                )
            )
    finally:
        loop.make_perception = original
    rows = np.array(rows)
    return {
        "episodes": len(rows),
        "success_rate": float(rows[:, 0].mean()),
        "collision_rate": float(rows[:, 1].mean()),
        "at_fault_collision_rate": float(rows[:, 2].mean()),
        "reached_goal_rate": float(rows[:, 3].mean()),
        "at_fault_episodes": [s["name"] for s, r in zip(scenarios, rows) if r[2]],
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="eth-ucy")
    parser.add_argument("--count", type=int, default=50)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--planner", default="viapath")
    parser.add_argument("--sigma-heading", type=float, default=0.336)
    parser.add_argument("--sigma-floor", type=float, default=0.05)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    scenarios = generate_suite(args.suite, args.count, args.seed)
    started = time.perf_counter()
    report = {
        "suite": args.suite,
        "count": args.count,
        "seed": args.seed,
        "planner": args.planner,
        "today": run(scenarios, args.planner),
        "heading_sigma": run(scenarios, args.planner, lambda: HeadingSigmaOracle(args.sigma_floor, args.sigma_heading)),
        "sigma_floor_mps": args.sigma_floor,
        "sigma_heading_rad": args.sigma_heading,
    }
    report["wall_s"] = time.perf_counter() - started
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print("| forecast σ | episodes | success | collision | at-fault | reached goal |")
    print("|---|---|---|---|---|---|")
    for key in ("today", "heading_sigma"):
        r = report[key]
        print(
            f"| {key} | {r['episodes']} | {r['success_rate']:.1%} | {r['collision_rate']:.1%} | "
            f"{r['at_fault_collision_rate']:.1%} | {r['reached_goal_rate']:.1%} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
