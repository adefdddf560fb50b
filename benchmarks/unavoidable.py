"""Could any command sequence have avoided an at-fault contact? A brute-force oracle that knows the future.

Usage: python benchmarks/unavoidable.py OUT_DIR [--suite DIR] [--planner viapath] [--shield on]
           [--depth 5] [--limit 20] [--weights PRESET] [--json]

For each at-fault onset of a ``viapath bench`` run (re-run with the same seed, as
``benchmarks/shield_faults.py`` does), start from the robot's real state at the step the person was
first present (or ``--depth`` steps before the onset, whichever is later), and try every command
sequence the drive can follow: at each of ``--depth`` steps the speed changes by −a·dt, 0 or +a·dt
and the turn rate by −, −½, 0, +½ or +1 × the turn acceleration·dt (15^depth sequences, every one
within the motion limits), then the hardest braking until rest. Each sequence is judged with the
recorded future of **every** person (not a forecast: the oracle knows where they will walk) by the
at-fault rule of ``viapath.sim.metrics.at_fault_onsets`` (a contact begins in a step that starts with
the robot faster than 0.05 m/s and moving towards that person). If no sequence avoids an at-fault
onset, no planner on this drive could have, whatever it knew: the contact is unavoidable once the
person is there. Replayed people only (a reactive replay's people would move differently).

The search is its own code, not the planner's or the shield's; ``--check`` first replays the
episode's real commands through it and requires the trace's poses and the metric's onsets back.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import json
import math
from pathlib import Path

import numpy as np

from viapath.observation import MotionLimits
from viapath.presets import preset_values
from viapath.scenarios import load_scenario
from viapath.sim import loop
from viapath.sim.metrics import at_fault_onsets, present_for

MIN_SPEED_MPS = 0.05  # the at-fault rule's speed threshold (docs/benchmark.md)
SPEED_STEPS = (-1.0, 0.0, 1.0)  # per step, × max_accel·dt
TURN_STEPS = (-1.0, -0.5, 0.0, 0.5, 1.0)  # per step, × max_turn_accel·dt


def drive(x, y, heading, speed, turn, speed_deltas, turn_deltas, limits: MotionLimits, dt_s: float, braking_steps: int):
    """Poses (K, J+1, 3) and speeds at the start of each step (K, J+1) of K sequences: the given
    per-step changes of speed and turn rate (K, D), then the hardest braking (speed and turn rate
    towards 0 at the limits) for ``braking_steps``. Each step moves along the exact arc, as
    viapath.kinematics.step does."""
    k, depth = speed_deltas.shape
    steps = depth + braking_steps
    poses = np.empty((k, steps + 1, 3))
    speeds = np.empty((k, steps + 1))
    poses[:, 0] = x, y, heading
    speeds[:, 0] = speed
    v = np.full(k, float(speed))
    w = np.full(k, float(turn))
    dv, dw = limits.max_accel_mps2 * dt_s, limits.max_turn_accel_radps2 * dt_s
    for j in range(steps):
        if j < depth:
            v = np.clip(v + speed_deltas[:, j], 0.0, limits.max_speed_mps)
            w = np.clip(w + turn_deltas[:, j], -limits.max_turn_rate_radps, limits.max_turn_rate_radps)
        else:
            v = v + np.clip(-v, -dv, dv)
            w = w + np.clip(-w, -dw, dw)
        px, py, ph = poses[:, j, 0], poses[:, j, 1], poses[:, j, 2]
        half = 0.5 * w * dt_s
        small = np.abs(half) < 1e-6
        sinc = np.where(small, 1.0 - half * half / 6.0, np.sin(half) / np.where(small, 1.0, half))
        chord = v * dt_s * sinc
        poses[:, j + 1, 0] = px + chord * np.cos(ph + half)
        poses[:, j + 1, 1] = py + chord * np.sin(ph + half)
        new_heading = ph + w * dt_s
        poses[:, j + 1, 2] = np.arctan2(np.sin(new_heading), np.cos(new_heading))
        speeds[:, j + 1] = v
    return poses, speeds


def search(trace, first_step: int, depth: int, limits: MotionLimits):
    """Of every sequence from ``first_step``, how many avoid an at-fault onset (with anyone) until rest."""
    dt = trace.dt_s
    braking = int(math.ceil(limits.max_speed_mps / (limits.max_accel_mps2 * dt))) + 2
    dv, dw = limits.max_accel_mps2 * dt, limits.max_turn_accel_radps2 * dt
    choices = np.array(list(itertools.product(SPEED_STEPS, TURN_STEPS)))  # (15, 2)
    combos = np.array(list(itertools.product(range(len(choices)), repeat=depth)))  # (15^D, D)
    speed_deltas, turn_deltas = choices[combos, 0] * dv, choices[combos, 1] * dw
    x, y, heading = trace.robot_poses[first_step]
    poses, speeds = drive(
        x,
        y,
        heading,
        trace.robot_speeds_mps[first_step],
        trace.robot_turn_rates_radps[first_step],
        speed_deltas,
        turn_deltas,
        limits,
        dt,
        braking,
    )
    last = first_step + depth + braking
    people = _people_window(trace, first_step, last)
    # Only people present somewhere in the window matter; sequences in chunks keep the (K, J, N, 2) arrays small.
    columns = np.flatnonzero(np.isfinite(people).all(-1).any(0))
    avoiding = 0
    for chunk in np.array_split(np.arange(len(combos)), max(1, len(combos) // 20_000)):
        faults = _faults(trace, poses[chunk], speeds[chunk], people, first_step, columns)
        avoiding += int((~faults.any(axis=(1, 2))).sum())
    return avoiding, len(combos)


def _people_window(trace, first_step: int, last: int) -> np.ndarray:
    """Recorded positions of steps first_step..last (the last rows repeated past the trace's end)."""
    rows = np.arange(first_step, last + 1)
    return trace.obstacle_positions[np.minimum(rows, len(trace.obstacle_positions) - 1)]


def _faults(trace, poses, speeds, people, first_step: int, columns=None) -> np.ndarray:
    """(K, J, N) at-fault onsets of K sequences starting at ``first_step`` with the people of ``columns``."""
    columns = np.arange(people.shape[1]) if columns is None else columns
    people = people[:, columns]
    radius = trace.robot_radius_m
    radii = trace.obstacle_radii_m[columns]
    if first_step > 0:
        before_start = trace.robot_poses[first_step - 1, :2] - trace.obstacle_positions[first_step - 1, columns]
        before_end = trace.robot_poses[first_step, :2] - trace.obstacle_positions[first_step, columns]
        contact_before = _touching(before_start, before_end, radii + radius)
        absent_before = ~np.isfinite(trace.obstacle_positions[first_step - 1, columns]).all(-1)
    else:
        contact_before = np.zeros(len(radii), dtype=bool)
        absent_before = np.ones(len(radii), dtype=bool)
    present = np.isfinite(people[:-1]).all(-1)  # (J, N)
    appeared = present & np.vstack([absent_before[None], ~present[:-1]])
    # The exemption is judged on the robot's position at the step (the same for every sequence only
    # at the first step; later steps use each sequence's own position).
    gap = np.hypot(*(poses[:, :-1, None, :2] - people[None, :-1]).transpose(3, 0, 1, 2))
    with np.errstate(invalid="ignore"):
        overlapping = appeared[None] & (gap < radii + radius)
    return _at_fault(poses, speeds, people, radii, radius, contact_before, overlapping)


def _at_fault(poses, speeds, people, radii, radius, contact_before, overlapping):
    """(K, J, N): an at-fault onset with person n begins in step j of sequence k (the rule of
    viapath.sim.metrics.at_fault_onsets, written again over K sequences)."""
    start = poses[:, :-1, None, :2] - people[None, :-1]
    end = poses[:, 1:, None, :2] - people[None, 1:]
    contact = _touching(start, end, radii + radius)
    previous = np.concatenate([np.broadcast_to(contact_before, (len(poses), 1, len(radii))), contact[:, :-1]], axis=1)
    heading = poses[:, :-1, 2]
    velocity = speeds[:, :-1, None] * np.stack([np.cos(heading), np.sin(heading)], axis=-1)
    towards = np.einsum("kjd,kjnd->kjn", velocity, -np.nan_to_num(start, nan=1e9)) > 0.0
    return contact & ~previous & towards & (speeds[:, :-1, None] > MIN_SPEED_MPS) & ~overlapping  # (K, J, N)


def _touching(start: np.ndarray, end: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Robot-minus-person offsets at a step's start and end (..., 2), NaN where the person is absent:
    does their distance, moving linearly over the step, come under ``reach``?"""
    present = np.isfinite(start).all(-1) & np.isfinite(end).all(-1)
    start = np.where(present[..., None], start, 1e9)
    motion = np.where(present[..., None], end, 1e9) - start
    speed_sq = np.sum(motion * motion, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = np.clip(np.where(speed_sq > 0, -np.sum(start * motion, axis=-1) / speed_sq, 0.0), 0.0, 1.0)
    closest = start + motion * tau[..., None]
    return present & (np.hypot(closest[..., 0], closest[..., 1]) < reach)


def check_replay(trace, limits: MotionLimits, first_step: int, depth: int) -> None:
    """The search's model against the episode itself: the real commands give the trace's poses and onsets."""
    dt = trace.dt_s
    steps = min(depth, len(trace.robot_poses) - 1 - first_step)
    speeds_true = trace.robot_speeds_mps[first_step : first_step + steps + 1]
    turns_true = trace.robot_turn_rates_radps[first_step : first_step + steps + 1]
    speed_deltas = np.diff(speeds_true)[None]
    turn_deltas = np.diff(turns_true)[None]
    x, y, heading = trace.robot_poses[first_step]
    poses, speeds = drive(x, y, heading, speeds_true[0], turns_true[0], speed_deltas, turn_deltas, limits, dt, 0)
    error = np.max(np.abs(poses[0, :, :2] - trace.robot_poses[first_step : first_step + steps + 1, :2]))
    if error > 1e-9:
        raise SystemExit(f"the search's drive model is off the trace by {error:.2e} m")
    people = _people_window(trace, first_step, first_step + steps)
    mine = _faults(trace, poses, speeds, people, first_step)[0]
    metric = at_fault_onsets(trace)[first_step : first_step + steps]
    if not np.array_equal(mine, metric):
        raise SystemExit("the search's at-fault rule disagrees with viapath.sim.metrics.at_fault_onsets on the trace")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--suite", type=Path, default=None, help="scenario folder (default OUT_DIR/suite)")
    parser.add_argument("--planner", default="viapath")
    parser.add_argument("--shield", default="on")
    parser.add_argument("--depth", type=int, default=5, help="free steps searched (15^depth sequences)")
    parser.add_argument("--limit", type=int, default=20)
    parser.add_argument("--weights", default=None, help="the weights preset the bench ran with (--weights)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    with open(args.out / "episodes.csv") as handle:
        rows = [
            r
            for r in csv.DictReader(handle)
            if r["planner"] == args.planner and r["shield"] == args.shield and r["at_fault_collision"] == "True"
        ]
    overrides = preset_values(args.weights, args.planner) if args.weights else None
    results = []
    for row in rows[: args.limit]:
        scenario = load_scenario((args.suite or args.out / "suite") / f"{row['scenario']}.yaml")
        if any(
            getattr(o, "replay", None) is not None and getattr(o.replay, "react", False)
            for o in getattr(scenario, "obstacles", []) or []
        ):
            continue
        episode = loop.run_episode(
            scenario,
            planner=args.planner,
            seed=int(row["seed"]),
            shield=args.shield != "off",
            planner_overrides=overrides,
            shield_options={"mode": "passive-friendly" if args.shield == "friendly" else "passive"},
        )
        trace = episode.trace
        limits = MotionLimits(**scenario.robot.limits.model_dump())
        onsets = at_fault_onsets(trace)
        seen = present_for(trace, 1.0)
        if not onsets.any():
            print(f"{row['scenario']}: the re-run has no at-fault onset (other options than the bench's? --weights)")
            continue
        for k, person in zip(*np.nonzero(onsets)):
            present = np.flatnonzero(np.isfinite(trace.obstacle_positions[: k + 1, person, 0]))
            appeared = int(present[0])
            first = max(appeared, int(k) - args.depth)
            check_replay(trace, limits, first, args.depth)
            avoiding, tried = search(trace, first, args.depth, limits)
            results.append(
                dict(
                    scenario=row["scenario"],
                    person=int(person),
                    onset_s=float(trace.times_s[k]),
                    appeared_s=float(trace.times_s[appeared]),
                    search_from_s=float(trace.times_s[first]),
                    seen_1s=bool(seen[k, person]),
                    robot_speed_at_search_mps=float(trace.robot_speeds_mps[first]),
                    sequences=tried,
                    avoiding=avoiding,
                    avoidable=avoiding > 0,
                )
            )
    if args.json:
        print(json.dumps(results, indent=2))
        return
    for r in results:
        verdict = (
            f"AVOIDABLE by {r['avoiding']} of {r['sequences']}"
            if r["avoidable"]
            else f"unavoidable: none of {r['sequences']} sequences"
        )
        print(
            f"{r['scenario']} person {r['person']}: onset {r['onset_s']:.1f} s, appeared {r['appeared_s']:.1f} s, "
            f"searched from {r['search_from_s']:.1f} s at {r['robot_speed_at_search_mps']:.2f} m/s: {verdict}"
        )


if __name__ == "__main__":
    main()
