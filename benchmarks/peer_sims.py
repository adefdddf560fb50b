"""viapath against each simulator's own behaviours, in that simulator, with its own metrics.

* navground (extra ``navground``), its experiment runner: ``Viapath`` against navground's ``HRVO`` and
  ``ORCA`` on a crossing and a corridor scenario, ``--runs`` runs each (navground samples the people
  per run from its own seeded samplers). Metrics are navground's records: collisions (runs in which the
  robot is in navground's collision record), efficacy (navground's per-step efficacy of the robot,
  averaged until it reaches the goal), time (the first recorded step within the goal tolerance).
* IR-SIM (extra ``irsim``): ``viapath`` against IR-SIM's ``rvo``, ``dash`` and ``sfm`` on two worlds
  (a crossing and a walled corridor), ``--seeds`` seeds each (the people's starts, goals and speeds are
  drawn from the seed), with IR-SIM's own flags: the robot's ``collision`` flag raised at any step and
  its ``arrive`` flag.

The people walk to their goals and avoid no one (navground's ``Dummy``, IR-SIM's omni ``dash``), as in
viapath's own scenarios: a robot that relies on others to share the avoidance gets no help. Every robot
has the same body (radius 0.25 m, a differential drive up to 0.6 m/s) and the same goal; viapath's
nominal speed is 0.3 m/s (navground's ``optimal_speed`` for every behaviour there). Counts do not
depend on the machine's load.

    python benchmarks/peer_sims.py [--runs 20] [--seeds 10] [--only navground|irsim] [--json]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import yaml

DT_S = 0.1
ROBOT_RADIUS_M = 0.25
NOMINAL_SPEED_MPS = 0.3
GOAL_TOLERANCE_M = 0.1

# -- navground ---------------------------------------------------------------------------------------------

NAVGROUND_BEHAVIOURS = ("Viapath", "HRVO", "ORCA")


def _person_group(position_from, position_to, direction, speed_from, speed_to) -> dict[str, Any]:
    return {
        "number": 1,
        "type": "human",
        "radius": 0.25,
        "kinematics": {"type": "Omni", "max_speed": 0.6},
        "behavior": {"type": "Dummy", "optimal_speed": {"sampler": "uniform", "from": speed_from, "to": speed_to}},
        "task": {"type": "Direction", "direction": list(direction)},
        "position": {"sampler": "uniform", "from": list(position_from), "to": list(position_to)},
        "orientation": float(np.arctan2(direction[1], direction[0])),
    }


def navground_scenarios() -> dict[str, dict[str, Any]]:
    """Two scenarios: the robot follows y = 0 to its goal; people cross it, or come down a corridor."""
    crossing_people = [
        _person_group([2.0, -6.0], [8.0, -2.0], (0.0, 1.0), 0.3, 0.5),
        _person_group([2.0, -6.0], [8.0, -2.0], (0.0, 1.0), 0.3, 0.5),
        _person_group([2.0, -6.0], [8.0, -2.0], (0.0, 1.0), 0.3, 0.5),
        _person_group([2.0, 2.0], [8.0, 6.0], (0.0, -1.0), 0.3, 0.5),
        _person_group([2.0, 2.0], [8.0, 6.0], (0.0, -1.0), 0.3, 0.5),
        _person_group([2.0, 2.0], [8.0, 6.0], (0.0, -1.0), 0.3, 0.5),
    ]
    corridor_people = [
        _person_group([4.0, -1.0], [11.0, 1.0], (-1.0, 0.0), 0.3, 0.5),
        _person_group([4.0, -1.0], [11.0, 1.0], (-1.0, 0.0), 0.3, 0.5),
        _person_group([4.0, -1.0], [11.0, 1.0], (-1.0, 0.0), 0.3, 0.5),
        _person_group([1.5, -0.8], [3.0, 0.8], (1.0, 0.0), 0.1, 0.15),  # a slow walker ahead, same way
    ]
    return {
        "crossing": {"goal": [10.0, 0.0], "people": crossing_people, "walls": []},
        "corridor": {
            "goal": [12.0, 0.0],
            "people": corridor_people,
            "walls": [{"line": [[-2.0, 1.5], [14.0, 1.5]]}, {"line": [[-2.0, -1.5], [14.0, -1.5]]}],
        },
    }


def navground_experiment(scenario: dict[str, Any], behaviour: str, runs: int, steps: int) -> dict[str, Any]:
    robot_behaviour: dict[str, Any] = {"type": behaviour, "optimal_speed": NOMINAL_SPEED_MPS}
    if behaviour == "Viapath":
        robot_behaviour["half_width_m"] = 1.0
    robot = {
        "number": 1,
        "type": "robot",
        "radius": ROBOT_RADIUS_M,
        "control_period": DT_S,
        "kinematics": {"type": "2WDiff", "wheel_axis": 0.4, "max_speed": 0.6},
        "behavior": robot_behaviour,
        "state_estimation": {"type": "Bounded", "range": 5.0},
        "task": {"type": "Waypoints", "waypoints": [scenario["goal"]], "tolerance": GOAL_TOLERANCE_M},
        "position": [0.0, 0.0],
        "orientation": 0.0,
    }
    return {
        "steps": steps,
        "time_step": DT_S,
        "runs": runs,
        "record_pose": True,
        "record_collisions": True,
        "record_efficacy": True,
        "scenario": {"groups": [robot, *scenario["people"]], "walls": scenario["walls"]},
    }


def navground_run_metrics(run: Any, goal: list[float]) -> dict[str, Any]:
    poses = np.asarray(run.poses)
    robot_uid = run.world.agents[0]._uid
    collisions = np.asarray(run.collisions).reshape(-1, 3)
    robot_collisions = int(((collisions[:, 1] == robot_uid) | (collisions[:, 2] == robot_uid)).sum())
    distance = np.hypot(*(poses[:, 0, :2] - np.asarray(goal)).T)
    reached = np.flatnonzero(distance <= GOAL_TOLERANCE_M + 1e-6)
    until = int(reached[0]) if len(reached) else len(poses)
    efficacy = np.asarray(run.efficacy)[: max(until, 1), 0]
    return {
        "collisions": robot_collisions,
        "reached": bool(len(reached)),
        "time_s": float((reached[0] + 1) * DT_S) if len(reached) else None,
        "efficacy": float(np.mean(efficacy)),
    }


def run_navground(runs: int, steps: int = 600) -> list[dict[str, Any]]:
    from navground import sim

    import viapath.integrations.navground  # noqa: F401  (registers Viapath; navground_py run loads its entry point)

    rows = []
    for name, scenario in navground_scenarios().items():
        for behaviour in NAVGROUND_BEHAVIOURS:
            experiment = sim.load_experiment(yaml.safe_dump(navground_experiment(scenario, behaviour, runs, steps)))
            experiment.run()
            per_run = [navground_run_metrics(run, scenario["goal"]) for run in experiment.runs.values()]
            rows.append(_summary("navground", name, behaviour, per_run))
    return rows


# -- IR-SIM ------------------------------------------------------------------------------------------------

IRSIM_BEHAVIOURS = ("viapath", "rvo", "dash", "sfm")


def _irsim_person(start, goal, speed) -> dict[str, Any]:
    return {
        "kinematics": {"name": "omni"},
        "shape": {"name": "circle", "radius": 0.25},
        "state": [float(start[0]), float(start[1]), 0.0],
        "goal": [float(goal[0]), float(goal[1]), 0.0],
        "vel_max": [float(speed), float(speed)],
        "behavior": {"name": "dash"},
    }


def irsim_world(world: str, behaviour: str, seed: int) -> dict[str, Any]:
    """The world ``world`` ("crossing" or "corridor") with people drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    if world == "crossing":
        goal, obstacles = [10.0, 0.0], []
        for k in range(6):
            x, y = rng.uniform(2.0, 8.0), rng.uniform(2.0, 6.0)
            sign = 1.0 if k % 2 else -1.0
            obstacles.append(_irsim_person((x, sign * y), (x, -sign * 8.0), rng.uniform(0.3, 0.5)))
    else:
        goal, obstacles = [12.0, 0.0], []
        for _ in range(3):
            start = (rng.uniform(4.0, 11.0), rng.uniform(-1.0, 1.0))
            obstacles.append(_irsim_person(start, (-4.0, start[1]), rng.uniform(0.3, 0.5)))
        slow = (rng.uniform(1.5, 3.0), rng.uniform(-0.8, 0.8))
        obstacles.append(_irsim_person(slow, (16.0, slow[1]), rng.uniform(0.1, 0.15)))
        for y in (1.5, -1.5):
            obstacles.append({"shape": {"name": "linestring", "vertices": [[-2.0, y], [14.0, y]]}, "state": [0, 0, 0]})
    robot_behaviour: dict[str, Any] = {"name": behaviour}
    if behaviour == "viapath":
        robot_behaviour.update(nominal_speed_mps=NOMINAL_SPEED_MPS, half_width_m=1.0)
    return {
        "world": {
            "height": 20,
            "width": 22,
            "step_time": DT_S,
            "sample_time": DT_S,
            "offset": [-4, -10],
            "collision_mode": "unobstructed",
        },
        "robot": [
            {
                "kinematics": {"name": "diff"},
                "shape": {"name": "circle", "radius": ROBOT_RADIUS_M},
                "state": [0.0, 0.0, 0.0],
                "goal": [*goal, 0.0],
                "goal_threshold": GOAL_TOLERANCE_M,
                "vel_max": [0.6, 2.0],
                "acce": [0.8, 6.0],
                "behavior": robot_behaviour,
            }
        ],
        "obstacle": obstacles,
    }


