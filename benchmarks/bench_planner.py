"""Planning time per cycle of the viapath planner: p50/p99 for 1, 10, 50 and 100 obstacles.

Usage: python benchmarks/bench_planner.py [--cycles 400] [--seed 0]

Scenes: the robot at the start of a 10 m designated path (corridor ±1.5 m), obstacles placed
uniformly within 8 m, walking at 0.3-1.5 m/s in random directions, none overlapping the robot;
only scenes where the straight leg at nominal speed is blocked are kept, so every cycle runs the
full search (6 speeds: the paper's five plus the current one). Single thread.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from viapath import DesignatedPath, Obstacles, Observation, RobotState
from viapath.planning import make_planner


def random_scene(rng, n_obstacles, path, planner):
    while True:
        distance = rng.uniform(0.8, 8.0, n_obstacles)
        bearing = rng.uniform(-np.pi, np.pi, n_obstacles)
        positions = np.stack([distance * np.cos(bearing), distance * np.sin(bearing)], 1)
        speed = rng.uniform(0.3, 1.5, n_obstacles)
        direction = rng.uniform(-np.pi, np.pi, n_obstacles)
        velocities = np.stack([speed * np.cos(direction), speed * np.sin(direction)], 1)
        obstacles = Obstacles(positions, velocities, np.full(n_obstacles, 0.25))
        observation = Observation(0.0, RobotState(np.zeros(2), 0.0, 0.23), obstacles)
        planner.reset()
        if planner.plan(observation).plan.status != "straight" or n_obstacles == 0:
            return observation


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=400)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    path = DesignatedPath([[0.0, 0.0], [10.0, 0.0]], half_width_m=1.5)
    planner = make_planner("viapath", path, nominal_speed_mps=0.2)
    print(f"viapath planner, {args.cycles} cycles per row, pid {os.getpid()}, single thread")
    print(f"{'obstacles':>9} {'p50 ms':>8} {'p99 ms':>8} {'max ms':>8} {'candidates':>10}")
    for n_obstacles in (1, 10, 50, 100):
        scenes = [random_scene(rng, n_obstacles, path, planner) for _ in range(40)]
        for scene in scenes[:5]:  # warm-up
            planner.plan(scene)
        samples, candidates = [], []
        for i in range(args.cycles):
            scene = scenes[i % len(scenes)]
            planner.reset()
            start = time.perf_counter()
            decision = planner.plan(scene)
            samples.append((time.perf_counter() - start) * 1e3)
            candidates.append(decision.plan.candidate_count)
        p50, p99 = np.percentile(samples, [50, 99])
        print(f"{n_obstacles:>9} {p50:>8.3f} {p99:>8.3f} {max(samples):>8.3f} {np.median(candidates):>10.0f}")


if __name__ == "__main__":
    main()
