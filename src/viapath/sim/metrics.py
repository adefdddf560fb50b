"""Episode metrics (docs/design.md §4 names, SI units), computed from the trace alone."""

from __future__ import annotations

from typing import Any

import numpy as np

from viapath.geometry import closest_approach
from viapath.static import segment_distances


def clearance_per_step(trace) -> np.ndarray:
    """Smallest surface-to-surface distance to any obstacle during each step (K-1,), exact for
    straight-line motion of both between samples; negative means overlap. inf with no obstacle."""
    poses = trace.robot_poses[:, :2]
    obstacles = trace.obstacle_positions
    if obstacles.shape[1] == 0 or len(poses) < 2:
        return np.full(max(len(poses) - 1, 0), np.inf)
    rel_start = poses[:-1, None, :] - obstacles[:-1]
    rel_end = poses[1:, None, :] - obstacles[1:]
    # A person who enters or leaves the scene this step is checked only where present at both ends.
    present = np.isfinite(rel_start).all(-1) & np.isfinite(rel_end).all(-1)
    rel_start = np.where(present[..., None], rel_start, 1e9)
    rel_end = np.where(present[..., None], rel_end, 1e9)
    distance, _ = closest_approach(rel_start, (rel_end - rel_start), 1.0)
    clearance = distance - trace.obstacle_radii_m[None, :] - trace.robot_radius_m
    return clearance.min(axis=1)


def at_fault_collision(trace, min_speed_mps: float = 0.05, seen_for_s: float = 0.0) -> bool:
    """Contact while the robot was moving towards the person (replayed people do not react to the
    robot, so only these contacts are the robot's fault): in the step where a contact with an
    obstacle begins, the robot's speed exceeds ``min_speed_mps`` and its velocity has a positive
    component towards that obstacle's centre (both taken at the start of the step). Only the onset
    counts: simulated discs pass through each other afterwards, which says nothing about fault.

    With ``seen_for_s`` > 0, only contacts with a person present for at least that long before the
    onset count: recorded tracks (ETH/UCY) begin wherever the annotators first marked someone, at
    times right beside the robot, and no planner can avoid a person it has never seen."""
    faults = at_fault_onsets(trace, min_speed_mps)
    if seen_for_s > 0:
        faults &= present_for(trace, seen_for_s)
    return bool(np.any(faults))


def at_fault_onsets(trace, min_speed_mps: float = 0.05) -> np.ndarray:
    """(K-1, N): a contact with obstacle n begins in step k while the robot moves towards it (see
    :func:`at_fault_collision`)."""
    poses = trace.robot_poses
    obstacles = trace.obstacle_positions
    if obstacles.shape[1] == 0 or len(poses) < 2:
        return np.zeros((max(len(poses) - 1, 0), obstacles.shape[1]), dtype=bool)
    rel_start = poses[:-1, None, :2] - obstacles[:-1]
    rel_end = poses[1:, None, :2] - obstacles[1:]
    present = np.isfinite(rel_start).all(-1) & np.isfinite(rel_end).all(-1)
    rel_start = np.where(present[..., None], rel_start, 1e9)
    rel_end = np.where(present[..., None], rel_end, 1e9)
    distance, _ = closest_approach(rel_start, rel_end - rel_start, 1.0)
    contact = distance < trace.obstacle_radii_m[None, :] + trace.robot_radius_m  # (K-1, N)
    speeds = trace.robot_speeds_mps[:-1]
    velocity = speeds[:, None] * np.stack([np.cos(poses[:-1, 2]), np.sin(poses[:-1, 2])], axis=1)
    towards = np.einsum("kj,knj->kn", velocity, -rel_start) > 0.0
    onset = contact & ~np.vstack([np.zeros((1, contact.shape[1]), dtype=bool), contact[:-1]])
    # Someone who is already overlapping the robot when they appear (at t = 0, or a replayed person's
    # first sample) did not meet a moving robot: not at fault (counted by overlapping_at_appearance).
    return onset & towards & (speeds[:, None] > min_speed_mps) & ~overlap_on_appearance(trace)


def seen(obstacle_positions) -> np.ndarray:
    """(K, N): person n is seen at step k: their position sample exists (finite). The one definition of
    when the robot can see a person, shared by the simulator (the perception receives every person with
    a finite sample, with the velocity of their motion then), the metrics (appearance) and the avoidable
    search (:mod:`viapath.bench.avoidable`, which starts at the first step seen)."""
    return np.isfinite(np.asarray(obstacle_positions, dtype=float)).all(-1)


