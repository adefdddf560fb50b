"""The guard's two checks of every cycle (:mod:`viapath.guard`), compiled: whether an observation's obstacle
fields need a stop or a repair, and the braking test of a command.

Compiled (:func:`viapath.jit.compiled`), and plain Python with ``NUMBA_DISABLE_JIT=1``. Choices:

* :func:`obstacles_sound` answers "look closer" (False) at the first field outside its bound; a NaN fails
  every comparison, so a bound also says "finite". The per-field checks of :mod:`viapath.guard` then say
  what is wrong.
* The braking roll-out (:func:`braking_points`) is the drive model of :mod:`viapath.kinematics` step by step
  (its own ``_clip`` and exact ``_arc``, compiled from their source): the command held for one control period
  in ``samples_per_period`` steps, then the stop command until the speed is at most 1e-12 m/s, at most
  ``ceil(top speed / speed step) + 2`` (and 1000) steps.
* Distances by ``np.hypot``: numpy's bits compiled and in plain Python (``math.hypot`` rounds differently).
* :func:`first_touched` looks only at obstacles within ``reachable_m`` now; a touch counts when some sample
  comes within robot + obstacle radius + margin of it (the smallest gap, NaN-propagating, at most 0) and the
  first sample is closer to it than the robot is now.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from viapath import kinematics
from viapath.jit import compiled

MAX_BRAKING_STEPS = 1000

_clip = compiled(kinematics._clip)
_arc = compiled(kinematics._arc)


class Braking(NamedTuple):
    """The drive's limits and how the guard rolls a command out."""

    max_speed_mps: float
    max_turn_rate_radps: float
    max_accel_mps2: float
    max_turn_accel_radps2: float
    period_s: float  # how long a command is held
    samples_per_period: int


@compiled
def obstacles_sound(
    positions: np.ndarray,
    velocities: np.ndarray,
    radii: np.ndarray,
    position_sigma: np.ndarray,
    velocity_sigma: np.ndarray,
    max_coordinate_m: float,
    max_obstacle_speed_mps: float,
    max_radius_m: float,
    max_velocity_sigma_mps: float,
    max_position_sigma_m: float,
) -> bool:
    """Every position within ±``max_coordinate_m``, every speed at most ``max_obstacle_speed_mps``, every
    radius and σ in [0, its largest]; all finite."""
    for i in range(positions.shape[0]):
        if not (abs(positions[i, 0]) <= max_coordinate_m and abs(positions[i, 1]) <= max_coordinate_m):
            return False
        if not np.hypot(velocities[i, 0], velocities[i, 1]) <= max_obstacle_speed_mps:
            return False
        if not (0.0 <= radii[i] <= max_radius_m):
            return False
        if not (0.0 <= velocity_sigma[i] <= max_velocity_sigma_mps):
            return False
        if not (0.0 <= position_sigma[i] <= max_position_sigma_m):
            return False
    return True


@compiled
def braking_points(
    x: float, y: float, heading: float, speed: float, turn: float, v_cmd: float, w_cmd: float, braking: Braking
) -> np.ndarray:
    """Positions (S, 2) of the robot at (x, y, heading) with (speed, turn) holding (``v_cmd``, ``w_cmd``) for
    one period and then commanded to stop until at rest, from the first sample on."""
    samples = braking.samples_per_period
    dt = braking.period_s / samples
    dv, dw = braking.max_accel_mps2 * dt, braking.max_turn_accel_radps2 * dt
    if not (math.isfinite(v_cmd) and math.isfinite(w_cmd)):
        v_cmd, w_cmd = 0.0, 0.0
    v_cmd = _clip(v_cmd, 0.0, braking.max_speed_mps)
    w_cmd = _clip(w_cmd, -braking.max_turn_rate_radps, braking.max_turn_rate_radps)
    points = np.empty((samples + MAX_BRAKING_STEPS, 2))
    count = 0
    for _ in range(samples):
        speed = speed + _clip(v_cmd - speed, -dv, dv)
        turn = turn + _clip(w_cmd - turn, -dw, dw)
        x, y, heading = _arc(x, y, heading, speed, turn, dt)
        points[count, 0], points[count, 1] = x, y
        count += 1
    top = max(braking.max_speed_mps, abs(speed))
    for _ in range(min(MAX_BRAKING_STEPS, int(math.ceil(top / max(braking.max_accel_mps2 * dt, 1e-9))) + 2)):
        if speed <= 1e-12:
            break
        speed = speed + _clip(0.0 - speed, -dv, dv)  # the stop command (0, 0), within every limit
        turn = turn + _clip(0.0 - turn, -dw, dw)
        x, y, heading = _arc(x, y, heading, speed, turn, dt)
        points[count, 0], points[count, 1] = x, y
        count += 1
    return points[:count]


@compiled
def first_touched(
    x0: float,
    y0: float,
    heading: float,
    speed: float,
    turn: float,
    v_cmd: float,
    w_cmd: float,
    max_speed_mps: float,
    max_turn_rate_radps: float,
    max_accel_mps2: float,
    max_turn_accel_radps2: float,
    period_s: float,
    samples_per_period: int,
    positions: np.ndarray,
    radii: np.ndarray,
    robot_radius_m: float,
    margin_m: float,
    reachable_m: float,
) -> int:
    """The first obstacle (row) within ``reachable_m`` now that the robot at (x0, y0) with its heading, speed
    and turn rate, holding (``v_cmd``, ``w_cmd``) for one period and then braking (:func:`braking_points`,
    :class:`Braking` given field by field: a record passed from Python costs microseconds per call), would
    touch while its first sample moves towards it; -1 if none."""
    n = positions.shape[0]
    near, distance, reach = np.empty(n, dtype=np.bool_), np.empty(n), np.empty(n)
    any_near = False
    for j in range(n):
        distance[j] = np.hypot(positions[j, 0] - x0, positions[j, 1] - y0)
        reach[j] = robot_radius_m + radii[j] + margin_m
        near[j] = distance[j] - reach[j] <= reachable_m
        any_near = any_near or near[j]
    if not any_near:
        return -1
    braking = Braking(
        max_speed_mps, max_turn_rate_radps, max_accel_mps2, max_turn_accel_radps2, period_s, samples_per_period
    )
    swept = braking_points(x0, y0, heading, speed, turn, v_cmd, w_cmd, braking)
    for j in range(n):
        if not near[j]:
            continue
        smallest = math.inf
        for s in range(swept.shape[0]):
            gap = np.hypot(swept[s, 0] - positions[j, 0], swept[s, 1] - positions[j, 1]) - reach[j]
            if gap != gap or smallest != smallest:
                smallest = math.nan
            elif gap < smallest:
                smallest = gap
        closer = np.hypot(swept[0, 0] - positions[j, 0], swept[0, 1] - positions[j, 1]) < distance[j] - 1e-12
        if smallest <= 0 and closer:
            return j
    return -1
