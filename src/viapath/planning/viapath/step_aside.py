"""Stepping aside (``step_aside_s``; 0: off): a standing or waiting robot that a person's forecast will walk
into moves out of their way, inside the corridor.

Source: beyond the paper (its robot plans for itself and stands when no candidate is free); passive
friendliness on top of passive safety (docs/design.md §7 and §11). A robot at rest is passively safe, yet a
person blind to it still walks into it; where a move inside the corridor keeps both clear, the robot takes it.

What we chose:
* **When.** After the recipe's decision, if its plan is ``stop``, ``wait``, ``blocked`` (waiting at a
  closed way) or ``escape``, and the robot is at rest (below 0.05 m/s, the at-fault rule's threshold) or
  stepping aside already: staying, the plan's own command
  held (for an escape: braking to rest and standing), is scored against the people's forecast over
  ``step_aside_s``, the capped uncertainty cones of the leg checks. If it keeps less than ``step_aside_clearance_m`` beyond the cones, the robot looks for a
  move. Static geometry alone never starts one. A wait is scored with the uncertainty inflation its
  standing was checked with (``slow_leg_inflation``). A ``slow`` plan is left alone: the robot is under way
  on a leg checked free, and the person crosses ahead of it (the paper's "side" behaviour). A robot still
  under way brakes first: a move started at speed near people that then change course (replayed crowds)
  came into contact while moving.
* **The moves.** Targets in 16 directions round the robot at ``step_aside_distances_m``, inside the
  corridor, and last cycle's target. The robot steers for a target as the planner's command does (turning
  first, slowing for large heading errors), no faster than the top of the speed set, and slows so as to
  stop on it (speed at most ``sqrt(2 a d)`` for the distance d left, a the drive's braking limit); it then
  stands there. Each move is rolled out with the drive's limits, and the robot then stands on its target,
  up to the planner's horizon (``horizon_s``): a place the person passes by, not one they reach a little
  later. The roll-out must stay inside the corridor and come no nearer static geometry than touching (the
  static discs, velocity 0).
* **The score.** A move's clearance is the smallest gap, over the roll-out, between the robot's centre and
  every forecast cone (the gap between two samples is bounded below by the smaller sample minus half what
  the two can close within the step, so a positive clearance is clear over the whole roll-out). The move
  taken has the most clearance up to ``step_aside_clearance_m``, less 0.05 per metre to the target, plus
  0.02 per metre of progress towards the subgoal (shorter moves, and forward rather than back, among
  equally clear ones), and a bonus of 0.03 for last cycle's target (no flipping between equal ones).
  A move must be clear over its whole roll-out and keep 0.05 m more than staying (up to
  ``step_aside_clearance_m``); last cycle's move goes on while it keeps clear and within 0.05 m of staying.
* **The shield.** The move's command must be admitted by the shield behind the planner (the next best move is
  tried, up to ``MAX_SHIELD_TRIES``); none admitted, the recipe's decision stands. The shield's own test is
  the safety argument; this step only chooses which admissible command leaves the person's way.
* The move's status is ``step-aside``; its plan's target is the target, its speed the speed commanded.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from viapath.jit import compiled
from viapath.observation import Command, Decision, Plan
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.escape import escape_top_speed
from viapath.planning.viapath.legs import clip
from viapath.planning.viapath.rollout import drive_step, steer

# Plans after which the robot looks for a way out of someone's path.
STEPPING_STATUSES = frozenset({"stop", "wait", "blocked", "escape"})
AT_REST_MPS = 0.05  # a robot this slow is at rest (the at-fault rule's threshold)
DIRECTIONS = 16  # targets round the robot, every 22.5°
MAX_SHIELD_TRIES = 4  # moves tried, best first, for one the shield admits
STOP_TOLERANCE_M = 0.02  # a target is reached within this: the robot stands there
_GAIN_M = 0.05  # clearance a move must add to the plan's own command's
_PER_METRE = 0.05  # score per metre to the target (shorter moves among equally clear ones)
_PROGRESS = 0.02  # score per metre of progress towards the subgoal
_SAME_TARGET = 0.03  # score bonus for last cycle's target
_SAME_TARGET_M = 0.05  # last cycle's target counts as the same within this


@compiled
def roll_outs(
    robot: np.ndarray,
    targets: np.ndarray,
    speed_caps: np.ndarray,
    held: np.ndarray,
    max_speed: float,
    max_accel: float,
    max_turn: float,
    max_turn_accel: float,
    dt: float,
    steps: int,
    gain: float,
    stop_tolerance: float,
) -> np.ndarray:
    """(K, steps + 1, 2) positions, from now, of the robot (x, y, heading, speed, turn rate) steering for each
    target (K, 2) no faster than its cap and slowing to stop on it (:func:`command_towards`); a row of ``held``
    (K, bool) instead holds the command (speed, turn rate) in that row of ``targets``. The drive as
    :func:`viapath.kinematics.step` moves it: speed and turn rate ramped at their limits, exact arcs."""
    k_count = targets.shape[0]
    out = np.empty((k_count, steps + 1, 2))
    dv = max_accel * dt
    dw = max_turn_accel * dt
    for k in range(k_count):
        x = robot[0]
        y = robot[1]
        heading = robot[2]
        speed = robot[3]
        turn = robot[4]
        out[k, 0, 0] = x
        out[k, 0, 1] = y
        for s in range(steps):
            if held[k]:
                v_cmd = clip(targets[k, 0], 0.0, max_speed)
                w_cmd = clip(targets[k, 1], -max_turn, max_turn)
            else:
                v_cmd, w_cmd = _towards(
                    x,
                    y,
                    heading,
                    targets[k, 0],
                    targets[k, 1],
                    speed_caps[k],
                    max_speed,
                    max_accel,
                    max_turn,
                    gain,
                    stop_tolerance,
                )
            x, y, heading, speed, turn = drive_step(x, y, heading, speed, turn, v_cmd, w_cmd, dv, dw, dt)
            out[k, s + 1, 0] = x
            out[k, s + 1, 1] = y
    return out


@compiled
def _towards(
    x: float,
    y: float,
    heading: float,
    tx: float,
    ty: float,
    cap: float,
    max_speed: float,
    max_accel: float,
    max_turn: float,
    gain: float,
    stop_tolerance: float,
) -> tuple[float, float]:
    """The command (speed, turn rate) steering for (tx, ty): :func:`viapath.kinematics.steer_towards` at
    :func:`stopping_speed` (:func:`.rollout.steer`)."""
    dx = tx - x
    dy = ty - y
    speed_mps = stopping_speed(math.sqrt(dx * dx + dy * dy), cap, max_accel, stop_tolerance)
    return steer(x, y, heading, tx, ty, speed_mps, max_speed, max_turn, gain)


@compiled
def stopping_speed(distance: float, cap: float, max_accel: float, stop_tolerance: float) -> float:
    """The speed for a target ``distance`` away: at most ``cap`` and no faster than the robot can stop from
    within what is left beyond ``stop_tolerance``; 0 within it."""
    left = distance - stop_tolerance
    if left <= 0.0:
        return 0.0
    return min(cap, math.sqrt(2.0 * max_accel * left))


@compiled
def clearances(
    positions: np.ndarray,
    dt: float,
    obstacle_positions: np.ndarray,
    obstacle_velocities: np.ndarray,
    radii: np.ndarray,
    growth: np.ndarray,
    growth_until_s: np.ndarray,
) -> np.ndarray:
    """(K,) the smallest gap over each roll-out (K, S, 2), sampled every ``dt`` from now, between the robot's
    centre and every obstacle's forecast cone (centre ``p + v t``, radius ``r + g min(t, cap)``): the smaller
    gap of two samples less half of what the two can close between them (the robot's step plus the person's
    walk and growth in a step), so a positive clearance keeps clear between samples too. inf with nobody."""
    k_count = positions.shape[0]
    s_count = positions.shape[1]
    out = np.full(k_count, np.inf)
    for k in range(k_count):
        best = np.inf
        for j in range(obstacle_positions.shape[0]):
            px = obstacle_positions[j, 0]
            py = obstacle_positions[j, 1]
            vx = obstacle_velocities[j, 0]
            vy = obstacle_velocities[j, 1]
            walk = (math.hypot(vx, vy) + abs(growth[j])) * dt
            previous = np.inf
            for s in range(s_count):
                t = s * dt
                reach = radii[j] + growth[j] * (t if t < growth_until_s[j] else growth_until_s[j])
                gap = math.hypot(positions[k, s, 0] - (px + vx * t), positions[k, s, 1] - (py + vy * t)) - reach
                if s == 0:
                    value = gap
                else:
                    hop = math.hypot(
                        positions[k, s, 0] - positions[k, s - 1, 0], positions[k, s, 1] - positions[k, s - 1, 1]
                    )
                    value = min(gap, previous) - 0.5 * (hop + walk)
                if value < best:
                    best = value
                previous = gap
        out[k] = best
    return out


def command_towards(planner: Any, observation: Any, target: np.ndarray) -> tuple[Command, float]:
    """The command of this cycle steering for ``target`` (the first step of its roll-out) and the speed it was
    made with."""
    robot = observation.robot
    distance = float(np.hypot(*(np.asarray(target) - robot.position)))
    cap = escape_top_speed(planner.limits, planner.config)
    speed = float(stopping_speed(distance, cap, planner.limits.max_accel_mps2, STOP_TOLERANCE_M))
    return planner.steer(observation, target, speed, planner.config.heading_gain), speed


def targets_round(checks: LegChecks, distances_m: tuple[float, ...], previous: np.ndarray | None) -> np.ndarray:
    """The moves' targets: ``DIRECTIONS`` directions times the distances, and last cycle's target, inside the
    corridor."""
    angles = np.arange(DIRECTIONS) * (2.0 * math.pi / DIRECTIONS)
    unit = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    targets = (checks.position + np.asarray(distances_m, dtype=float)[:, None, None] * unit[None]).reshape(-1, 2)
    if previous is not None:
        targets = np.vstack([previous[None], targets])
    return targets[checks.inside(targets)]


def _people_and_statics(checks: LegChecks, packed: tuple[np.ndarray, ...]) -> tuple[tuple[np.ndarray, ...], ...]:
    """The packed obstacles (:meth:`LegChecks.packed_obstacles`) split into people and static discs."""
    mask = checks.obstacles.static_mask
    if mask is None:
        return packed, tuple(a[:0] for a in packed)
    static = np.asarray(mask, dtype=bool)
    return tuple(np.ascontiguousarray(a[~static]) for a in packed), tuple(
        np.ascontiguousarray(a[static]) for a in packed
    )


def _drive(planner: Any) -> tuple[Any, ...]:
    """The roll-outs' drive arguments after the targets (:func:`roll_outs`)."""
    limits, config = planner.limits, planner.config
    return (
        limits.max_speed_mps,
        limits.max_accel_mps2,
        limits.max_turn_rate_radps,
        limits.max_turn_accel_radps2,
        config.escape_dt_s,
        max(1, int(round(config.step_aside_s / config.escape_dt_s))),
        config.heading_gain,
        STOP_TOLERANCE_M,
    )