def irsim_episode(world: dict[str, Any], folder: Path, max_steps: int) -> dict[str, Any]:
    import irsim

    file = folder / "world.yaml"
    file.write_text(yaml.safe_dump(world, sort_keys=False))
    env = irsim.make(str(file), display=False, disable_all_plot=True, log_level="ERROR")
    env.load_behavior("viapath.integrations.irsim")
    robot, collided, steps = env.robot, False, 0
    while steps < max_steps and not robot.arrive:
        env.step()
        steps += 1
        collided |= bool(robot.collision)
    env.end(0)
    return {
        "collisions": int(collided),
        "reached": bool(robot.arrive),
        "time_s": steps * DT_S if robot.arrive else None,
        "efficacy": None,
    }


def run_irsim(seeds: int, max_steps: int = 600) -> list[dict[str, Any]]:
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for world in ("crossing", "corridor"):
            for behaviour in IRSIM_BEHAVIOURS:
                per_seed = [
                    irsim_episode(irsim_world(world, behaviour, seed), Path(folder), max_steps) for seed in range(seeds)
                ]
                rows.append(_summary("irsim", world, behaviour, per_seed))
    return rows


# -- report ------------------------------------------------------------------------------------------------


def _summary(simulator: str, scenario: str, behaviour: str, runs: list[dict[str, Any]]) -> dict[str, Any]:
    times = [r["time_s"] for r in runs if r["time_s"] is not None]
    efficacies = [r["efficacy"] for r in runs if r["efficacy"] is not None]
    return {
        "simulator": simulator,
        "scenario": scenario,
        "behaviour": behaviour,
        "runs": len(runs),
        "runs_with_collision": sum(1 for r in runs if r["collisions"] > 0),
        "reached_goal": sum(1 for r in runs if r["reached"]),
        "reached_without_collision": sum(1 for r in runs if r["reached"] and r["collisions"] == 0),
        "median_time_s": float(np.median(times)) if times else None,
        "mean_efficacy": float(np.mean(efficacies)) if efficacies else None,
    }


