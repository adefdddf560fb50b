"""The ROS 2 table of docs/results.md: the paper's three scenarios over ROS 2 against ``viapath run``.

Usage: python benchmarks/ros2_paper_table.py [--rate 20] [--scenarios paper-behind,paper-front,paper-side] [--json]

For each scenario it starts ``viapath ros2 node --use-sim-time`` and ``viapath ros2 sim SCENARIO --rate R
--lockstep --json`` as two processes in a ROS domain of their own with
``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` (nothing leaves the machine), ends the node by its pid,
and runs ``viapath run SCENARIO --perception laser`` in this process (the node's laser chain).
It prints the markdown table that docs/results.md shows (benchmarks/results_page.py --with ros2 puts it there).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

SCENARIOS = ("paper-behind", "paper-front", "paper-side")


def _env(domain: int) -> dict[str, str]:
    env = dict(os.environ)
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_DOMAIN_ID=str(domain), PYTHONUNBUFFERED="1")
    env.pop("ROS_STATIC_PEERS", None)
    return env


def over_ros2(names, rate: float) -> dict[str, dict]:
    """Every scenario's node and simulator at once (lock-step: the load changes no figure)."""
    cli = [sys.executable, "-m", "viapath.cli"]
    runs = {}
    with tempfile.TemporaryDirectory(prefix="viapath_ros2_table_") as folder:
        for k, name in enumerate(names):
            domain = 101 + (os.getpid() * 7 + k) % 100  # 101..200: apart from the tests' 1..100
            logs = [open(Path(folder) / f"{name}_{part}.err", "w") for part in ("node", "sim")]  # noqa: SIM115 -- closed in the finally below
            node = subprocess.Popen(
                [*cli, "ros2", "node", "--use-sim-time"],
                env=_env(domain),
                stdout=subprocess.DEVNULL,
                stderr=logs[0],
                stdin=subprocess.DEVNULL,
            )
            sim = subprocess.Popen(
                [*cli, "ros2", "sim", name, "--rate", str(rate), "--lockstep", "--json"],
                env=_env(domain),
                stdout=subprocess.PIPE,
                stderr=logs[1],
                stdin=subprocess.DEVNULL,
                text=True,
            )
            runs[name] = (node, sim, logs)
        out = {}
        try:
            for name, (_node, sim, _logs) in runs.items():
                stdout, _ = sim.communicate(timeout=900)
                if sim.returncode != 0:
                    raise SystemExit(
                        f"{name}: viapath ros2 sim exited {sim.returncode}: "
                        f"{(Path(folder) / f'{name}_sim.err').read_text()[-2000:]}"
                    )
                out[name] = json.loads(stdout.strip().splitlines()[-1])
        finally:
            for node, sim, logs in runs.values():
                for proc in (sim, node):
                    if proc.poll() is None:
                        proc.send_signal(signal.SIGTERM)
                        try:
                            proc.wait(timeout=10)
                        except subprocess.TimeoutExpired:
                            proc.kill()
                            proc.wait()
                for log in logs:
                    log.close()
    return out


def with_run(name: str) -> dict:
    """``viapath run NAME --perception laser --json``."""
    from viapath.scenarios import load_scenario
    from viapath.sim.loop import run_episode

    spec = load_scenario(name)
    spec = spec.model_copy(
        update={"perception": spec.perception.model_copy(update={"options": {"detector": {"keep_segments": False}}})}
    )
    return run_episode(spec, perception="laser").metrics


def _pair(a: dict, b: dict, key: str, fmt: str, unit: str = "") -> str:
    show = lambda v: "—" if v is None else format(v, fmt)
    return f"{show(a.get(key))}{unit} / {show(b.get(key))}{unit}"


def table(ros: dict[str, dict], run: dict[str, dict]) -> str:
    lines = [
        "| scenario | time to goal, ROS 2 / run | min clearance, ROS 2 / run | max speed | shield interventions |",
        "|---|---|---|---|---|",
    ]
    for name in ros:
        r, v = ros[name], run[name]
        lines.append(
            f"| {name} | {_pair(r, v, 'time_to_goal_s', '.1f', ' s')} | {_pair(r, v, 'min_clearance_m', '.4f', ' m')} "
            f"| {_pair(r, v, 'max_speed_mps', '.2f')} m/s | {_pair(r, v, 'shield_interventions', 'd')} |"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rate", type=float, default=20.0, help="simulated time runs R times faster (lock-step)")
    parser.add_argument("--scenarios", default=",".join(SCENARIOS))
    parser.add_argument("--json", action="store_true", help="print both sets of metrics as JSON instead")
    args = parser.parse_args(argv)
    names = [n for n in args.scenarios.split(",") if n]
    ros = over_ros2(names, args.rate)
    run = {name: with_run(name) for name in names}
    if args.json:
        print(json.dumps({"ros2": ros, "run": run}, indent=1, default=str))
    else:
        print(table(ros, run))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
