"""The shield's braking sweep: where the robot goes when it drives a command for one control period and then
brakes as hard as its limits allow, until it is at rest (the shield's definition is in
:mod:`viapath.safety.shield`).

The drive model is the project's (:mod:`viapath.kinematics`): the commanded (v, ω) is reached through the
acceleration limits once per control period and held along an exact arc for the period. Each period is cut
into ``substeps`` equal sub-intervals, whose ends are the sweep's samples.

Compiled (:func:`viapath.jit.compiled`), and plain Python with ``NUMBA_DISABLE_JIT=1``. Choices:

* The braking steps are the drive's own recurrence (speed and turn rate braked towards 0 by one period's
  acceleration step), until every command is at rest, at most ``MAX_BRAKING_STEPS``. A period in which the
  discrete model first stands still counts as moving, at the speed it began with (a real drive ramps its
  speed down within the period, and the at-fault metric reads the speed at the start of a step); the last
  step of all, in which no command moves any more, is left out.
* The arc is written as v/ω (sin h1 − sin h0) (a line for |ω| < 1e-9 rad/s), from the heading at the start
  of each period (the sum of the previous periods' turns) and the position at its start (the sum of the
  previous periods' displacements, added in order).
* ``reach_m`` (path length until rest) is summed in order; it only feeds the bound of who is near.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from viapath.jit import compiled

STRAIGHT_RADPS = 1e-9  # a turn rate below this is driven as a straight line
MAX_BRAKING_STEPS = 10_000


class Robot(NamedTuple):
    """The robot now."""

    x_m: float
    y_m: float
    heading_rad: float
    speed_mps: float
    turn_rate_radps: float
    radius_m: float


class Drive(NamedTuple):
    """The drive's limits, the control period and how many sub-intervals the sweep cuts it into."""

    max_speed_mps: float
    max_accel_mps2: float
    max_turn_rate_radps: float
    max_turn_accel_radps2: float
    dt_s: float
    substeps: int


class Sweep(NamedTuple):
    """Braking roll-outs of K commands over T = J·substeps + 1 samples (J braking steps, t = 0 first)."""

    positions: np.ndarray  # (K, T, 2) at the sub-interval ends
    headings: np.ndarray  # (K, T)
    effective_mps: np.ndarray  # (K, J) the speed the robot may still have in each step (for "towards")
    turns_radps: np.ndarray  # (K, J)
    moving: np.ndarray  # (K, J) bool: the robot moves during the step
    sagitta_m: np.ndarray  # (K, J) how far an arc of one sub-interval strays from its chord
    rest_time_s: np.ndarray  # (K,)
    rest_index: np.ndarray  # (K,) the sample at which each is at rest
    reach_m: np.ndarray  # (K,) path length until rest
    substep_s: float
    substeps: int  # sub-intervals per braking step: sample t lies in step t // substeps


@compiled(inline=True)
def clip(x: float, low: float, high: float) -> float:
    """np.clip of a scalar: the maximum with ``low``, then the minimum with ``high``."""
    if x < low:
        x = low
    if x > high:
        x = high
    return x


@compiled
def achieved_first_period(commands: np.ndarray, robot: Robot, drive: Drive) -> np.ndarray:
    """(v, ω) the drive reaches in one period for each command (K, 2), as
    :func:`viapath.kinematics.limit_command`: a command with a part not finite is a stop."""
    dv = drive.max_accel_mps2 * drive.dt_s
    dw = drive.max_turn_accel_radps2 * drive.dt_s
    out = np.empty((commands.shape[0], 2))
    for k in range(commands.shape[0]):
        v, w = commands[k, 0], commands[k, 1]
        v_cmd = clip(v if math.isfinite(v) else 0.0, 0.0, drive.max_speed_mps)
        w_cmd = clip(w if math.isfinite(w) else 0.0, -drive.max_turn_rate_radps, drive.max_turn_rate_radps)
        if not (math.isfinite(v) and math.isfinite(w)):
            v_cmd, w_cmd = 0.0, 0.0
        out[k, 0] = robot.speed_mps + clip(v_cmd - robot.speed_mps, -dv, dv)
        out[k, 1] = robot.turn_rate_radps + clip(w_cmd - robot.turn_rate_radps, -dw, dw)
    return out