def table(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| simulator | scenario | behaviour | runs | runs with a collision | reached goal | "
        "reached, no collision | median time to goal (s) | mean efficacy |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        time_s = "–" if r["median_time_s"] is None else f"{r['median_time_s']:.1f}"
        efficacy = "–" if r["mean_efficacy"] is None else f"{r['mean_efficacy']:.2f}"
        lines.append(
            f"| {r['simulator']} | {r['scenario']} | {r['behaviour']} | {r['runs']} | {r['runs_with_collision']} | "
            f"{r['reached_goal']} | {r['reached_without_collision']} | {time_s} | {efficacy} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=20, help="navground runs per scenario and behaviour")
    parser.add_argument("--seeds", type=int, default=10, help="IR-SIM seeds per world and behaviour")
    parser.add_argument("--only", choices=("navground", "irsim"), default=None)
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    args = parser.parse_args(argv)
    rows = []
    with contextlib.redirect_stdout(sys.stderr):  # IR-SIM prints its plotting backend's fallback on import
        if args.only in (None, "navground"):
            rows += run_navground(args.runs)
        if args.only in (None, "irsim"):
            rows += run_irsim(args.seeds)
    if args.json:
        print(json.dumps({"runs": args.runs, "seeds": args.seeds, "rows": rows}, indent=1))
    else:
        print(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