def step_aside(planner: Any, checks: LegChecks, decision: Decision, previous: np.ndarray | None) -> Decision | None:
    """The move out of someone's way after ``decision`` (:data:`STEPPING_STATUSES`), or None (the decision
    stands). ``previous``: last cycle's step-aside target, if it stepped aside."""
    if decision.plan.status not in STEPPING_STATUSES or len(checks.obstacles) == 0:
        return None
    if previous is None and checks.speed_mps > AT_REST_MPS:
        return None  # a step aside starts from rest: a robot under way brakes first (or escapes)
    if checks.obstacles.static_mask is not None and bool(np.all(checks.obstacles.static_mask)):
        return None  # only static geometry: nobody to step aside for
    drive = _drive(planner)
    dt = planner.config.escape_dt_s
    people, statics = _people_and_statics(checks, checks.packed_obstacles())
    # Staying: the plan's own command held (its slow leg, its standing), and for an escape braking to rest.
    own = decision.command
    stay = np.zeros((1, 2)) if decision.plan.status == "escape" else np.array([[own.speed_mps, own.turn_rate_radps]])
    stay_positions = roll_outs(checks.packed_robot(), stay, np.zeros(1), np.ones(1, np.bool_), *drive)
    stay_clearance = float(clearances(stay_positions, dt, *people)[0])
    if stay_clearance >= planner.config.step_aside_clearance_m:
        return None
    # Static geometry: no nearer than touching, or than staying keeps if that is nearer already.
    static_floor = min(0.0, float(clearances(stay_positions, dt, *statics)[0]))
    moves = _scored_moves(planner, checks, drive, people, statics, static_floor, stay_clearance, previous)
    if moves is None:
        return None
    targets, clearance, score = moves
    for k in np.argsort(-score, kind="stable")[:MAX_SHIELD_TRIES]:
        if not np.isfinite(score[k]):
            break
        target = targets[k].copy()
        command, speed = command_towards(planner, planner._situation.observation, target)
        plan = Plan(
            "step-aside",
            speed,
            target,
            waypoints=np.array([checks.position, target]),
            subgoal_index=checks.subgoal_index,
            extras={
                "step_aside": {
                    "instead_of": decision.plan.status,
                    "clearance_m": float(clearance[k]),
                    "clearance_staying_m": stay_clearance,
                }
            },
        )
        if planner._inside_shield(plan):
            return Decision(command, plan)
    return None


