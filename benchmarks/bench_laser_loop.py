"""Laser loop speed: two simulated URG-04LX scans (683 beams each), 10 people, tracking.

    python benchmarks/bench_laser_loop.py [--steps 600] [--loop-steps 300] [--runs 3] [--options JSON] [--json]

Two figures, ``--runs`` times:
* ``laser_steps_per_s``: the laser chain alone, one step = ray casting of both scanners (with
  range noise), fusion, segmentation, circle fits, association, tracking and the static layer
  (``LaserPerception.observe``) on the scene of ``bench_perception.py`` (10 people circling a robot
  driving between two walls; all stay in view).
* ``closed_loop_steps_per_s``: ``viapath.sim.loop.run_episode`` with laser perception on the
  closed-loop scene of ``bench_perception.py`` (10 people, viapath planner + shield): laser chain
  plus planning plus simulation.
``--options``: the laser perception's options as JSON (default ``{"detector": {"keep_segments": false}}``),
e.g. to run an older checkout with the arithmetic it was fastest with. The load average is printed with
each run, and each figure is given per wall-clock second and per second of this process's CPU time
(steadier on a shared machine; equal on an idle one). Not a test: numbers depend on the machine.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_perception import scene

from viapath.jit import enabled
from viapath.perception.laser import LaserPerception

DEFAULT_OPTIONS = {"detector": {"keep_segments": False}}


def laser_chain(options: dict, steps: int) -> tuple[float, float]:
    worlds = [scene(10, k) for k in range(steps)]
    perception = LaserPerception(**options)
    perception.reset(np.random.default_rng(1))
    for world in worlds[:20]:  # warm-up (and numba's cache load)
        perception.observe(world)
    perception.reset(np.random.default_rng(1))
    started, cpu = time.perf_counter(), time.process_time()
    for world in worlds:
        perception.observe(world)
    return steps / (time.perf_counter() - started), steps / (time.process_time() - cpu)


def closed_loop_scenario(options: dict, steps: int):
    from viapath.scenarios import scenario_from_dict

    rng = np.random.default_rng(3)
    obstacles = []
    for _ in range(10):
        y = rng.uniform(-3.0, 3.0)
        x = rng.uniform(2.0, 14.0)
        obstacles.append(
            {
                "start": [float(x), float(y)],
                "velocity": [float(rng.uniform(-0.4, 0.4)), float(-np.sign(y) * 0.1)],
                "radius": 0.25,
            }
        )
    return scenario_from_dict(
        {
            "name": "bench-10",
            "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.2, "radius": 0.25},
            "path": {"waypoints": [[0.0, 0.0], [15.0, 0.0]], "half_width": 1.5},
            "obstacles": obstacles,
            "walls": [[[-2.0, -4.0], [20.0, -4.0]], [[-2.0, 4.0], [20.0, 4.0]]],
            "duration_s": steps * 0.1,
            "perception": {"mode": "laser", "options": options},
        }
    )


def closed_loop(options: dict, steps: int) -> tuple[float, float]:
    from viapath.sim.loop import run_episode

    scenario = closed_loop_scenario(options, steps)
    run_episode(scenario, seed=0)
    started, cpu = time.perf_counter(), time.process_time()
    episode = run_episode(scenario, seed=0)
    n = len(episode.trace.times_s)
    return n / (time.perf_counter() - started), n / (time.process_time() - cpu)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=600, help="laser-chain steps per run")
    parser.add_argument("--loop-steps", type=int, default=300, help="closed-loop steps per run (0: skip)")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--options", type=json.loads, default=DEFAULT_OPTIONS, help="laser options, JSON")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    results = {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "compiled": enabled(),
        "options": args.options,
        "runs": [],
    }
    for run in range(args.runs):
        row = {"run": run + 1, "load_average": os.getloadavg()}
        row["laser_steps_per_s"], row["laser_steps_per_cpu_s"] = laser_chain(args.options, args.steps)
        if args.loop_steps > 0:
            row["closed_loop_steps_per_s"], row["closed_loop_steps_per_cpu_s"] = closed_loop(
                args.options, args.loop_steps
            )
        results["runs"].append(row)
        if not args.json:
            load = " ".join(f"{v:.2f}" for v in row["load_average"])
            figures = "  ".join(f"{k.replace('_steps_per', '')} {v:6.0f}" for k, v in row.items() if "steps" in k)
            print(f"run {run + 1} (load {load}): steps per wall s / per CPU s:  {figures}")
    if args.json:
        print(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
