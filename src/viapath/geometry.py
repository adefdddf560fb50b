"""x-y-t geometry of the method: avoiding lines, reachable cones, via points, moving-disc checks.

Source: Yamada, Sa, Ohya, "Moving Obstacle Avoidance for Mobile Robot Moving on Designated Path",
§3 and Fig. 4, after Tsubouchi et al.'s "iterated forecast and planning"; made precise in docs/design.md §2.

* An obstacle with centre ``c + v t`` and combined radius ``R`` is an oblique cylinder in x-y-t.
* The avoiding line of an obstacle is the cylinder generator through the 2-D tangent point from the
  robot position ``p`` at t = 0: ``w = sqrt(D^2 - R^2) * Rot(±asin(R/D)) (c - p)/D``.
* The via point is where that line meets the reachable cone ``|x - p| = v t``:
  ``|w + v_obs t| = v t``. We solve it in the stable form ``s = |w|/t``:
  ``s^2 + 2 s (ŵ·v_obs) + |v_obs|^2 - v^2 = 0``, so ``s = -ŵ·v_obs ± sqrt(v^2 - (ŵ × v_obs)^2)``.
  The ``+`` root (largest s, earliest t) is "pass early"; the ``-`` root, positive only when the
  obstacle is faster than the robot, is "let it overtake". Equal speeds need no special case.

What the paper leaves open and we chose:
* side ``+1`` (left) rotates the centre direction counter-clockwise: the robot passes the obstacle
  with the obstacle on its right.
* The contact test allows a radius that grows linearly with time (``R + g t``), which turns the
  cylinder into a cone: this is how prediction uncertainty enters (docs/design.md §2, pitfalls).

Everything here is vectorised numpy with broadcasting over leading axes.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

LEFT = 1
RIGHT = -1


def cross2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """z component of the 2-D cross product, over the last axis."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def rotate(vectors: np.ndarray, angle_rad: np.ndarray | float) -> np.ndarray:
    """Rotate 2-D vectors counter-clockwise by ``angle_rad`` (broadcast)."""
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    x, y = vectors[..., 0], vectors[..., 1]
    return np.stack([c * x - s * y, s * x + c * y], axis=-1)


def angles_of(vectors: np.ndarray) -> np.ndarray:
    """The angle of each (x, y) row, by libm's atan2: Python's ``math.atan2``, which the compiled code and
    the controller call too. numpy's ``np.arctan2`` is SIMD code chosen by the CPU (Intel's SVML on AVX-512
    machines) and there rounds differently from libm in the last bit for about 7 % of angles, so the planner's
    angles would depend on the machine and differ from the compiled code's."""
    return np.array([math.atan2(y, x) for x, y in np.reshape(vectors, (-1, 2)).tolist()], dtype=float)


def wrap_angle(angle_rad: Any) -> Any:
    """Wrap to (-pi, pi]."""
    if type(angle_rad) in (float, np.float64):
        # One angle (each roll-out's heading error): a float's % is np.mod's (fmod, then the divisor added
        # when the signs differ), without making an array of it.
        return np.float64(math.pi - (math.pi - angle_rad) % math.tau)
    return np.pi - np.mod(np.pi - np.asarray(angle_rad), 2.0 * np.pi)


def tangent_vectors(
    origin: np.ndarray, centres: np.ndarray, radii: np.ndarray, side: np.ndarray | int
) -> tuple[np.ndarray, np.ndarray]:
    """Vector from ``origin`` to the tangent point on disc (centre, radius) on ``side`` (+1 left, -1 right).

    Returns ``(w, valid)``; ``valid`` is False where the origin lies inside the disc (no tangent).
    With ``d = c - origin``, ``D = |d|`` and ``L = sqrt(D² - R²)``, the tangent vector is ``d`` turned
    by ``±asin(R/D)`` and scaled to ``L``: ``w = L (L d ∓ R d⊥) / D²`` (no trigonometry needed).
    """
    dx = centres[..., 0] - origin[..., 0]
    dy = centres[..., 1] - origin[..., 1]
    distance_sq = dx * dx + dy * dy
    radius_sq = radii * radii
    valid = distance_sq > radius_sq
    length = np.sqrt(np.maximum(distance_sq - radius_sq, 0.0))
    scale = length / np.where(valid, distance_sq, 1.0)
    side_radius = side * radii
    wx, wy = scale * (length * dx - side_radius * dy), scale * (side_radius * dx + length * dy)
    w = np.empty(np.shape(wx) + (2,))  # filled in place: np.stack's Python costs more than both products
    w[..., 0], w[..., 1] = wx, wy
    return w, valid