def first_seen_steps(obstacle_positions) -> np.ndarray:
    """(N,): the first step at which each person is seen (:func:`seen`); -1 for someone never seen."""
    visible = seen(obstacle_positions)
    first = np.argmax(visible, axis=0) if len(visible) else np.zeros(visible.shape[1], dtype=int)
    return np.where(visible.any(axis=0), first, -1)


def appeared_in_step(obstacle_positions) -> np.ndarray:
    """(K-1, N): person n is seen at step k and was not at step k - 1 (or k = 0): they appear in step k."""
    visible = seen(obstacle_positions)[:-1]
    return visible & ~np.vstack([np.zeros((1, visible.shape[1]), dtype=bool), visible[:-1]])


def overlap_on_appearance(trace) -> np.ndarray:
    """(K-1, N): obstacle n appears in step k (:func:`appeared_in_step`), present at both ends of the step,
    already overlapping the robot."""
    poses = trace.robot_poses
    obstacles = trace.obstacle_positions
    if obstacles.shape[1] == 0 or len(poses) < 2:
        return np.zeros((max(len(poses) - 1, 0), obstacles.shape[1]), dtype=bool)
    rel_start = poses[:-1, None, :2] - obstacles[:-1]
    present = np.isfinite(rel_start).all(-1) & np.isfinite(obstacles[1:]).all(-1)
    with np.errstate(invalid="ignore"):
        overlapping = (
            np.hypot(rel_start[..., 0], rel_start[..., 1]) < trace.obstacle_radii_m[None] + trace.robot_radius_m
        )
    return appeared_in_step(obstacles) & present & overlapping


def static_clearance_per_step(trace) -> np.ndarray:
    """Smallest distance from the robot's surface to static geometry standing during each step (K-1,),
    exact for the straight chord between the step's poses (the distance between that chord and each
    static edge); negative means overlap. inf without static geometry."""
    poses = trace.robot_poses[:, :2]
    walls = np.asarray(getattr(trace, "walls", np.zeros((0, 2, 2))), dtype=float).reshape(-1, 2, 2)
    steps = max(len(poses) - 1, 0)
    if len(walls) == 0 or steps == 0:
        return np.full(steps, np.inf)
    distance = segment_distances(poses[:-1], poses[1:], walls)  # (K-1, W)
    until = getattr(trace, "wall_until_s", None)
    standing = np.ones(distance.shape, dtype=bool)
    if until is not None:
        standing = np.asarray(until)[None, :] > np.asarray(trace.times_s[:-1])[:, None]
        distance = np.where(standing, distance, np.inf)
    clearance = distance.min(axis=1) - trace.robot_radius_m
    closed = getattr(trace, "wall_closed_ids", None)
    if closed is not None and (np.asarray(closed) >= 0).any():
        inside = _inside_closed(poses[:-1], poses[1:], walls, np.asarray(closed), standing)
        # Inside a box or a polygon is as deep in it as the robot is far from its outline.
        clearance = np.where(inside, -distance.min(axis=1) - trace.robot_radius_m, clearance)
    return clearance


