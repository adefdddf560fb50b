"""The closed loop: perceive, plan, drive, at the scan period (10 Hz by default).

Deterministic for a given seed: the only randomness (perception noise) draws from one generator.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from viapath.observation import Command, Observation, RobotState
from viapath.path import DesignatedPath
from viapath.perception.base import WorldSnapshot
from viapath.planning import Decision
from viapath.scenarios.build import Setup, build
from viapath.sim import robot as kinematics
from viapath.sim.metrics import compute_metrics, plan_side
from viapath.sim.obstacles import scenario_obstacle_states
from viapath.sim.reactive import obstacle_motion
from viapath.sim.static_world import StaticWorld
from viapath.sim.step_record import StepRecord


@dataclass
class Trace:
    """Everything that happened, one row per step (robot rows include the final state)."""

    scenario_name: str
    planner_name: str
    perception_mode: str
    dt_s: float
    path: DesignatedPath
    robot_radius_m: float
    times_s: np.ndarray  # (K,)
    robot_poses: np.ndarray  # (K, 3) x, y, heading
    robot_speeds_mps: np.ndarray  # (K,)
    robot_turn_rates_radps: np.ndarray  # (K,)
    commands: np.ndarray  # (K, 2) v, ω commanded at each step (last row: nothing commanded)
    obstacle_positions: np.ndarray  # (K, N, 2), NaN where absent
    obstacle_velocities: np.ndarray  # (K, N, 2)
    obstacle_radii_m: np.ndarray  # (N,)
    plan_speeds_mps: np.ndarray  # (K,)
    plan_targets: np.ndarray  # (K, 2)
    plan_status: list[str]
    via_points: list[np.ndarray]  # per step, (k, 2)
    plan_times_ms: np.ndarray  # (K,)
    reached_goal: bool
    walls: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 2)))  # (W, 2, 2) every static edge
    wall_until_s: np.ndarray | None = None  # (W,) each edge stands while t < this (None: always)
    # (W,) the closed shape (box, polygon) each edge bounds, -1 for an open wall (None: every edge open)
    wall_closed_ids: np.ndarray | None = None
    perceived: list[Any] = field(default_factory=list)  # per step Obstacles, when recorded
    scan_points: list[np.ndarray] = field(default_factory=list)  # per step, world frame, laser only
    extras: dict[str, Any] = field(default_factory=dict)
    # Side of the chosen plan's first via point relative to robot -> subgoal: +1 left, -1 right, 0 none.
    plan_sides: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))  # (K,)


@dataclass
class Episode:
    trace: Trace
    metrics: dict[str, Any]


def run_episode(
    scenario,
    planner: str | None = None,
    perception: str | None = None,
    seed: int | None = None,
    position_noise_m: float | None = None,
    velocity_noise_mps: float | None = None,
    record_perceived: bool = False,
    planner_overrides: dict[str, Any] | None = None,
    on_step: Callable[[StepRecord], None] | None = None,
    shield: bool | None = None,
    shield_options: dict[str, Any] | None = None,
) -> Episode:
    """Run one scenario to the goal or to ``duration_s``; returns the trace and its metrics.

    ``on_step`` (views, recorders) is called once per planning cycle with a :class:`StepRecord`.
    ``shield``: filter the planner's commands through the passive-safety shield (None: on for the
    planners in ``viapath.safety.SHIELDED_BY_DEFAULT``); ``shield_options``: its options."""
    dt = scenario.dt_s
    n_steps = int(round(scenario.duration_s / dt))
    times = np.arange(n_steps + 1) * dt
    motion = obstacle_motion(scenario, times)  # None unless some replayed person reacts to the robot
    positions, velocities, radii = (
        scenario_obstacle_states(scenario, times)
        if motion is None
        else (motion.positions, motion.velocities, motion.radii)
    )
    static_world = StaticWorld.of_scenario(scenario)
    setup = build(
        scenario,
        planner,
        planner_overrides,
        shield,
        shield_options,
        perception,
        position_noise_m,
        velocity_noise_mps,
    )
    rng = np.random.default_rng(scenario.seed if seed is None else seed)
    setup.perception.reset(rng)
    loop = _Loop(scenario, setup, static_world, times, positions, velocities, radii)
    spec = scenario.robot
    state = kinematics.UnicycleState(spec.start[0], spec.start[1], spec.heading, spec.speed, 0.0)
    reached = False
    goal_tolerance = setup.subgoal_policy.goal_tolerance_m
    goal_x, goal_y = (
        float(value) for value in setup.path.goal
    )  # the goal test in scalars: every step of every episode
    for k in range(n_steps + 1):
        loop.rows["pose"].append((state.x, state.y, state.heading_rad))
        loop.rows["speed"].append(state.speed_mps)
        loop.rows["turn"].append(state.turn_rate_radps)
        if np.hypot(goal_x - state.x, goal_y - state.y) <= goal_tolerance:
            reached = True
        if reached or k == n_steps:
            _append_idle(loop.rows, state)
            break
        command = loop.cycle(k, state, record_perceived, on_step)
        if motion is not None:  # people move to step k + 1 seeing the robot at step k (rows filled in place)
            motion.step(
                state.position, state.speed_mps * np.array([np.cos(state.heading_rad), np.sin(state.heading_rad)])
            )
        state = kinematics.step(state, command, setup.limits, dt)
    trace = loop.trace(reached, scenario.seed if seed is None else seed)
    metrics = compute_metrics(trace)
    metrics.update(setup.perception.episode_metrics())
    metrics.update({"shield": False, "shield_interventions": None, **setup.planner.episode_metrics()})
    return Episode(trace, metrics)


@dataclass
class _Loop:
    """One episode's fixed inputs and what it records, one row per step."""

    scenario: Any
    setup: Setup
    static_world: StaticWorld
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    radii: np.ndarray
    rows: dict[str, list] = field(
        default_factory=lambda: {
            k: []
            for k in ("pose", "speed", "turn", "command", "plan_speed", "target", "status", "via", "plan_ms", "side")
        }
    )
    perceived: list = field(default_factory=list)
    scan_points: list = field(default_factory=list)

    def cycle(self, k: int, state, record_perceived: bool, on_step) -> Command:
        """Perceive, plan and record step ``k``; the command to drive (a stop for a non-finite one)."""
        rows, spec, sensing, time_s = self.rows, self.scenario.robot, self.setup.perception, float(self.times[k])
        standing = self.static_world.at(time_s)
        world = WorldSnapshot(
            time_s,
            np.array([state.x, state.y, state.heading_rad]),
            spec.radius,
            self.positions[k],
            self.velocities[k],
            self.radii,
            standing.segments,
            standing,
        )
        observed = sensing.observe(world)
        if record_perceived:
            self.perceived.append(observed)
        if self.setup.perception_mode == "laser":
            self.scan_points.append(np.asarray(sensing.last_points_world))
        observation = Observation(
            time_s,
            RobotState(state.position, state.heading_rad, state.speed_mps, state.turn_rate_radps, spec.radius),
            observed,
            sensing.static_layer(world),
        )
        started = time.perf_counter()
        decision: Decision = self.setup.planner.plan(observation)
        rows["plan_ms"].append((time.perf_counter() - started) * 1e3)
        command = decision.command
        if not (math.isfinite(command.speed_mps) and math.isfinite(command.turn_rate_radps)):
            command = Command.stop()
        rows["command"].append((command.speed_mps, command.turn_rate_radps))
        rows["plan_speed"].append(decision.plan.speed_mps)
        rows["target"].append(np.asarray(decision.plan.target, dtype=float))
        rows["status"].append(decision.plan.status)
        rows["via"].append(np.asarray(decision.plan.via_points, dtype=float).reshape(-1, 2))
        rows["side"].append(plan_side(decision.plan.waypoints))
        if on_step is not None:
            on_step(
                StepRecord(
                    k,
                    time_s,
                    state,
                    observation,
                    decision,
                    rows["plan_ms"][-1],
                    world,
                    sensing.last_scans or None,
                    sensing,
                    self.setup.planner,
                )
            )
        return command

    def trace(self, reached: bool, seed: int) -> Trace:
        rows, n = self.rows, len(self.rows["pose"])
        return Trace(
            scenario_name=self.scenario.name,
            planner_name=self.setup.planner_name,
            perception_mode=self.setup.perception_mode,
            dt_s=self.scenario.dt_s,
            path=self.setup.path,
            robot_radius_m=self.scenario.robot.radius,
            times_s=self.times[:n],
            robot_poses=np.array(rows["pose"]),
            robot_speeds_mps=np.array(rows["speed"]),
            robot_turn_rates_radps=np.array(rows["turn"]),
            commands=np.array(rows["command"]),
            obstacle_positions=self.positions[:n],
            obstacle_velocities=self.velocities[:n],
            obstacle_radii_m=self.radii,
            plan_speeds_mps=np.array(rows["plan_speed"]),
            plan_targets=np.array(rows["target"]),
            plan_status=rows["status"],
            via_points=rows["via"],
            plan_times_ms=np.array(rows["plan_ms"]),
            reached_goal=reached,
            walls=self.static_world.segments,
            wall_until_s=self.static_world.until_s,
            wall_closed_ids=self.static_world.closed_ids(),
            perceived=self.perceived,
            scan_points=self.scan_points,
            extras={"nominal_speed_mps": self.scenario.robot.speed, "seed": seed},
            plan_sides=np.array(rows["side"], dtype=int),
        )


def _append_idle(rows: dict[str, list], state: kinematics.UnicycleState) -> None:
    """The last row has no planning cycle: record 'nothing commanded' so every column has one row per step."""
    rows["command"].append((0.0, 0.0))
    rows["plan_speed"].append(0.0)
    rows["target"].append(state.position)
    rows["status"].append("end")
    rows["via"].append(np.zeros((0, 2)))
    rows["plan_ms"].append(np.nan)
    rows["side"].append(0)