def via_times(w: np.ndarray, obstacle_velocity: np.ndarray, speed: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Times at which a robot leaving the cone apex at ``speed`` meets the avoiding line ``w + v_obs t``.

    Returns ``(t_early, t_late)``; ``inf`` where that root does not exist. ``t_late`` is finite only
    when the obstacle is faster than the robot (two crossings: pass early / let it overtake).
    """
    wx, wy = w[..., 0], w[..., 1]
    vx, vy = obstacle_velocity[..., 0], obstacle_velocity[..., 1]
    length = np.sqrt(wx * wx + wy * wy)
    positive = length > 0
    inverse = 1.0 / np.where(positive, length, 1.0)
    along = (wx * vx + wy * vy) * inverse
    across = (wx * vy - wy * vx) * inverse
    discriminant = np.asarray(speed) ** 2 - across * across
    root = np.sqrt(np.maximum(discriminant, 0.0))
    s_early = root - along
    s_late = -along - root
    ok = positive & (discriminant >= 0)
    t_early = np.where(ok & (s_early > 1e-12), length / np.where(s_early > 1e-12, s_early, 1.0), np.inf)
    ok &= (s_late > 1e-12) & (discriminant > 0)
    t_late = np.where(ok, length / np.where(ok, s_late, 1.0), np.inf)
    return t_early, t_late


def first_contact_time(
    rel_position: np.ndarray,
    rel_velocity: np.ndarray,
    radius: np.ndarray | float,
    duration: np.ndarray | float,
    growth: np.ndarray | float = 0.0,
) -> np.ndarray:
    """First time in [0, duration] at which ``|rel_position + rel_velocity τ| <= radius + growth τ``.

    ``rel_*`` are robot minus obstacle. Returns ``inf`` where there is no contact, 0 where the two
    already touch. With ``growth = 0`` this is the classic moving-disc check; with ``growth > 0`` the
    obstacle is a cone in x-y-t (prediction uncertainty growing with time).
    """
    px, py = rel_position[..., 0], rel_position[..., 1]
    vx, vy = rel_velocity[..., 0], rel_velocity[..., 1]
    return _first_contact(px, py, vx, vy, np.asarray(radius, dtype=float), np.asarray(growth, dtype=float), duration)


def _first_contact(
    px: np.ndarray,
    py: np.ndarray,
    vx: np.ndarray,
    vy: np.ndarray,
    radius: np.ndarray,
    growth: np.ndarray | float,
    duration: np.ndarray | float,
) -> np.ndarray:
    if np.count_nonzero(growth):  # np.any's dispatch costs more than the check (legs_first_contact's hot path)
        a = vx * vx + vy * vy - growth * growth
        b = px * vx + py * vy - radius * growth
    else:
        a = vx * vx + vy * vy
        b = px * vx + py * vy
    c = px * px + py * py - radius * radius
    discriminant = b * b - a * c
    # c / (-b + sqrt(disc)) is the smaller positive root of a τ² + 2 b τ + c = 0 in every case
    # (a > 0, a < 0, a = 0) where one exists, without cancellation.
    denominator = np.sqrt(np.maximum(discriminant, 0.0)) - b
    ok = (discriminant >= 0) & (denominator > 0)
    # A denominator of a few subnormals overflows to ±inf: past any duration when c > 0, replaced by 0 below when not.
    with np.errstate(over="ignore"):
        tau = c / np.where(ok, denominator, 1.0)
    tau = np.where(ok & (tau <= duration), tau, np.inf)
    return np.where(c <= 0, 0.0, tau)


def closest_approach(
    rel_position: np.ndarray, rel_velocity: np.ndarray, duration: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray]:
    """Minimum distance and its time over τ in [0, duration] for linear relative motion."""
    speed_sq = np.sum(rel_velocity * rel_velocity, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = np.where(speed_sq > 0, -np.sum(rel_position * rel_velocity, axis=-1) / speed_sq, 0.0)
    tau = np.clip(tau, 0.0, duration)
    closest = rel_position + rel_velocity * np.asarray(tau)[..., None]
    return np.hypot(closest[..., 0], closest[..., 1]), tau


def legs_first_contact(
    starts: np.ndarray,
    start_times: np.ndarray,
    velocities: np.ndarray,
    durations: np.ndarray,
    obstacle_positions: np.ndarray,
    obstacle_velocities: np.ndarray,
    radii: np.ndarray,
    growth: np.ndarray | float = 0.0,
    growth_until_s: np.ndarray | float = np.inf,
    leg_radii_m: np.ndarray | None = None,
) -> np.ndarray:
    """First contact time, measured from each leg's start, for K legs against N moving discs: (K, N).

    Obstacle j is at ``obstacle_positions[j] + obstacle_velocities[j] t`` with radius
    ``radii[j] + growth[j] min(t, growth_until_s[j])`` (t from the planning instant): a cone in x-y-t
    that turns into a cylinder at ``growth_until_s`` (a scalar or one time per obstacle). Leg k starts at ``starts[k]`` at time
    ``start_times[k]`` and moves at ``velocities[k]`` for ``durations[k]``. ``leg_radii_m`` (K,), when
    given, is added to every disc's radius for leg k (what a leg at its speed must keep besides).
    """
    if leg_radii_m is not None:
        radii = np.asarray(radii, dtype=float)[None, :] + np.asarray(leg_radii_m, dtype=float)[:, None]
    t0 = np.asarray(start_times, dtype=float)[:, None]
    duration = np.asarray(durations, dtype=float)[:, None]
    growth = np.asarray(growth, dtype=float)
    ox, oy = obstacle_positions[:, 0], obstacle_positions[:, 1]
    ovx, ovy = obstacle_velocities[:, 0], obstacle_velocities[:, 1]
    px = starts[:, 0:1] - (ox + ovx * t0)
    py = starts[:, 1:2] - (oy + ovy * t0)
    vx = velocities[:, 0:1] - ovx
    vy = velocities[:, 1:2] - ovy
    until = np.asarray(growth_until_s, dtype=float)
    if not np.count_nonzero(growth) or not np.isfinite(until).any():
        return _first_contact(px, py, vx, vy, radii + growth * t0, growth, duration)
    # Split each leg where the cone stops growing: the cone part, then the cylinder part.
    cone_duration = np.clip(until - t0, 0.0, duration)
    early = _first_contact(
        px, py, vx, vy, radii + growth * np.minimum(t0, until), np.where(until > t0, growth, 0.0), cone_duration
    )
    full_growth = growth * np.where(np.isfinite(until), until, 0.0)
    late = _first_contact(
        px + vx * cone_duration, py + vy * cone_duration, vx, vy, radii + full_growth, 0.0, duration - cone_duration
    )
    # The cylinder part exists only for legs that reach the end of the cone.
    late = np.where(t0 + duration >= until, late + cone_duration, np.inf)
    return np.where(np.isfinite(early), early, late)


VIA_SIDES = np.array([LEFT, RIGHT, LEFT, RIGHT])  # of the via options: (left, early), (right, early), ...
VIA_ROOTS = np.array([0, 0, 1, 1])  # ... 0 = pass early (before the obstacle), 1 = late (behind it)