def _inside_closed(
    starts: np.ndarray, ends: np.ndarray, walls: np.ndarray, closed_ids: np.ndarray, standing: np.ndarray
) -> np.ndarray:
    """(K-1,): the step starts or ends inside a standing closed shape (even-odd rule over its edges, a
    ray towards +x), where the distance to its edges alone would say "clear"."""
    edges = np.flatnonzero(closed_ids >= 0)
    shapes, owner = np.unique(closed_ids[edges], return_inverse=True)
    a, b = walls[edges, 0], walls[edges, 1]
    inside = np.zeros(len(starts), dtype=bool)
    for points in (starts, ends):
        px, py = points[:, None, 0], points[:, None, 1]
        straddles = (a[None, :, 1] > py) != (b[None, :, 1] > py)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = a[None, :, 0] + (py - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (
                b[None, :, 1] - a[None, :, 1]
            )
        crossing = (straddles & (px < x_cross) & standing[:, edges]).astype(np.int64)  # (K-1, E)
        counts = np.zeros((len(points), len(shapes)), dtype=np.int64)
        np.add.at(counts.T, owner, crossing.T)
        inside |= (counts % 2 == 1).any(axis=1)
    return inside


def static_contact_onsets(trace, static_clearance: np.ndarray | None = None) -> np.ndarray:
    """(K-1,): a contact with static geometry begins in step k (overlap in k, none in k - 1)."""
    clearance = static_clearance_per_step(trace) if static_clearance is None else static_clearance
    contact = clearance <= 0.0  # touching is contact: a robot placed against a wall is in contact with it
    return contact & ~np.concatenate([[False], contact[:-1]])


def present_for(trace, seconds: float) -> np.ndarray:
    """(K-1, N): obstacle n was present at step k and at each of the steps of the ``seconds`` before."""
    window = int(np.ceil(seconds / trace.dt_s - 1e-9)) + 1  # samples spanning `seconds`
    visible = np.isfinite(trace.obstacle_positions[:-1]).all(-1)  # (K-1, N)
    count = np.vstack([np.zeros((1, visible.shape[1]), int), np.cumsum(visible, axis=0)])
    ends = np.arange(1, len(visible) + 1)
    return count[ends] - count[np.maximum(ends - window, 0)] == window


def compute_metrics(trace) -> dict[str, Any]:
    poses = trace.robot_poses[:, :2]
    dt = trace.dt_s
    clearance = clearance_per_step(trace)
    faults = at_fault_onsets(trace)
    static_clearance = static_clearance_per_step(trace)
    static_onsets = static_contact_onsets(trace, static_clearance)
    # Static geometry does not move: touching it is the robot's fault whenever the robot moves, except a
    # contact there from the first step (the robot was placed on it: counted, not at fault).
    static_faults = static_onsets & (trace.robot_speeds_mps[:-1] > 0.05) if len(static_onsets) else static_onsets
    if len(static_faults):
        static_faults = static_faults.copy()
        static_faults[0] = False
    min_static = float(static_clearance.min()) if len(static_clearance) else float("inf")
    min_clearance = min(float(clearance.min()) if len(clearance) else float("inf"), min_static)
    lateral = np.abs(trace.path.lateral_deviation(poses))
    outside = trace.path.corridor_excess(poses) > 1e-6
    plan_ms = trace.plan_times_ms[np.isfinite(trace.plan_times_ms)]
    speeds = trace.robot_speeds_mps
    return {
        "scenario": trace.scenario_name,
        "planner": trace.planner_name,
        "perception": trace.perception_mode,
        "reached_goal": bool(trace.reached_goal),
        "collision": bool(min_clearance < 0.0 or np.any(static_onsets)),
        "at_fault_collision": bool(np.any(faults) or np.any(static_faults)),
        "at_fault_collision_seen_1s": bool(np.any(faults & present_for(trace, 1.0)) or np.any(static_faults)),
        "static_contact": int(np.count_nonzero(static_onsets)),
        "min_static_clearance_m": _finite_or_none(min_static),
        "blocked_s": blocked_time_s(trace),
        "overlapping_at_appearance": int(np.count_nonzero(overlap_on_appearance(trace))),
        "min_clearance_m": _finite_or_none(min_clearance),
        "time_to_goal_s": float(trace.times_s[-1]) if trace.reached_goal else None,
        "path_length_m": float(np.sum(np.hypot(*np.diff(poses, axis=0).T))),
        "mean_lateral_deviation_m": float(lateral.mean()),
        "max_lateral_deviation_m": float(lateral.max()),
        "time_outside_corridor_s": float(np.count_nonzero(outside[:-1]) * dt),
        "min_speed_mps": float(speeds.min()),
        "max_speed_mps": float(speeds.max()),
        "plan_time_p50_ms": float(np.percentile(plan_ms, 50)) if len(plan_ms) else None,
        "plan_time_p99_ms": float(np.percentile(plan_ms, 99)) if len(plan_ms) else None,
        **smoothness_metrics(trace),
    }


# -- smoothness ------------------------------------------------------------------------------------
# Taken from what the robot actually did (``robot_speeds_mps``, ``robot_turn_rates_radps``: one sample
# per step, after the drive's limits), not from the raw commands, which may jump: a planner that
# commands bang-bang speed changes shows up here as acceleration at the limit and large jerk.

STEERING_REVERSAL_THRESHOLD_RADPS = 0.05


def accel_jerk(speeds_mps, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Finite-difference acceleration (K-1,) and jerk (K-2,) of a speed profile sampled every ``dt_s``."""
    speeds = np.asarray(speeds_mps, dtype=float)
    accel = np.diff(speeds) / dt_s
    return accel, np.diff(accel) / dt_s


def steering_reversals(turn_rates_radps, threshold_radps: float = STEERING_REVERSAL_THRESHOLD_RADPS) -> int:
    """Sign changes of the turn rate among the samples whose magnitude exceeds ``threshold_radps``;
    small values in between (driving straight for a while) neither count nor reset the sign."""
    turn = np.asarray(turn_rates_radps, dtype=float)
    signs = np.sign(turn[np.abs(turn) > threshold_radps])
    return int(np.count_nonzero(signs[1:] != signs[:-1]))


def plan_side(waypoints) -> int:
    """Which side of the straight line robot -> subgoal a chosen polyline passes on first:
    +1 left, -1 right, 0 straight (no via point, or the via point on that line)."""
    line = np.asarray(waypoints, dtype=float).reshape(-1, 2)
    if len(line) < 3:
        return 0
    goal, via = line[-1] - line[0], line[1] - line[0]
    cross = goal[0] * via[1] - goal[1] * via[0]
    scale = max(float(np.hypot(*goal) * np.hypot(*via)), 1e-12)
    return int(np.sign(cross)) if abs(cross) > 1e-6 * scale else 0


def plan_switches(sides, speeds_mps, speed_tolerance_mps: float = 0.05) -> int:
    """Cycles whose chosen side (+1/0/-1) or chosen speed differs from the previous cycle's."""
    sides = np.asarray(sides)
    speeds = np.asarray(speeds_mps, dtype=float)
    if len(sides) < 2:
        return 0
    changed = (sides[1:] != sides[:-1]) | (np.abs(np.diff(speeds)) > speed_tolerance_mps)
    return int(np.count_nonzero(changed))


def command_flips(commands, speed_jump_mps: float = 0.25, turn_threshold_radps: float = 0.5) -> int:
    """Cycles whose command flips against the previous cycle's: the speed command jumps by at least
    ``speed_jump_mps``, or the turn command changes sign with both at least ``turn_threshold_radps``
    (a bang-bang escape: 0.6 ↔ 0 m/s, +2 ↔ -2 rad/s)."""
    commands = np.asarray(commands, dtype=float).reshape(-1, 2)
    if len(commands) < 2:
        return 0
    speed, turn = commands[:, 0], commands[:, 1]
    jump = np.abs(np.diff(speed)) >= speed_jump_mps
    strong = np.abs(turn) >= turn_threshold_radps
    reverse = (turn[1:] * turn[:-1] < 0) & strong[1:] & strong[:-1]
    return int(np.count_nonzero(jump | reverse))


def side_flips(sides) -> int:
    """Left <-> right changes of the chosen side, ignoring straight (0) cycles in between."""
    sides = np.asarray(sides)
    sided = sides[sides != 0]
    return int(np.count_nonzero(sided[1:] != sided[:-1]))


def blocked_time_s(trace) -> float:
    """Time (s) the planner reported ``blocked``: waiting short of static geometry across the way (a closed door)."""
    status = list(getattr(trace, "plan_status", []))
    return float(sum(1 for s in status if s == "blocked") * trace.dt_s)


def smoothness_metrics(trace) -> dict[str, Any]:
    dt = trace.dt_s
    accel, jerk = accel_jerk(trace.robot_speeds_mps, dt)
    turn = np.asarray(trace.robot_turn_rates_radps, dtype=float)
    # Planning cycles only: the last row ("end") has no plan.
    status = list(getattr(trace, "plan_status", []))
    cycles = len(status) - 1 if status and status[-1] == "end" else len(status)
    sides = np.asarray(getattr(trace, "plan_sides", np.zeros(0)))[:cycles]
    plan_speeds = np.asarray(getattr(trace, "plan_speeds_mps", np.zeros(0)), dtype=float)[:cycles]
    if len(sides) != len(plan_speeds):  # a trace that does not record sides: speed changes only
        sides = np.zeros(len(plan_speeds), dtype=int)
    return {
        "max_abs_accel_mps2": float(np.abs(accel).max()) if len(accel) else 0.0,
        "max_abs_jerk_mps3": float(np.abs(jerk).max()) if len(jerk) else 0.0,
        "max_abs_turn_rate_radps": float(np.abs(turn).max()) if len(turn) else 0.0,
        "steering_reversals": steering_reversals(turn),
        "plan_switches": plan_switches(sides, plan_speeds),
        "plan_side_flips": side_flips(sides),
        "command_flips": command_flips(np.asarray(getattr(trace, "commands", np.zeros((0, 2))))[:cycles]),
        "escape_cycles": int(sum(1 for s in status[:cycles] if s == "escape")),
    }


def _finite_or_none(value: float):
    return float(value) if np.isfinite(value) else None
