"""The per-cycle harness every planner gets, compiled where it costs most (extra ``fast``; issue 16): the
guard's two tests of every observation and every command, and the safety inflation, in one call each instead
of a dozen small numpy operations. Loaded by :func:`viapath.compiled.harness_kernels`.

* :func:`obstacles_sound` is :func:`viapath.guard._obstacles_sound`: whether no obstacle field needs a stop
  or a repair.
* :func:`any_within` is ``(distance - reach <= limit_m).any()`` of :func:`viapath.guard.check_command`:
  whether any obstacle is within the robot's stopping distance (then the guard's numpy code rolls out the
  braking path, as before).
* :func:`inflation` is :meth:`viapath.planning.base.Inflation.of`'s arithmetic.

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

from numba import njit


@njit("boolean(float64[:, :], float64[:, :], float64[:], float64[:], float64[:], float64, float64, float64, "
      "float64, float64)", cache=True, nogil=True)
def obstacles_sound(positions, velocities, radii, position_sigma, velocity_sigma, max_coordinate_m,
                    max_obstacle_speed_mps, max_radius_m, max_velocity_sigma_mps, max_position_sigma_m):
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


@njit("boolean(float64[:, :], float64[:], float64, float64, float64, float64, float64)", cache=True, nogil=True)
def any_within(positions, radii, x, y, robot_radius_m, margin_m, limit_m):
    """Whether some obstacle's gap to the robot at (x, y), ``hypot - (robot_radius_m + radius + margin_m)``,
    is at most ``limit_m``."""
    for i in range(positions.shape[0]):
        if math.hypot(positions[i, 0] - x, positions[i, 1] - y) - (robot_radius_m + radii[i] + margin_m) <= limit_m:
            return True
    return False


@njit("void(float64[:], float64[:], float64[:], float64, float64, float64, float64, float64[:, ::1])", cache=True,
      nogil=True)
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
