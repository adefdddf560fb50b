"""Shared by the robustness tests (issue 12): planners on a straight corridor, observations, brute force."""

from __future__ import annotations

import math

import numpy as np

from viapath.observation import Command, MotionLimits, Observation, Obstacles, RobotState
from viapath.path import DesignatedPath
from viapath.planning import available_planners, make_planner

LIMITS = MotionLimits()
ROBOT_RADIUS_M = 0.25


def corridor() -> DesignatedPath:
    return DesignatedPath(np.array([[0.0, 0.0], [8.0, 0.0]]), half_widths_m=np.array([1.0]))


def planners() -> list[str]:
    return available_planners()


def fresh(name: str):
    return make_planner(name, corridor(), nominal_speed_mps=0.2, limits=LIMITS, robot_radius_m=ROBOT_RADIUS_M)


def robot(x=0.0, y=0.0, heading=0.0, speed=0.2, turn=0.0) -> RobotState:
    return RobotState(np.array([x, y]), heading, speed, turn, ROBOT_RADIUS_M)


def one_obstacle(position=(0.6, 0.0), velocity=(0.0, 0.0), radius=0.25, velocity_sigma=0.0) -> Obstacles:
    return Obstacles(
        np.array([position], dtype=float),
        np.array([velocity], dtype=float),
        np.array([radius]),
        velocity_sigma_mps=np.array([velocity_sigma]),
    )


def inside_limits(command: Command, limits: MotionLimits = LIMITS) -> bool:
    v, w = command.speed_mps, command.turn_rate_radps
    return (
        math.isfinite(v)
        and math.isfinite(w)
        and -1e-9 <= v <= limits.max_speed_mps + 1e-9
        and abs(w) <= limits.max_turn_rate_radps + 1e-9
    )


def brute_stopping_distance_m(speed_mps: float, limits: MotionLimits = LIMITS, period_s: float = 0.1) -> float:
    """Independent of viapath.guard: hold the speed one period, then step a stop command in 1 ms
    steps at the acceleration limit and add up the distance."""
    v = max(0.0, speed_mps)
    distance = v * period_s
    dt = 1e-3
    while v > 0:
        v_next = max(0.0, v - limits.max_accel_mps2 * dt)
        distance += 0.5 * (v + v_next) * dt
        v = v_next
    return distance


def _towards(value: float, goal: float, step: float) -> float:
    return min(goal, value + step) if goal > value else max(goal, value - step)


def moves_towards_close_obstacle(
    command: Command,
    observation: Observation,
    period_s: float = 0.1,
    limits: MotionLimits = LIMITS,
    robot_radius_m: float = ROBOT_RADIUS_M,
) -> int | None:
    """Independent brute force (1 ms Euler steps, not viapath.kinematics): the robot holds the command
    for one period and is then commanded to stop, speed and turn rate ramping at the limits. Returns
    the index of an obstacle with a valid position that this motion touches (as it stands now) after
    first moving nearer to it, or None. A command with v <= 0 is not motion."""
    v_cmd, w_cmd = command.speed_mps, command.turn_rate_radps
    if not v_cmd > 0:
        return None
    state = observation.robot
    x, y = (float(c) for c in state.position)
    heading, speed, turn = float(state.heading_rad), float(state.speed_mps), float(state.turn_rate_radps)
    if not all(math.isfinite(c) for c in (x, y, heading, speed, turn)):
        return None
    obstacles = observation.obstacles
    centres = np.asarray(obstacles.positions, dtype=float)
    radii = np.asarray(obstacles.radii_m, dtype=float)
    radii = np.where(np.isfinite(radii) & (radii >= 0), radii, 0.3)
    valid = np.isfinite(centres).all(axis=1)
    if not valid.any():
        return None
    start = np.hypot(centres[:, 0] - x, centres[:, 1] - y)
    dt = 1e-3
    xs, ys = [], []
    t = 0.0
    a, alpha = limits.max_accel_mps2 * dt, limits.max_turn_accel_radps2 * dt
    goal_v = min(max(v_cmd, 0.0), limits.max_speed_mps)
    while t < 60.0:
        holding = t < period_s - 1e-12
        if not holding and abs(speed) <= 1e-9:
            break
        target_v, target_w = (goal_v, w_cmd) if holding else (0.0, 0.0)
        speed = _towards(speed, target_v, a)
        turn = _towards(turn, target_w, alpha)
        x += speed * math.cos(heading) * dt
        y += speed * math.sin(heading) * dt
        heading += turn * dt
        t += dt
        xs.append(x)
        ys.append(y)
    path = np.column_stack([xs, ys])  # (S, 2), one row per ms
    distance = np.hypot(path[:, None, 0] - centres[None, :, 0], path[:, None, 1] - centres[None, :, 1])  # (S, N)
    min_gap = distance.min(axis=0) - robot_radius_m - radii
    first = min(len(path) - 1, int(round(period_s / 5 / dt)) - 1)
    nearer = distance[first] < start - 1e-9
    hits = valid & nearer & (min_gap < 0) & (start - robot_radius_m - radii > 0)
    overlapping_deeper = valid & nearer & (start - robot_radius_m - radii <= 0)
    bad = np.flatnonzero(hits | overlapping_deeper)
    return int(bad[0]) if len(bad) else None
