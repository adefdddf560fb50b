"""The per-cycle harness every planner gets, compiled where it costs most (extra ``fast``): the
guard's two tests of every observation and every command, and the safety inflation, in one call each instead
of a dozen small numpy operations. Loaded by :func:`viapath.compiled.harness_kernels`.

* :func:`obstacles_sound` is :func:`viapath.guard._obstacles_sound`: whether no obstacle field needs a stop
  or a repair.
* :func:`first_touched` is :func:`viapath.guard.check_command`'s braking test: the first obstacle within the
  robot's stopping distance that holding the command and then braking (:func:`viapath.guard.braking_path`)
  would touch.
* :func:`inflation` is :meth:`viapath.planning.base.Inflation.of`'s arithmetic; :func:`situation_numbers` is the
  same and :meth:`viapath.path.DesignatedPath.corridor_excess` of the robot's position, in the one call
  :meth:`viapath.planning.base.Planner.situation` makes every cycle.

They agree with the numpy code bit for bit: the same operations in the same order on each element (no
fused multiply-add: numba does not contract without fastmath), ``math.hypot`` compiles to libm's hypot,
which np.hypot calls too (Python's own ``math.hypot`` rounds differently), and a NaN fails every comparison,
as it does in the numpy reductions. ``tests/robustness/test_harness_kernels.py`` holds them to the numpy
code on random and degenerate fields.

The signatures are given, so the module compiles (or loads numba's cache) when first imported, and an
array of another layout is taken by the same code (no compilation in the middle of a run); an array of
another dtype raises TypeError and the guard uses its numpy code.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from viapath import kinematics


@njit(
    "boolean(float64[:, :], float64[:, :], float64[:], float64[:], float64[:], float64, float64, float64, "
    "float64, float64)",
    cache=True,
    nogil=True,
)
def obstacles_sound(
    positions,
    velocities,
    radii,
    position_sigma,
    velocity_sigma,
    max_coordinate_m,
    max_obstacle_speed_mps,
    max_radius_m,
    max_velocity_sigma_mps,
    max_position_sigma_m,
):
    """Every position within ±``max_coordinate_m``, every speed at most ``max_obstacle_speed_mps``, every
    radius and σ in [0, its largest]; all finite."""
    for i in range(positions.shape[0]):
        if not (abs(positions[i, 0]) <= max_coordinate_m and abs(positions[i, 1]) <= max_coordinate_m):
            return False
        if not math.hypot(velocities[i, 0], velocities[i, 1]) <= max_obstacle_speed_mps:
            return False
        if not (0.0 <= radii[i] <= max_radius_m):
            return False
        if not (0.0 <= velocity_sigma[i] <= max_velocity_sigma_mps):
            return False
        if not (0.0 <= position_sigma[i] <= max_position_sigma_m):
            return False
    return True


@njit(
    "void(float64[:], float64[:], float64[:], float64, float64, float64, float64, float64[:, ::1])",
    cache=True,
    nogil=True,
)
def inflation(radii, position_sigma, velocity_sigma, robot_radius_m, margin_m, sigmas, max_inflation_m, out):
    """Rows of ``out`` (4, N): obstacle radius + margin + k·σ_position; the same + the robot's radius (added
    where numpy adds it); the cone's growth k·σ_velocity; when it stops growing (∞ if it does not grow)."""
    for i in range(radii.shape[0]):
        position_term = sigmas * position_sigma[i]
        growth = sigmas * velocity_sigma[i]
        out[0, i] = radii[i] + margin_m + position_term
        out[1, i] = radii[i] + robot_radius_m + margin_m + position_term
        out[2, i] = growth
        out[3, i] = max_inflation_m / growth if growth > 0 else math.inf


@njit(
    "float64(float64[:], float64[:], float64[:], float64, float64, float64, float64, float64[:, ::1], float64, "
    "float64, float64[:, :], float64[:, :], float64[:], float64[:])",
    cache=True,
    nogil=True,
)
def situation_numbers(
    radii,
    position_sigma,
    velocity_sigma,
    robot_radius_m,
    margin_m,
    sigmas,
    max_inflation_m,
    out,
    x,
    y,
    segment_starts,
    segment_directions,
    segment_lengths,
    half_widths,
):
    """:func:`inflation` into ``out``, and returns how far the finite point (x, y) is outside the corridor: the
    path's ``_point_excess``, operation for operation (the clamp as np.clip's max-then-min)."""
    inflation(radii, position_sigma, velocity_sigma, robot_radius_m, margin_m, sigmas, max_inflation_m, out)
    best = math.inf
    for i in range(segment_lengths.shape[0]):
        sx, sy, dx, dy = segment_starts[i, 0], segment_starts[i, 1], segment_directions[i, 0], segment_directions[i, 1]
        along = (x - sx) * dx + (y - sy) * dy
        along = along if along > 0.0 else 0.0
        along = along if along < segment_lengths[i] else segment_lengths[i]
        excess = math.hypot(x - (sx + along * dx), y - (sy + along * dy)) - half_widths[i]
        if excess < best:
            best = excess
    return best