def _scored_moves(
    planner: Any,
    checks: LegChecks,
    drive: tuple[Any, ...],
    people: tuple[np.ndarray, ...],
    statics: tuple[np.ndarray, ...],
    static_floor: float,
    stay_clearance: float,
    previous: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The moves' targets, clearances from the people and scores (-inf: not usable); None if none is usable."""
    config = planner.config
    wanted = config.step_aside_clearance_m
    targets = targets_round(checks, tuple(config.step_aside_distances_m), previous)
    if len(targets) == 0:
        return None
    cap = escape_top_speed(planner.limits, config)
    dt = config.escape_dt_s
    # The move, then standing on its target, up to the planner's horizon: a place the person passes by, not a
    # place they reach a little later (a group filling the corridor).
    long = max(drive[5], int(round(max(checks.horizon_s, config.step_aside_s) / dt)))
    drive_long = (*drive[:5], long, *drive[6:])
    positions = roll_outs(
        checks.packed_robot(), targets, np.full(len(targets), cap), np.zeros(len(targets), np.bool_), *drive_long
    )
    inside = checks.inside(positions.reshape(-1, 2)).reshape(positions.shape[:2]).all(axis=1)
    inside &= clearances(positions, dt, *statics) >= static_floor
    clearance = clearances(positions, dt, *people)
    # A move keeps clear over the whole roll-out, and more clearly than staying.
    needed = max(min(stay_clearance + _GAIN_M, wanted), 0.0)
    required = np.full(len(targets), needed)
    same = np.zeros(len(targets), dtype=bool)
    if previous is not None:
        # Last cycle's move goes on while it keeps about what staying would (no flipping between the two).
        same = np.hypot(*(targets - previous).T) <= _SAME_TARGET_M
        required[same] = max(min(needed, stay_clearance - _GAIN_M), 0.0)
    usable = inside & (clearance >= required)
    if not usable.any():
        return None
    offsets = targets - checks.position
    toward = checks.subgoal - checks.position
    toward = toward / max(float(np.hypot(*toward)), 1e-9)
    score = (
        np.minimum(clearance, wanted)
        - _PER_METRE * np.hypot(offsets[:, 0], offsets[:, 1])
        + _PROGRESS * (offsets @ toward)
        + _SAME_TARGET * same
    )
    return targets, clearance, np.where(usable, score, -np.inf)
