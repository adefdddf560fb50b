"""Soak run: hours of simulated time with a crowd and laser perception, every cycle checked (issue 12).

Usage: python benchmarks/soak.py [--sim-hours 1.0] [--people 50] [--planner viapath] [--seed 0]
                                 [--report-every-s 300] [--json]

A 24 m x 8 m hall (walls the scanners see) with ``--people`` people walking straight at 0.3-1.0 m/s
and bouncing off the walls (they do not avoid the robot or each other: a harsh crowd). The robot
drives a 20 m designated path (half-width 1.5 m) from one end to the other and back, a fresh planner
per leg, perceiving with the paper's two simulated URG-04LX scanners through the robot-side chain
(:meth:`LaserPerception.scan` then :meth:`LaserPerception.process`, i.e. detection and tracking as a
robot runs them; ``observe`` is not used because the simulator's bookkeeping for tracking-error
metrics keeps every cycle). Every cycle is checked: the command is finite and inside the motion
limits, and no exception escapes. Memory: the process RSS (``/proc/self/statm``) and the Python heap
(``tracemalloc``, off by default as it slows the run: ``--tracemalloc``) are sampled every
``--report-every-s`` simulated seconds; "flat" is judged on the growth after the first sample.

Printed: cycles, bad commands (must be 0), exceptions (must be 0), legs completed, contacts
(onsets; at-fault = robot moving towards the person, as the benchmark's metric), guard statuses,
plan and perception times (p50 / p99 ms), RSS at each sample and its growth per simulated hour.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import tracemalloc
from collections import Counter

import numpy as np

from viapath.kinematics import UnicycleState, step
from viapath.observation import Command, MotionLimits, Observation, RobotState
from viapath.path import DesignatedPath
from viapath.perception.laser import LaserPerception
from viapath.planning import make_planner
from viapath.sim.perception import WorldSnapshot

HALL_X = (-2.0, 22.0)
HALL_Y = (-4.0, 4.0)
DT_S = 0.1


def rss_mb() -> float:
    with open("/proc/self/statm") as handle:
        pages = int(handle.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 1e6


def hall_walls() -> np.ndarray:
    (x0, x1), (y0, y1) = HALL_X, HALL_Y
    corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    return np.array([[corners[i], corners[(i + 1) % 4]] for i in range(4)], dtype=float)


class Crowd:
    def __init__(self, count: int, rng: np.random.Generator, radius_m: float = 0.25):
        self.radius_m = radius_m
        self.positions = np.column_stack(
            [rng.uniform(HALL_X[0] + 0.5, HALL_X[1] - 0.5, count), rng.uniform(HALL_Y[0] + 0.5, HALL_Y[1] - 0.5, count)]
        )
        # Nobody starts on the robot's start.
        close = np.hypot(*self.positions.T) < 1.5
        self.positions[close, 1] = np.where(self.positions[close, 1] >= 0, 2.5, -2.5)
        speed = rng.uniform(0.3, 1.0, count)
        angle = rng.uniform(-math.pi, math.pi, count)
        self.velocities = np.column_stack([speed * np.cos(angle), speed * np.sin(angle)])
        self.radii = np.full(count, radius_m)

    def step(self, dt: float) -> None:
        self.positions += self.velocities * dt
        for axis, (low, high) in enumerate((HALL_X, HALL_Y)):
            low, high = low + self.radius_m, high - self.radius_m
            below, above = self.positions[:, axis] < low, self.positions[:, axis] > high
            self.positions[below, axis] = 2 * low - self.positions[below, axis]
            self.positions[above, axis] = 2 * high - self.positions[above, axis]
            self.velocities[below | above, axis] *= -1


def run(
    sim_hours: float,
    people: int,
    planner_name: str,
    seed: int,
    report_every_s: float,
    use_tracemalloc: bool,
    progress: bool,
) -> dict:
    rng = np.random.default_rng(seed)
    limits = MotionLimits()
    radius = 0.25
    crowd = Crowd(people, rng)
    walls = hall_walls()
    perception = LaserPerception()
    perception.reset(np.random.default_rng(seed + 1))
    ends = [np.array([0.0, 0.0]), np.array([20.0, 0.0])]
    leg = 0

    def new_planner(start, goal):
        path = DesignatedPath(np.array([start, goal]), half_widths_m=np.array([1.5]))
        return make_planner(planner_name, path, nominal_speed_mps=0.3, limits=limits, robot_radius_m=radius)

    planner = new_planner(ends[0], ends[1])
    state = UnicycleState(0.0, 0.0, 0.0, 0.0, 0.0)
    cycles = int(round(sim_hours * 3600.0 / DT_S))
    statuses: Counter[str] = Counter()
    bad_commands, exceptions = [], []  # stay empty in a good run (checked: both must be 0)
    # Preallocated, so that the script's own bookkeeping does not grow with the run.
    plan_ms, perception_ms = np.full(cycles, np.nan), np.full(cycles, np.nan)
    in_contact = np.zeros(people, dtype=bool)
    contacts = at_fault = 0
    samples = []
    if use_tracemalloc:
        tracemalloc.start()
    started = time.perf_counter()
    every = max(1, int(round(report_every_s / DT_S)))
    for k in range(cycles):
        t = k * DT_S
        pose = np.array([state.x, state.y, state.heading_rad])
        world = WorldSnapshot(t, pose, radius, crowd.positions.copy(), crowd.velocities.copy(), crowd.radii, walls)
        try:
            tick = time.perf_counter()
            scans = perception.scan(world)
            obstacles = perception.process(t, pose, scans)
            tock = time.perf_counter()
            decision = planner.plan(
                Observation(
                    t,
                    RobotState(state.position, state.heading_rad, state.speed_mps, state.turn_rate_radps, radius),
                    obstacles,
                )
            )
            perception_ms[k] = (tock - tick) * 1e3
            plan_ms[k] = (time.perf_counter() - tock) * 1e3
        except Exception as error:
            exceptions.append(f"t={t:.1f}: {type(error).__name__}: {error}")
            decision = None
        if decision is None:
            command = None
        else:
            command = decision.command
            statuses[decision.plan.status] += 1
            v, w = command.speed_mps, command.turn_rate_radps
            if not (
                math.isfinite(v)
                and math.isfinite(w)
                and -1e-9 <= v <= limits.max_speed_mps + 1e-9
                and abs(w) <= limits.max_turn_rate_radps + 1e-9
            ):
                bad_commands.append(f"t={t:.1f}: ({v}, {w})")
        # Contacts: onsets, at-fault when the robot moved towards the person at > 0.05 m/s.
        offsets = crowd.positions - state.position
        gap = np.hypot(*offsets.T) - radius - crowd.radii
        touching = gap < 0
        onset = touching & ~in_contact
        if onset.any():
            contacts += int(onset.sum())
            heading = np.array([math.cos(state.heading_rad), math.sin(state.heading_rad)])
            towards = (offsets[onset] @ heading) > 0
            at_fault += int(np.sum(towards & (state.speed_mps > 0.05)))
        in_contact = touching
        state = step(state, command if command is not None else Command.stop(), limits, DT_S)
        crowd.step(DT_S)
        if np.hypot(*(state.position - ends[(leg + 1) % 2])) < 0.3:
            leg += 1
            planner = new_planner(ends[leg % 2], ends[(leg + 1) % 2])
        if (k + 1) % every == 0 or k == cycles - 1:
            sample = {
                "sim_s": round((k + 1) * DT_S, 1),
                "wall_s": round(time.perf_counter() - started, 1),
                "rss_mb": round(rss_mb(), 1),
            }
            if use_tracemalloc:
                sample["heap_mb"] = round(tracemalloc.get_traced_memory()[0] / 1e6, 2)
            samples.append(sample)
            if progress:
                print(f"  {sample}", file=sys.stderr, flush=True)
    wall = time.perf_counter() - started
    first, last = samples[0], samples[-1]
    hours_between = max((last["sim_s"] - first["sim_s"]) / 3600.0, 1e-9)
    result = {
        "sim_hours": sim_hours,
        "people": people,
        "planner": planner_name,
        "seed": seed,
        "cycles": cycles,
        "bad_commands": len(bad_commands),
        "bad_command_examples": bad_commands[:5],
        "exceptions": len(exceptions),
        "exception_examples": exceptions[:5],
        "legs_completed": leg,
        "contact_onsets": contacts,
        "at_fault_onsets": at_fault,
        "statuses": dict(statuses.most_common()),
        "plan_p50_ms": float(np.nanpercentile(plan_ms, 50)),
        "plan_p99_ms": float(np.nanpercentile(plan_ms, 99)),
        "perception_p50_ms": float(np.nanpercentile(perception_ms, 50)),
        "perception_p99_ms": float(np.nanpercentile(perception_ms, 99)),
        "wall_s": wall,
        "memory_samples": samples,
        "rss_growth_mb_per_sim_hour_after_first_sample": (last["rss_mb"] - first["rss_mb"]) / hours_between,
    }
    if use_tracemalloc:
        result["heap_growth_mb_per_sim_hour_after_first_sample"] = (last["heap_mb"] - first["heap_mb"]) / hours_between
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sim-hours", type=float, default=1.0)
    parser.add_argument("--people", type=int, default=50)
    parser.add_argument("--planner", default="viapath")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--report-every-s", type=float, default=300.0)
    parser.add_argument("--tracemalloc", action="store_true")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    result = run(
        args.sim_hours, args.people, args.planner, args.seed, args.report_every_s, args.tracemalloc, progress=True
    )
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for key, value in result.items():
            print(f"{key}: {value}")
    return 0 if result["bad_commands"] == 0 and result["exceptions"] == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
