"""A person appears 1.3 m ahead of the robot (0.3 m/s) walking straight at it at 1.7 m/s: what the robot commands in
the cycle they are first seen, per perception mode.

Usage: python benchmarks/first_seen.py [--modes oracle,tracked,laser] [--sigma 0.03] [--confirmed-only] [--json]

The person is a replayed track whose first sample is at 2.0 s (viapath.sim.metrics.first_seen_steps: the first
step with a position sample, the cycle the simulator hands them to the perception, the step the avoidable search
starts from). One row per mode: the cycle the planner is first told of them, the command then, the robot's speed
at the contact (if any) and whether it was at fault. ``tracked`` gives the detections a σ of ``--sigma`` per axis.
``--confirmed-only``: the trackers report confirmed tracks only (``report_tentative_within_m`` = 0), for comparison.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

from viapath.scenarios import scenario_from_dict
from viapath.sim.loop import run_episode
from viapath.sim.metrics import first_seen_steps

ROW_S = 0.4  # the replay's row step


def scenario(folder: Path):
    rows = [f"{50 + 10 * i}\t1\t{1.9 - 1.7 * ROW_S * i:.4f}\t0.1" for i in range(12)]
    file = folder / "walker.txt"
    file.write_text("\n".join(rows) + "\n")
    return scenario_from_dict(
        {
            "name": "appears-close",
            "dt_s": 0.1,
            "duration_s": 6.0,
            "robot": {"start": [0, 0], "heading": 0, "radius": 0.25, "speed": 0.3},
            "path": {"waypoints": [[0, 0], [8, 0]], "half_width": 1.0},
            "obstacles": [{"replay": {"file": str(file), "dt_s": ROW_S, "radius": 0.25}}],
        },
        "appears-close",
    )


def run_one(mode: str, sigma_m: float, folder: Path) -> dict:
    noise = {"position_noise_m": sigma_m} if mode == "tracked" else {}
    episode = run_episode(scenario(folder), perception=mode, record_perceived=True, **noise)
    trace = episode.trace
    first = int(first_seen_steps(trace.obstacle_positions)[0])
    told = next(k for k, seen in enumerate(trace.perceived) if len(seen))
    onsets = [s for t, who, s in _contacts(trace)]
    return {
        "mode": mode,
        "first_seen_s": round(float(trace.times_s[first]), 2),
        "told_s": round(float(trace.times_s[told]), 2),
        "distance_when_seen_m": round(
            float(np.hypot(*(trace.obstacle_positions[first, 0] - trace.robot_poses[first, :2]))), 2
        ),
        "command_before_mps": round(float(trace.commands[first - 1, 0]), 3),
        "command_when_seen_mps": round(float(trace.commands[first, 0]), 3),
        "status_when_seen": trace.plan_status[first],
        "speed_at_contact_mps": round(onsets[0], 3) if onsets else None,
        "at_fault": bool(episode.metrics["at_fault_collision"]),
    }


def _confirmed_only() -> None:
    """Every tracker this process makes reports confirmed tracks only (the perception models make their own)."""
    import functools

    from viapath.perception import laser, oracle

    for module in (laser, oracle):
        module.TrackerParams = functools.partial(module.TrackerParams, report_tentative_within_m=0.0)  # type: ignore[misc]


def _contacts(trace):
    from viapath.bench.avoidable import contact_speeds

    return contact_speeds(trace)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", default="oracle,tracked,laser")
    parser.add_argument("--sigma", type=float, default=0.03, help="tracked mode's detection σ, m")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--confirmed-only", action="store_true", help="trackers report confirmed tracks only")
    args = parser.parse_args(argv)
    if args.confirmed_only:
        _confirmed_only()
    with tempfile.TemporaryDirectory() as folder:
        rows = [run_one(mode, args.sigma, Path(folder)) for mode in args.modes.split(",")]
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    for r in rows:
        print(
            f"{r['mode']:8s} first seen {r['first_seen_s']} s at {r['distance_when_seen_m']} m, planner told at "
            f"{r['told_s']} s; command {r['command_before_mps']} m/s before, {r['command_when_seen_mps']} m/s "
            f"({r['status_when_seen']}) in that cycle; speed at contact {r['speed_at_contact_mps']} m/s, "
            f"at fault {r['at_fault']}"
        )


if __name__ == "__main__":
    main()