@compiled
def _braking_steps(
    achieved: np.ndarray, speed_now_mps: float, dv: float, dw: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per command and braking step (K, J): speed, turn rate and the speed at the step's start."""
    k_count, j_count = achieved.shape[0], 1
    for k in range(k_count):
        s, n = achieved[k, 0], 1
        while s != 0.0 and n < MAX_BRAKING_STEPS:
            s = s + clip(-s, -dv, dv)
            n += 1
        j_count = max(j_count, n)
    speed, turn = np.empty((k_count, j_count)), np.empty((k_count, j_count))
    previous = np.empty((k_count, j_count))
    for k in range(k_count):
        s, w = achieved[k, 0], achieved[k, 1]
        speed[k, 0], turn[k, 0], previous[k, 0] = s, w, speed_now_mps
        for j in range(1, j_count):
            previous[k, j] = s
            s = s + clip(-s, -dv, dv)
            w = w + clip(-w, -dw, dw)
            speed[k, j], turn[k, j] = s, w
    if j_count > 1:  # the last step: nobody moves in it any more, so nobody needs it
        last_moves = False
        for k in range(k_count):
            last_moves = last_moves or previous[k, j_count - 1] != 0.0
        if not last_moves:
            j_count -= 1
    return speed[:, :j_count], turn[:, :j_count], previous[:, :j_count]


@compiled
def braking_sweep(robot: Robot, drive: Drive, achieved: np.ndarray) -> Sweep:
    """One period at each achieved (v, ω) (K, 2), then the hardest braking until at rest."""
    dt, m = drive.dt_s, drive.substeps
    speed, turn, previous = _braking_steps(
        achieved, robot.speed_mps, drive.max_accel_mps2 * dt, drive.max_turn_accel_radps2 * dt
    )
    k_count, j_count = speed.shape
    h = dt / m
    positions, headings = np.empty((k_count, j_count * m + 1, 2)), np.empty((k_count, j_count * m + 1))
    effective, sagitta = np.empty((k_count, j_count)), np.empty((k_count, j_count))
    moving = np.empty((k_count, j_count), dtype=np.bool_)
    rest_time, rest_index, reach = np.empty(k_count), np.empty(k_count, dtype=np.int64), np.empty(k_count)
    for k in range(k_count):
        positions[k, 0, 0], positions[k, 0, 1], headings[k, 0] = robot.x_m, robot.y_m, robot.heading_rad
        cum_turn, cum_x, cum_y, steps_moving, path_length = 0.0, 0.0, 0.0, 0, 0.0
        for j in range(j_count):
            s, w = speed[k, j], turn[k, j]
            h0 = robot.heading_rad + (cum_turn if j > 0 else 0.0)
            dx, dy = _period_arc(positions, headings, k, j * m, h0, s, w, h, m)
            for i in range(1, m + 1):  # the period's samples: its start position plus the arc so far
                positions[k, j * m + i, 0] += robot.x_m + (cum_x if j > 0 else 0.0)
                positions[k, j * m + i, 1] += robot.y_m + (cum_y if j > 0 else 0.0)
            cum_turn = cum_turn + w * dt if j > 0 else w * dt
            cum_x = cum_x + dx if j > 0 else dx
            cum_y = cum_y + dy if j > 0 else dy
            p = previous[k, j]
            moving[k, j] = s != 0.0 or p != 0.0
            effective[k, j] = max(abs(s), abs(p))
            sagitta[k, j] = abs(s * w) * h * h / 8.0
            steps_moving += 1 if moving[k, j] else 0
            path_length += abs(s)
        rest_time[k], rest_index[k], reach[k] = steps_moving * dt, steps_moving * m, path_length * dt
    return Sweep(positions, headings, effective, turn, moving, sagitta, rest_time, rest_index, reach, h, m)


@compiled
def _period_arc(
    positions: np.ndarray, headings: np.ndarray, k: int, first: int, h0: float, s: float, w: float, h: float, m: int
) -> tuple[float, float]:
    """The arc of one period from heading ``h0`` at (v, ω) = (s, w): its displacement at each of the m
    sub-interval ends into ``positions[k, first + 1 :]`` (relative to the period's start) and the headings
    there; returns the whole period's displacement."""
    straight = abs(w) < STRAIGHT_RADPS
    safe_w = 1.0 if straight else w
    dx, dy = 0.0, 0.0
    for i in range(m):
        tau = h * (i + 1)
        h1 = h0 + w * tau
        if straight:
            dx, dy = s * tau * math.cos(h0), s * tau * math.sin(h0)
        else:
            dx, dy = s / safe_w * (math.sin(h1) - math.sin(h0)), -s / safe_w * (math.cos(h1) - math.cos(h0))
        positions[k, first + 1 + i, 0], positions[k, first + 1 + i, 1] = dx, dy
        headings[k, first + 1 + i] = h1
    return dx, dy
