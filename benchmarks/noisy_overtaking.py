"""The built-in overtaking under perception noise: command flips, contacts and time outside the corridor.

Usage: python benchmarks/noisy_overtaking.py [--modes tracked,laser,white] [--seeds 8] [--sigma 0.03] [--json]

Modes: ``tracked`` (noisy detections, σ ``--sigma`` per axis, through the Kalman tracker), ``laser`` (the
simulated scanners and the whole laser chain), ``white`` (the oracle with white noise every cycle:
position σ ``--sigma``, velocity σ ``--velocity-sigma``; a stress figure). One row per mode and seed
(seeds 0..N-1) with the command flips (viapath.sim.metrics.command_flips), side flips, contacts,
at-fault contacts, time outside the corridor and time to the goal, then each mode's worst and median.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from viapath.scenarios.loader import load_scenario
from viapath.sim.loop import run_episode

FIELDS = (
    "command_flips",
    "plan_side_flips",
    "collision",
    "at_fault_collision",
    "time_outside_corridor_s",
    "reached_goal",
    "time_to_goal_s",
    "min_clearance_m",
)


def run_one(mode: str, seed: int, sigma_m: float, velocity_sigma_mps: float, scenario_name: str = "overtaking"):
    scenario = load_scenario(scenario_name)
    if mode == "tracked":
        episode = run_episode(scenario, perception="tracked", seed=seed, position_noise_m=sigma_m, velocity_noise_mps=0)
    elif mode == "laser":
        episode = run_episode(scenario, perception="laser", seed=seed)
    elif mode == "white":
        episode = run_episode(
            scenario, perception="oracle", seed=seed, position_noise_m=sigma_m, velocity_noise_mps=velocity_sigma_mps
        )
    else:
        raise SystemExit(f"--modes: unknown mode {mode!r}; expected tracked, laser or white")
    return {"mode": mode, "seed": seed, **{name: episode.metrics[name] for name in FIELDS}}


def summary(rows: list[dict]) -> dict:
    flips = np.array([r["command_flips"] for r in rows])
    return {
        "runs": len(rows),
        "command_flips_max": int(flips.max()),
        "command_flips_median": float(np.median(flips)),
        "side_flips_max": int(max(r["plan_side_flips"] for r in rows)),
        "contacts": sum(bool(r["collision"]) for r in rows),
        "at_fault": sum(bool(r["at_fault_collision"]) for r in rows),
        "outside_corridor_s": float(sum(r["time_outside_corridor_s"] for r in rows)),
        "reached": sum(bool(r["reached_goal"]) for r in rows),
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", default="tracked,laser,white")
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--sigma", type=float, default=0.03, help="position σ, m")
    parser.add_argument("--velocity-sigma", type=float, default=0.05, help="white mode's velocity σ, m/s")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    result = {}
    for mode in args.modes.split(","):
        rows = [run_one(mode, seed, args.sigma, args.velocity_sigma) for seed in range(args.seeds)]
        result[mode] = {"rows": rows, "summary": summary(rows)}
        if not args.json:
            for r in rows:
                print(
                    f"{mode:8s} seed {r['seed']}: command flips {r['command_flips']:3d}, side flips "
                    f"{r['plan_side_flips']:3d}, contact {r['collision']!s:5s}, at fault {r['at_fault_collision']!s:5s}, "
                    f"outside {r['time_outside_corridor_s']:.1f} s, goal {r['reached_goal']!s:5s} "
                    f"{r['time_to_goal_s'] if r['time_to_goal_s'] is None else round(r['time_to_goal_s'], 1)} s"
                )
            print(f"{mode:8s} {result[mode]['summary']}", flush=True)
    if args.json:
        print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
