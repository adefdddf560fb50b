"""Running IR-SIM worlds as a user would (irsim.make, env.load_behavior, env.step) and reading IR-SIM's
own flags; clearances are measured independently, with shapely on IR-SIM's own geometry."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples" / "irsim"


@dataclass
class IrsimRun:
    arrived: bool
    collided: bool  # IR-SIM's collision flag of the robot, raised at any step
    steps: int
    min_clearance_m: float  # robot outline to any obstacle outline, every step (shapely)
    positions: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))


def write_world(tmp_path: Path, world: dict[str, Any], name: str = "world.yaml") -> Path:
    file = tmp_path / name
    file.write_text(yaml.safe_dump(world, sort_keys=False))
    return file


def run_world(world_file: Path, max_steps: int = 600, seed: int | None = None) -> IrsimRun:
    import irsim

    env = irsim.make(str(world_file), display=False, disable_all_plot=True, seed=seed)
    env.load_behavior("viapath.integrations.irsim")
    robot = env.robot
    collided, clearance, positions = False, np.inf, []
    steps = 0
    while steps < max_steps:
        env.step()
        steps += 1
        collided |= bool(robot.collision)
        positions.append(np.asarray(robot.state[:2, 0], dtype=float).copy())
        for obj in env.obstacle_list:
            clearance = min(clearance, float(robot.geometry.distance(obj.geometry)))
        if robot.arrive:
            break
    arrived = bool(robot.arrive)
    env.end(0)
    return IrsimRun(arrived, collided, steps, clearance, np.array(positions))
