"""Plan time with static geometry from real scans and 10 people: viapath, p50/p99.

    python benchmarks/bench_static.py [--cycles 300] [--seed 0] [--people 10] [--clock wall|cpu] [--json]

The static layer is made as the laser chain makes it (:mod:`viapath.perception.static_layer`) from two
consecutive real scans of ``leg_tracker_laser/positive_2.bag`` (../shared/data, or $VIAPATH_DATA), the
first as a forward scanner and the second turned round as a backward one at the robot (about 1 500
returns), so the robot stands among real walls and clutter. 40 scenes (cycled) add ``--people`` people
0.8-6 m away walking at 0.3-1.5 m/s; the designated path runs 10 m along +x (corridor ±1.5 m). One cycle
is ``planner.plan(observation)`` after ``reset()``: the guard (which samples the layer into discs), subgoal
tracking, inflation and the decision. The layer's own time (``layer_ms``: marking, thinning, memory) is
timed apart: on a robot it is perception's. Wall clock by default; ``--clock cpu`` takes the thread's CPU
time, which leaves out the waits for a core on a loaded machine. Prints the machine's load average: run it
three times. With ``NUMBA_DISABLE_JIT=1`` the planner's compiled steps run as plain Python (the figures then
say so: ``compiled`` false).
"""

from __future__ import annotations

import argparse
import json
import os
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from viapath import DesignatedPath, Observation, Obstacles, RobotState, jit
from viapath.bench.suites import data_root
from viapath.guard import with_static_rows
from viapath.io.rosbag import read_laser_scans
from viapath.perception.static_layer import StaticObstacleLayer
from viapath.planning import make_planner


def real_layer(first_scan: int = 50):
    bag = Path(data_root()) / "leg_tracker_laser" / "positive_2.bag"
    scans = []
    for index, message in enumerate(read_laser_scans(bag)):
        if index >= first_scan:
            scans.append(message)
        if len(scans) == 2:
            break
    front = scans[0].scanner_model("front")
    rear = replace(scans[1].scanner_model("rear"), mount_yaw_rad=scans[1].scanner_model().mount_yaw_rad + np.pi)
    layer = StaticObstacleLayer((front, rear))
    ranges = [scans[0].ranges_m, scans[1].ranges_m]
    started = time.perf_counter()
    static = layer.update(0.0, np.zeros(3), ranges, np.zeros((0, 2)), np.zeros(0))
    layer_ms = (time.perf_counter() - started) * 1e3
    returns = int(sum(np.isfinite(r).sum() for r in ranges))
    # The robot stands on a designated path, as on a robot: the spot within 3 m of the scanners and the
    # heading whose first 6 m stay clearest of the returns; the layer is moved so that the path runs from
    # the origin along +x.
    points = static.segments.reshape(-1, 2)
    grid = np.stack(np.meshgrid(np.linspace(-3, 3, 25), np.linspace(-3, 3, 25)), -1).reshape(-1, 2)
    best = (-1.0, None, None)
    for angle in np.linspace(-np.pi, np.pi, 36, endpoint=False):
        direction = np.array([np.cos(angle), np.sin(angle)])
        along = np.linspace(0.0, 6.0, 25)
        for spot in grid:
            line = spot + along[:, None] * direction
            clearance = np.hypot(*(line[:, None] - points[None]).transpose(2, 0, 1)).min()
            if clearance > best[0]:
                best = (clearance, spot, angle)
    _, spot, angle = best
    c, s_ = np.cos(-angle), np.sin(-angle)
    static = replace(static, segments=(static.segments - spot) @ np.array([[c, s_], [-s_, c]]))
    return static, returns, layer_ms, (front, rear, ranges)


def scenes(rng, count: int, people: int, static) -> list[Observation]:
    out = []
    for _ in range(count):
        distance = rng.uniform(0.8, 6.0, people)
        bearing = rng.uniform(-np.pi, np.pi, people)
        positions = np.stack([distance * np.cos(bearing), distance * np.sin(bearing)], 1)
        speed, heading = rng.uniform(0.3, 1.5, people), rng.uniform(-np.pi, np.pi, people)
        velocities = np.stack([speed * np.cos(heading), speed * np.sin(heading)], 1)
        out.append(
            Observation(
                0.0,
                RobotState(np.zeros(2), 0.0, 0.2, 0.0, 0.23),
                Obstacles(positions, velocities, np.full(people, 0.25)),
                static,
            )
        )
    return out


CLOCK = [time.perf_counter]


def time_planner(observations, cycles: int) -> dict:
    path = DesignatedPath([[0.0, 0.0], [10.0, 0.0]], half_widths_m=[1.5])
    planner = make_planner("viapath", path, nominal_speed_mps=0.2)
    for observation in observations[:5]:  # warm up (a first compiled call loads from the on-disk cache)
        planner.reset()
        planner.plan(observation)
    samples, statuses = [], {}
    for k in range(cycles):
        observation = observations[k % len(observations)]
        planner.reset()
        clock = CLOCK[0]
        started = clock()
        decision = planner.plan(observation)
        samples.append((clock() - started) * 1e3)
        statuses[decision.plan.status] = statuses.get(decision.plan.status, 0) + 1
    samples = np.array(samples)
    return {
        "p50_ms": float(np.percentile(samples, 50)),
        "p99_ms": float(np.percentile(samples, 99)),
        "max_ms": float(samples.max()),
        "statuses": statuses,
        "compiled": jit.enabled(),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--people", type=int, default=10)
    parser.add_argument("--clock", choices=("wall", "cpu"), default="wall")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    CLOCK[0] = time.perf_counter if args.clock == "wall" else time.thread_time
    static, returns, _layer_ms, (front, rear, ranges) = real_layer()
    layer_times = []
    for _k in range(30):  # the layer's own time, with its memory of the cycle before
        layer = StaticObstacleLayer((front, rear))
        layer.update(0.0, np.zeros(3), ranges, np.zeros((0, 2)), np.zeros(0))
        started = CLOCK[0]()
        layer.update(0.1, np.zeros(3), ranges, np.zeros((0, 2)), np.zeros(0))
        layer_times.append((CLOCK[0]() - started) * 1e3)
    observations = scenes(np.random.default_rng(args.seed), 40, args.people, static)
    merged = with_static_rows(observations[0]).obstacles
    figures = {
        "returns": returns,
        "segments": len(static),
        "static_discs": merged.static_count,
        "people": args.people,
        "layer_p50_ms": float(np.percentile(layer_times, 50)),
        "viapath": time_planner(observations, args.cycles),
        "load_average": os.getloadavg()[0],
        "clock": args.clock,
    }
    if args.json:
        print(json.dumps(figures))
        return
    print(
        f"{returns} returns -> {len(static)} segments -> {merged.static_count} static discs; {args.people} people; "
        f"layer p50 {figures['layer_p50_ms']:.2f} ms; load {figures['load_average']:.1f}"
    )
    for name in ("viapath",):
        f = figures[name]
        print(
            f"  {name} (compiled: {f['compiled']}) p50 {f['p50_ms']:.2f} ms  p99 {f['p99_ms']:.2f} ms  max {f['max_ms']:.2f} ms  "
            f"{f['statuses']}"
        )


if __name__ == "__main__":
    main()