# braking_path's steps compiled from their own source (kinematics' _clip and exact arc; libm's sin, cos and atan2,
# as Python's math): one definition, and the same numbers.
_clip = njit("float64(float64, float64, float64)", cache=True, nogil=True)(kinematics._clip)
_arc = njit("UniTuple(float64, 3)(float64, float64, float64, float64, float64, float64)", cache=True, nogil=True)(
    kinematics._arc
)


@njit(
    "int64(float64, float64, float64, float64, float64, float64, float64, float64[:], float64[:, :], float64[:], "
    "float64, float64, float64, int64)",
    cache=True,
    nogil=True,
)
def first_touched(
    x0,
    y0,
    heading0,
    speed0,
    turn0,
    v_cmd,
    w_cmd,
    limits,
    positions,
    radii,
    robot_radius_m,
    margin_m,
    reachable_m,
    samples_per_period,
):
    """check_command's braking test in one call: the first obstacle (index) that the robot, holding (v_cmd, w_cmd)
    for one control period and then braking at the limits (:func:`viapath.guard.braking_path`), would touch
    while its first sample moves towards it, among those within ``reachable_m`` now; -1 if none. The robot
    is at (x0, y0) with its heading, speed and turn rate; ``limits``: max speed, max turn rate, max accel, max
    turn accel, control period."""
    n = positions.shape[0]
    near = np.zeros(n, np.bool_)
    distance = np.empty(n)
    reach = np.empty(n)
    any_near = False
    for j in range(n):
        distance[j] = math.hypot(positions[j, 0] - x0, positions[j, 1] - y0)
        reach[j] = robot_radius_m + radii[j] + margin_m
        if distance[j] - reach[j] <= reachable_m:
            near[j] = True
            any_near = True
    if not any_near:
        return -1
    # braking_path's samples
    max_speed, max_turn, accel, turn_accel, period_s = limits[0], limits[1], limits[2], limits[3], limits[4]
    dt = period_s / samples_per_period
    x, y, heading, speed, turn = x0, y0, heading0, speed0, turn0
    dv = accel * dt
    dw = turn_accel * dt
    if not (math.isfinite(v_cmd) and math.isfinite(w_cmd)):
        v_cmd, w_cmd = 0.0, 0.0
    v_cmd = _clip(v_cmd, 0.0, max_speed)
    w_cmd = _clip(w_cmd, -max_turn, max_turn)
    swept = np.empty((samples_per_period + 1000, 2))  # braking_path's braking steps are at most 1000
    count = 0
    for _ in range(samples_per_period):
        speed = speed + _clip(v_cmd - speed, -dv, dv)
        turn = turn + _clip(w_cmd - turn, -dw, dw)
        x, y, heading = _arc(x, y, heading, speed, turn, dt)
        swept[count, 0] = x
        swept[count, 1] = y
        count += 1
    top = max(max_speed, abs(speed))  # (the speed after the held command, as braking_path takes it)
    for _ in range(min(1000, int(math.ceil(top / max(accel * dt, 1e-9))) + 2)):
        if speed <= 1e-12:
            break
        speed = speed + _clip(0.0 - speed, -dv, dv)
        turn = turn + _clip(0.0 - turn, -dw, dw)
        x, y, heading = _arc(x, y, heading, speed, turn, dt)
        swept[count, 0] = x
        swept[count, 1] = y
        count += 1
    # the first near obstacle some sample touches (the smallest gap, NaN-propagating as numpy's min, at most 0)
    # while the first sample is closer to it than the robot is now
    for j in range(n):
        if not near[j]:
            continue
        smallest = math.inf
        for s in range(count):
            gap = math.hypot(swept[s, 0] - positions[j, 0], swept[s, 1] - positions[j, 1]) - reach[j]
            if gap != gap or smallest != smallest:
                smallest = math.nan
            elif gap < smallest:
                smallest = gap
        closer = math.hypot(swept[0, 0] - positions[j, 0], swept[0, 1] - positions[j, 1]) < distance[j] - 1e-12
        if smallest <= 0 and closer:
            return j
    return -1
