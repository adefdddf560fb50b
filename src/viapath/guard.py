"""The guarded entry of every planner: bad input never becomes motion (docs/design.md §4, §7).

Every planner's ``plan`` is wrapped by :func:`guard_plan` (the planner base does it for each
subclass, plug-ins and navground peers included), so each cycle goes:

1. **Structure** (:func:`inspect_observation`): an observation whose fields have the wrong shape or
   type cannot be read at all and raises :class:`ObservationError`, naming the field, e.g.
   ``obstacles.positions: expected an (N, 2) array of [x, y] rows, found shape (2, 5)``. This is the
   only exception bad input makes (the same class is raised when :class:`~viapath.observation.Obstacles`
   is built with wrong shapes).
2. **Values**, checked once, each problem named by field and index:

   * the robot state (position, heading, speed, turn rate, radius) or the time is not finite, or
     beyond its bound (``max_coordinate_m``, ``max_heading_rad``, ``max_state_speed_mps``,
     ``max_state_turn_rate_radps``: values no odometry reports): the robot is told to **stop** (v = 0, ω = 0: with the
     drive's acceleration limits that is the hardest braking within the limits); the planner is not
     called, the decision's ``plan.status`` is ``"guard-stop"`` and ``plan.extras["guard"]`` lists why;
   * an obstacle's **position** is not finite: something is there and we do not know where, so the
     robot stops too (the same status). Dropping it would be the one thing never to do;
   * an obstacle with a known position and a bad **velocity** (NaN, inf, faster than
     ``max_obstacle_speed_mps``) is **kept** standing still with the largest velocity uncertainty
     ``max_velocity_sigma_mps`` (a planner under uncertainty grows it into a cone in every
     direction); a bad **radius** (NaN, inf, negative) becomes ``default_radius_m`` (a person); one
     above ``max_radius_m`` is never shrunk: the robot **stops**; a bad **σ** (NaN, inf, negative, above the largest) becomes
     the largest σ. The planner sees the repaired obstacles; ``plan.extras["guard"]`` lists each repair.
3. **The command** (:func:`check_command`): it must be finite and inside the limits
   (0 ≤ v ≤ ``max_speed_mps``, |ω| ≤ ``max_turn_rate_radps``), else it becomes a stop
   (``"guard-stop"``). A command that moves the robot towards an obstacle within its stopping
   distance keeps its turn rate but its speed becomes 0 (``"guard-brake"``): turning on the spot
   moves no part of a round robot towards anyone. "Within stopping distance": holding the command
   for one control period and then braking at the limits (:func:`braking_path`, stepped with the
   drive model of :mod:`viapath.kinematics`) the robot would touch the obstacle *as it stands now*
   (radius + ``brake_margin_m``), and the first step brings it nearer. A robot passing beside a
   person is not braked (braking in front of someone walking at you is worse than passing). This is a last line, not the shield of docs/design.md §7: it knows nothing of
   where people go, only that the robot must not be the one closing in.

Choices where the issue is silent: the largest σ and the default radius are configuration
(:class:`GuardConfig`), not the largest value seen this cycle, so one bad track cannot make the
others look safer or worse; a time that is not finite stops the robot too (planners use it for their
period); a speed above the motion limits but below ``max_state_speed_mps`` in the *state* (odometry) is
not an error: the command check brakes from it.
"""

from __future__ import annotations

import contextvars
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from viapath.guard_checks import Braking, first_touched, obstacles_sound
from viapath.observation import (
    Command,
    Decision,
    MotionLimits,
    Observation,
    ObservationError,
    Obstacles,
    Plan,
    RobotState,
)
from viapath.static import STATIC_ID_BASE, sample_discs

__all__ = [
    "GuardConfig",
    "Inspection",
    "ObservationError",
    "check_command",
    "guard_plan",
    "inspect_observation",
    "inspected",
    "stopping_distance_m",
]


@dataclass(frozen=True)
class GuardConfig:
    default_radius_m: float = 0.3  # a person, for an obstacle whose radius is unknown
    max_radius_m: float = 10.0
    max_velocity_sigma_mps: float = 1.0  # unknown velocity / bad velocity σ: a person may walk any way at ~1 m/s
    max_position_sigma_m: float = 0.5
    max_obstacle_speed_mps: float = 10.0
    max_coordinate_m: float = 1e6
    max_heading_rad: float = 1e6  # beyond, float steps of the angle are too coarse to steer by
    max_state_speed_mps: float = 50.0  # odometry beyond these is a sensor fault, not a robot state
    max_state_turn_rate_radps: float = 100.0
    control_period_s: float = 0.1  # the scan period (docs/design.md §2): how long a command is held
    static_spacing_m: float = 0.15  # static segments become discs this far apart at most (viapath.static)
    static_range_m: float = 12.0  # static geometry is considered at least this far from the robot
    # ... and at least the robot's stopping distance (from its top speed) plus this: what the planner
    # needs beyond the point where it can stop to plan a way round (a fast robot with gentle brakes sees
    # a wall early enough to stop for it, whatever its speed).
    static_reach_m: float = 10.0
    brake_margin_m: float = 0.02
    tolerance: float = 1e-9

    @functools.cached_property
    def all_finite(self) -> bool:
        """Every bound a finite number (then an inspected observation holds only finite obstacle fields)."""
        return all(math.isfinite(float(getattr(self, name))) for name in self.__dataclass_fields__)


DEFAULT_CONFIG = GuardConfig()


@dataclass
class Inspection:
    """What :func:`inspect_observation` found: the observation to plan with (repaired), or why not."""

    observation: Observation | None  # None: the robot must stop
    stop_reasons: list[str] = field(default_factory=list)
    repairs: list[str] = field(default_factory=list)


def _show(values: Any) -> str:
    return "[" + ", ".join(f"{v:g}" for v in np.atleast_1d(np.asarray(values, dtype=float))) + "]"


def _array(name: str, value: Any, shape: tuple[int, ...]) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ObservationError(f"{name}: expected numbers of shape {shape}, found {value!r}"[:300]) from None
    if array.shape != shape:
        raise ObservationError(f"{name}: expected shape {shape}, found shape {array.shape}")
    return array


def _scalar(name: str, value: Any) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ObservationError(f"{name}: expected a number, found {value!r}"[:300]) from None


def inspect_observation(observation: Observation, config: GuardConfig = DEFAULT_CONFIG) -> Inspection:
    """Check an observation once; raise :class:`ObservationError` on wrong structure, else return
    the repaired observation or the reasons to stop (see the module docstring)."""
    if not isinstance(observation, Observation):
        raise ObservationError(
            f"observation: expected a viapath.observation.Observation, found {type(observation).__name__}"
        )
    robot, obstacles = observation.robot, observation.obstacles
    if not isinstance(robot, RobotState):
        raise ObservationError(f"robot: expected a RobotState, found {type(robot).__name__}")
    if not isinstance(obstacles, Obstacles):
        raise ObservationError(f"obstacles: expected an Obstacles, found {type(obstacles).__name__}")
    if _plainly_sound(observation, robot, obstacles, config):
        return Inspection(observation, [], [])  # the common case, in few operations
    time_s, stop = _robot_stop_reasons(observation, robot, config)
    positions, velocities, radii, position_sigma, velocity_sigma, ids = _obstacle_arrays(obstacles)
    if not stop and _obstacles_sound(positions, velocities, radii, position_sigma, velocity_sigma, config):
        return Inspection(observation, [], [])  # the common case: nothing to stop for, nothing to repair
    velocities, radii = velocities.copy(), radii.copy()
    position_sigma, velocity_sigma = position_sigma.copy(), velocity_sigma.copy()
    repairs = _repair_obstacles(positions, velocities, radii, position_sigma, velocity_sigma, config, stop)
    if stop:
        return Inspection(None, stop, repairs)
    if not repairs:
        return Inspection(observation, [], [])
    repaired = Obstacles(positions, velocities, radii, position_sigma, velocity_sigma, ids, obstacles.static_mask)
    return Inspection(Observation(time_s, robot, repaired, observation.static), [], repairs)


def _robot_stop_reasons(observation: Observation, robot: RobotState, config: GuardConfig) -> tuple[float, list[str]]:
    """The observation's time as a float and the reasons to stop found in it and the robot's state."""
    stop: list[str] = []
    time_s = _scalar("time_s", observation.time_s)
    if not math.isfinite(time_s):
        stop.append(f"time_s: expected a finite number, found {time_s:g}")
    position = _array("robot.position", robot.position, (2,))
    x, y = float(position[0]), float(position[1])  # a NaN fails the bound too; an inf is not finite
    if not (
        math.isfinite(x)
        and math.isfinite(y)
        and abs(x) <= config.max_coordinate_m
        and abs(y) <= config.max_coordinate_m
    ):
        stop.append(
            f"robot.position: expected 2 finite numbers within ±{config.max_coordinate_m:g} m, found {_show(position)}"
        )
    for name, bound, unit in (
        ("heading_rad", config.max_heading_rad, "rad"),
        ("speed_mps", config.max_state_speed_mps, "m/s"),
        ("turn_rate_radps", config.max_state_turn_rate_radps, "rad/s"),
    ):
        value = _scalar(f"robot.{name}", getattr(robot, name))
        if not (math.isfinite(value) and abs(value) <= bound):
            stop.append(f"robot.{name}: expected a finite number within ±{bound:g} {unit}, found {value:g}")
    radius = _scalar("robot.radius_m", robot.radius_m)
    if not (math.isfinite(radius) and radius > 0):
        stop.append(f"robot.radius_m: expected a finite number > 0, found {radius:g}")
    return time_s, stop


def _obstacle_arrays(obstacles: Obstacles) -> tuple[np.ndarray, ...]:
    """positions, velocities, radii, position σ, velocity σ and ids as arrays of their shapes, or
    :class:`ObservationError`."""
    try:
        positions = np.asarray(obstacles.positions, dtype=float)
    except (TypeError, ValueError):
        raise ObservationError("obstacles.positions: expected an (N, 2) array of numbers") from None
    if positions.ndim != 2 or positions.shape[1] != 2:
        raise ObservationError(
            f"obstacles.positions: expected an (N, 2) array of [x, y] rows, found shape {positions.shape}"
        )
    n = len(positions)
    velocities = _array("obstacles.velocities", obstacles.velocities, (n, 2))
    radii = _array("obstacles.radii_m", obstacles.radii_m, (n,))
    position_sigma = _array("obstacles.position_sigma_m", obstacles.position_sigma_m, (n,))
    velocity_sigma = _array("obstacles.velocity_sigma_mps", obstacles.velocity_sigma_mps, (n,))
    ids = np.asarray(obstacles.ids)
    if ids.shape != (n,):
        raise ObservationError(f"obstacles.ids: expected shape ({n},), found shape {ids.shape}")
    return positions, velocities, radii, position_sigma, velocity_sigma, ids


def _repair_obstacles(
    positions: np.ndarray,
    velocities: np.ndarray,
    radii: np.ndarray,
    position_sigma: np.ndarray,
    velocity_sigma: np.ndarray,
    config: GuardConfig,
    stop: list[str],
) -> list[str]:
    """Repair the obstacle fields in place (velocities, radii and σ; the caller's copies) and append to
    ``stop`` what cannot be repaired (an unknown position, an implausible size); returns the repairs."""
    repairs: list[str] = []
    n = len(positions)
    bad_position = ~(np.isfinite(positions).all(axis=1) & (np.abs(positions) <= config.max_coordinate_m).all(axis=1))
    for i in np.flatnonzero(bad_position):
        stop.append(
            f"obstacles.positions[{i}]: expected 2 finite numbers within ±{config.max_coordinate_m:g} m, "
            f"found {_show(positions[i])}; where it is is unknown: stopping"
        )
    speed = np.hypot(velocities[:, 0], velocities[:, 1]) if n else np.zeros(0)
    bad_velocity = ~(np.isfinite(velocities).all(axis=1) & (speed <= config.max_obstacle_speed_mps))
    for i in np.flatnonzero(bad_velocity & ~bad_position):
        repairs.append(
            f"obstacles.velocities[{i}]: expected 2 finite numbers (speed ≤ {config.max_obstacle_speed_mps:g} "
            f"m/s), found {_show(velocities[i])}; kept standing with velocity σ "
            f"{config.max_velocity_sigma_mps:g} m/s"
        )
    velocities[bad_velocity] = 0.0
    velocity_sigma[bad_velocity] = config.max_velocity_sigma_mps
    bad_radius = ~(np.isfinite(radii) & (radii >= 0))
    for i in np.flatnonzero(bad_radius & ~bad_position):
        repairs.append(
            f"obstacles.radii_m[{i}]: expected a finite number ≥ 0, found {radii[i]:g}; "
            f"kept with radius {config.default_radius_m:g} m"
        )
    radii[bad_radius] = config.default_radius_m
    for i in np.flatnonzero((radii > config.max_radius_m) & ~bad_position):
        # Never shrunk: a smaller disc would let the robot drive into its edge. How far it reaches is not
        # plausible, so the robot stops, as for an obstacle whose position is unknown.
        stop.append(
            f"obstacles.radii_m[{i}]: expected at most {config.max_radius_m:g} m, found {radii[i]:g}; "
            "an implausible size: stopping"
        )
    for name, values, largest, unit in (
        ("velocity_sigma_mps", velocity_sigma, config.max_velocity_sigma_mps, "m/s"),
        ("position_sigma_m", position_sigma, config.max_position_sigma_m, "m"),
    ):
        bad = ~(np.isfinite(values) & (values >= 0) & (values <= largest))
        for i in np.flatnonzero(bad & ~bad_position):
            repairs.append(
                f"obstacles.{name}[{i}]: expected a finite number in [0, {largest:g}] {unit}, "
                f"found {values[i]:g}; kept with the largest σ {largest:g} {unit}"
            )
        values[bad] = largest
    return repairs


_FLOAT64 = np.dtype(np.float64)


def static_range_for(robot: RobotState, limits: MotionLimits | None, config: GuardConfig = DEFAULT_CONFIG) -> float:
    """How far from the robot static geometry is considered this cycle: ``static_range_m``, or the
    stopping distance from the higher of the top speed and the measured one plus ``static_reach_m``
    when that is farther."""
    limits = limits or MotionLimits()
    speed = float(robot.speed_mps)
    top = max(float(limits.max_speed_mps), abs(speed) if math.isfinite(speed) else 0.0)
    return max(config.static_range_m, stopping_distance_m(top, limits, config) + config.static_reach_m)


# m: segments up to this long are sampled into discs once per layer; longer ones are clipped to the window
# round the robot each cycle (a 2000 km wall would otherwise be 13 million discs).
LONGEST_SAMPLED_M = 100.0


def _clip_to_window(segments: np.ndarray, centre: np.ndarray, half_size_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Segments (M, 2, 2) clipped to the squares of half size ``half_size_m`` (M,) round ``centre``
    (Liang-Barsky): the clipped segments and which ones meet their square at all. Written with each
    segment's midpoint and half-vector so that coordinates up to the largest float do not overflow."""
    middle = segments[:, 0] / 2 + segments[:, 1] / 2
    half = segments[:, 1] / 2 - segments[:, 0] / 2
    low, high = np.full(len(segments), -1.0), np.full(len(segments), 1.0)
    inside = np.ones(len(segments), dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        for axis in range(2):
            d = half[:, axis]
            lo = centre[axis] - half_size_m - middle[:, axis]
            hi = centre[axis] + half_size_m - middle[:, axis]
            flat = d == 0
            inside &= ~flat | ((lo <= 0) & (hi >= 0))
            a, b = lo / np.where(flat, 1.0, d), hi / np.where(flat, 1.0, d)
            low = np.where(flat, low, np.maximum(low, np.minimum(a, b)))
            high = np.where(flat, high, np.minimum(high, np.maximum(a, b)))
    inside &= low <= high
    clipped = np.stack([middle + low[:, None] * half, middle + high[:, None] * half], axis=1)
    return clipped[inside], inside


def with_static_rows(
    observation: Observation,
    config: GuardConfig = DEFAULT_CONFIG,
    repairs: list[str] | None = None,
    limits: MotionLimits | None = None,
) -> Observation:
    """The observation with its static layer as static rows of its obstacles (discs of velocity 0 and
    σ 0 sampled along the segments, :func:`viapath.static.sample_discs`, within :func:`static_range_for` of
    the robot) and no static layer left: what every planner, this guard's command check and the shield see.
    Segments with a coordinate that is not finite are left out (and listed in ``repairs``): a static
    return says where something is, and a bad one says nothing. A segment longer than the window round
    the robot or with a coordinate beyond ``max_coordinate_m`` is clipped to that window (never left out
    whole: its part near the robot is as real as a short wall), so a wall of any length costs discs
    in proportion to the window only."""
    static = observation.static
    good = static.finite_mask()
    if not good.all():
        if repairs is not None:
            for i in np.flatnonzero(~good)[:5]:
                repairs.append(
                    f"static.segments[{i}]: expected finite coordinates, found "
                    f"{_show(static.segments[i].ravel())}; left out"
                )
        static = static.subset(good)
    position = np.asarray(observation.robot.position, dtype=float)
    reach = static_range_for(observation.robot, limits, config)
    static = static.near(position, reach + config.static_spacing_m)
    plain, wide = static.split_wide(config.max_coordinate_m, LONGEST_SAMPLED_M)
    centres, radii, shape_ids = plain.discs(float(observation.robot.radius_m), config.static_spacing_m)
    if len(wide):
        window = reach + wide.padding_m + config.static_spacing_m
        clipped, meets = _clip_to_window(wide.segments, position, window)
        if len(clipped):
            pad = wide.padding_m[meets]
            more = sample_discs(
                clipped, wide.shape_ids[meets], float(observation.robot.radius_m), config.static_spacing_m, True
            )
            centres = np.concatenate([centres, more[0]])
            radii = np.concatenate([radii, more[1] + pad[more[3]]])
            shape_ids = np.concatenate([shape_ids, more[2]])
    near = np.hypot(*(centres - position).T) - radii <= reach
    if not near.all():
        centres, radii, shape_ids = centres[near], radii[near], shape_ids[near]
    people, n = observation.obstacles, len(centres)
    if n == 0:
        return Observation(observation.time_s, observation.robot, people)
    zeros = np.zeros(n)
    merged = Obstacles(
        np.concatenate([people.positions, centres]),
        np.concatenate([people.velocities, np.zeros((n, 2))]),
        np.concatenate([people.radii_m, radii]),
        np.concatenate([people.position_sigma_m, zeros]),
        np.concatenate([people.velocity_sigma_mps, zeros]),
        np.concatenate([np.asarray(people.ids, dtype=np.int64), STATIC_ID_BASE + shape_ids]),
        np.concatenate([people.is_static, np.ones(n, dtype=bool)]),
    )
    return Observation(observation.time_s, observation.robot, merged)


def _plainly_sound(observation: Observation, robot: RobotState, obstacles: Obstacles, config: GuardConfig) -> bool:
    """The common case of :func:`inspect_observation`, in few operations (every cycle comes here): every
    number a float and every array a float64 array of its shape, nothing to stop for, nothing to repair.
    False says only "look closer": the checks below then decide, and name what is wrong. With every bound
    finite (``config.all_finite``) a value within its bound is finite too."""
    time_s, heading, speed, turn, radius = (
        observation.time_s,
        robot.heading_rad,
        robot.speed_mps,
        robot.turn_rate_radps,
        robot.radius_m,
    )
    position, positions, velocities = robot.position, obstacles.positions, obstacles.velocities
    if not (
        isinstance(time_s, float)
        and isinstance(heading, float)
        and isinstance(speed, float)
        and isinstance(turn, float)
        and isinstance(radius, float)
        and config.all_finite
        and type(position) is np.ndarray
        and position.dtype is _FLOAT64
        and position.shape == (2,)
        and type(positions) is np.ndarray
        and positions.dtype is _FLOAT64
        and positions.ndim == 2
        and positions.shape[1] == 2
    ):
        return False
    x, y = position.tolist()
    if not (
        math.isfinite(time_s)
        and abs(x) <= config.max_coordinate_m
        and abs(y) <= config.max_coordinate_m
        and abs(heading) <= config.max_heading_rad
        and abs(speed) <= config.max_state_speed_mps
        and abs(turn) <= config.max_state_turn_rate_radps
        and 0.0 < radius < math.inf
    ):
        return False
    return _plain_obstacle_arrays(obstacles) and _obstacles_sound(
        positions,
        velocities,
        obstacles.radii_m,
        obstacles.position_sigma_m,
        obstacles.velocity_sigma_mps,
        config,
    )


def _plain_obstacle_arrays(obstacles: Obstacles) -> bool:
    """Whether every obstacle field but the positions (checked already) is a float64 array of its shape (the
    ids: an array of one per row)."""
    n = obstacles.positions.shape[0]
    velocities, radii, position_sigma, velocity_sigma, ids = (
        obstacles.velocities,
        obstacles.radii_m,
        obstacles.position_sigma_m,
        obstacles.velocity_sigma_mps,
        obstacles.ids,
    )
    rows, row = (n, 2), (n,)
    return (
        type(velocities) is np.ndarray
        and velocities.dtype is _FLOAT64
        and velocities.shape == rows
        and type(radii) is np.ndarray
        and radii.dtype is _FLOAT64
        and radii.shape == row
        and type(position_sigma) is np.ndarray
        and position_sigma.dtype is _FLOAT64
        and position_sigma.shape == row
        and type(velocity_sigma) is np.ndarray
        and velocity_sigma.dtype is _FLOAT64
        and velocity_sigma.shape == row
        and type(ids) is np.ndarray
        and ids.shape == row
    )


def _obstacles_sound(
    positions: np.ndarray,
    velocities: np.ndarray,
    radii: np.ndarray,
    position_sigma: np.ndarray,
    velocity_sigma: np.ndarray,
    config: GuardConfig,
) -> bool:
    """Whether no obstacle field needs a stop or a repair (:func:`viapath.guard_checks.obstacles_sound`, one
    compiled call: an episode's every cycle comes here; the per-field checks run only when this is False)."""
    if len(positions) == 0:
        return True
    return obstacles_sound(
        positions,
        velocities,
        radii,
        position_sigma,
        velocity_sigma,
        config.max_coordinate_m,
        config.max_obstacle_speed_mps,
        config.max_radius_m,
        config.max_velocity_sigma_mps,
        config.max_position_sigma_m,
    )


def stopping_distance_m(speed_mps: float, limits: MotionLimits, config: GuardConfig = DEFAULT_CONFIG) -> float:
    """How far the robot goes holding ``speed_mps`` for one control period and then braking at the
    limit, plus the margin."""
    v = max(0.0, float(speed_mps))
    return v * config.control_period_s + v * v / (2.0 * max(limits.max_accel_mps2, 1e-9)) + config.brake_margin_m


BRAKING_SAMPLES_PER_PERIOD = 5  # the braking roll-out's samples of the held command


def check_command(
    command: Any,
    observation: Observation,
    limits: MotionLimits,
    robot_radius_m: float,
    config: GuardConfig = DEFAULT_CONFIG,
) -> tuple[Command, str | None, str | None]:
    """The command to send, the status if it was replaced (``guard-stop`` / ``guard-brake``) and why."""
    try:
        v, w = float(command.speed_mps), float(command.turn_rate_radps)
    except (AttributeError, TypeError, ValueError):
        return Command.stop(), "guard-stop", f"command: expected a Command (v, ω), found {command!r}"[:300]
    tol = config.tolerance
    if not (math.isfinite(v) and math.isfinite(w)):
        return Command.stop(), "guard-stop", f"command ({v:g}, {w:g}): not finite"
    if not (-tol <= v <= limits.max_speed_mps + tol and abs(w) <= limits.max_turn_rate_radps + tol):
        return (
            Command.stop(),
            "guard-stop",
            (
                f"command ({v:g} m/s, {w:g} rad/s): outside the limits 0 ≤ v ≤ {limits.max_speed_mps:g} m/s, "
                f"|ω| ≤ {limits.max_turn_rate_radps:g} rad/s"
            ),
        )
    v = min(max(v, 0.0), limits.max_speed_mps)
    w = min(max(w, -limits.max_turn_rate_radps), limits.max_turn_rate_radps)
    obstacles = observation.obstacles
    if v > 0 and len(obstacles.positions):
        robot = observation.robot
        position = np.asarray(robot.position, dtype=float)
        # Only obstacles the robot could reach before it is at rest, at its fastest, need the roll-out.
        reachable_m = stopping_distance_m(max(limits.max_speed_mps, float(robot.speed_mps)), limits, config)
        i = _first_touched(robot, position, v, w, limits, obstacles, robot_radius_m, config, reachable_m)
        if i >= 0:
            distance_m = float(np.hypot(*(obstacles.positions[i] - position)))
            reach_m = robot_radius_m + obstacles.radii_m[i] + config.brake_margin_m
            return (
                Command(0.0, w),
                "guard-brake",
                (
                    f"command ({v:g} m/s, {w:g} rad/s) closes on obstacle {i} (id {int(obstacles.ids[i])}), "
                    f"{distance_m - reach_m + config.brake_margin_m:.3f} m away: braking from here would still "
                    "reach it; speed set to 0"
                ),
            )
    return _unchanged(command, v, w), None, None


def _first_touched(
    robot: RobotState,
    position: np.ndarray,
    v: float,
    w: float,
    limits: MotionLimits,
    obstacles: Obstacles,
    robot_radius_m: float,
    config: GuardConfig,
    reachable_m: float,
) -> int:
    """The first obstacle (index) within ``reachable_m`` now that the robot, holding (v, w) for a control period
    and then braking (:func:`braking_path`), would touch while its first sample moves towards it; -1 if none:
    :func:`viapath.guard_checks.first_touched`, one compiled call."""
    return first_touched(
        float(position[0]),
        float(position[1]),
        float(robot.heading_rad),
        float(robot.speed_mps),
        float(robot.turn_rate_radps),
        v,
        w,
        *_braking(limits, config),
        obstacles.positions,
        obstacles.radii_m,
        float(robot_radius_m),
        float(config.brake_margin_m),
        float(reachable_m),
    )


_BRAKING: tuple[Any, ...] = (None, None, None)  # the last (limits, config, Braking), replaced whole (threads)


def _braking(limits: MotionLimits, config: GuardConfig) -> Braking:
    """How :func:`_first_touched` rolls a command out (both dataclasses are frozen: the record of the same
    two objects is kept)."""
    global _BRAKING
    last = _BRAKING
    if last[0] is limits and last[1] is config:
        return cast(Braking, last[2])
    braking = Braking(
        float(limits.max_speed_mps),
        float(limits.max_turn_rate_radps),
        float(limits.max_accel_mps2),
        float(limits.max_turn_accel_radps2),
        float(config.control_period_s),
        BRAKING_SAMPLES_PER_PERIOD,
    )
    _BRAKING = (limits, config, braking)
    return braking


def _unchanged(command: Any, v: float, w: float) -> Command:
    """``command`` itself when it is a Command of these very floats (float() and the clipping hand back the
    object they were given when it is a float within the limits), else a new Command(v, w)."""
    if type(command) is Command and command.speed_mps is v and command.turn_rate_radps is w:
        return command
    return Command(v, w)


def _stop_decision(
    planner: Any, observation: Observation, status: str, reasons: list[str], extras: dict[str, Any] | None = None
) -> Decision:
    try:
        target = np.asarray(observation.robot.position, dtype=float).reshape(2).copy()
    except Exception:
        target = np.zeros(2)
    subgoal_index = getattr(getattr(planner, "subgoals", None), "index", 1)
    plan = Plan(status, 0.0, target, subgoal_index=subgoal_index, extras={"guard": list(reasons), **(extras or {})})
    return Decision(Command.stop(), plan)


@dataclass
class _GuardedCycle:
    """One cycle as the outermost guarded ``plan`` sees it: the observation its inspection handed on, the
    configuration it was inspected with, and the last command check against that observation. A planner
    inside another guarded one (the shield's) has its command checked by both guards; when the outer one
    is handed the same command, it is the same check and made once."""

    observation: Observation
    config: GuardConfig
    last_check: tuple[Any, ...] | None = None  # (limits, radius, v, ω, what check_command returned)

    def check(
        self, command: Any, limits: MotionLimits, robot_radius_m: float
    ) -> tuple[Command, str | None, str | None]:
        """:func:`check_command` of ``command`` against this cycle's observation (a pure function of its
        arguments: a check of the same command, limits and radius is answered from the last one)."""
        v, w = getattr(command, "speed_mps", None), getattr(command, "turn_rate_radps", None)
        if not (type(command) is Command and isinstance(v, float) and isinstance(w, float)):
            # Anything else (an array, a string, an int) is checked, never compared: check_command says what it is.
            return check_command(command, self.observation, limits, robot_radius_m, self.config)
        last = self.last_check
        if (
            last is not None
            and last[0] is limits
            and last[1] == robot_radius_m
            and _same_number(last[2], v)
            and _same_number(last[3], w)
        ):
            return last[4]
        result = check_command(command, self.observation, limits, robot_radius_m, self.config)
        self.last_check = (limits, robot_radius_m, v, w, result)
        return result


def _same_number(a: float, b: float) -> bool:
    """Equal, with the same sign for zeros (a NaN is never the same: it is checked again)."""
    return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)


#: The cycle of the innermost running guarded ``plan`` (per thread and task).
_INSPECTED: contextvars.ContextVar[_GuardedCycle | None] = contextvars.ContextVar(
    "viapath_guard_inspected", default=None
)


def inspected(observation: Observation) -> bool:
    """Whether the innermost running guarded ``plan`` was handed this very ``observation`` out of its
    inspection, with a configuration of finite numbers: then every obstacle field is finite (sound within
    finite bounds, or repaired to finite values), and :meth:`~viapath.observation.Obstacles.finite` would
    keep every obstacle."""
    cycle = _INSPECTED.get()
    if cycle is None or cycle.observation is not observation:
        return False
    return cycle.config.all_finite


def guard_plan(plan: Callable[..., Decision]) -> Callable[..., Decision]:
    """Wrap a planner's ``plan(self, observation)`` with the checks of this module (idempotent; a
    ``plan`` that calls ``super().plan`` is guarded once, at the outside)."""
    if getattr(plan, "__viapath_guarded__", False):
        return plan

    @functools.wraps(plan)
    def guarded(self: Any, observation: Observation, *args: Any, **kwargs: Any) -> Decision:
        if getattr(self, "_guard_active", False):
            return plan(self, observation, *args, **kwargs)
        config = getattr(self, "guard_config", DEFAULT_CONFIG)
        cycle = _INSPECTED.get()
        if cycle is not None and cycle.observation is observation and cycle.config == config:
            # A planner inside another guarded one (the shield's): this very observation came out of the
            # outer guard's inspection with the same configuration, and an inspected (or repaired)
            # observation passes again with nothing to stop for or repair. The cycle is the outer one's.
            inspection = Inspection(observation, [], [])
        else:
            inspection = inspect_observation(observation, config)
            if inspection.observation is None:
                return _stop_decision(self, observation, "guard-stop", inspection.stop_reasons + inspection.repairs)
            if len(inspection.observation.static):
                inspection.observation = with_static_rows(
                    inspection.observation, config, inspection.repairs, getattr(self, "limits", None)
                )
            cycle = _GuardedCycle(inspection.observation, config)
        self._guard_active = True
        token = _INSPECTED.set(cycle)
        try:
            decision = plan(self, inspection.observation, *args, **kwargs)
        finally:
            _INSPECTED.reset(token)
            self._guard_active = False
        return _checked(self, observation, decision, cycle, inspection.repairs)

    guarded.__viapath_guarded__ = True  # type: ignore[attr-defined]
    return guarded


def _checked(
    planner: Any, observation: Observation, decision: Decision, cycle: _GuardedCycle, repairs: list[str]
) -> Decision:
    """The planner's ``decision`` after the command check (:meth:`_GuardedCycle.check`), with the inspection's
    ``repairs`` listed in its plan."""
    limits = getattr(planner, "limits", None) or MotionLimits()
    own_radius = float(getattr(planner, "robot_radius_m", 0.0) or 0.0)
    if not math.isfinite(own_radius):  # max(nan, r) is nan, which no check would brake for
        bad_radius = f"robot_radius_m: expected a finite number, found {own_radius:g}"
        return _stop_decision(planner, observation, "guard-stop", repairs + [bad_radius])
    radius = max(own_radius, float(observation.robot.radius_m))
    command, status, reason = cycle.check(getattr(decision, "command", None), limits, radius)
    if status is not None:
        plan_ = getattr(decision, "plan", None)
        if status == "guard-stop" or plan_ is None:
            original = getattr(plan_, "status", None)
            return _stop_decision(
                planner, observation, "guard-stop", [*repairs, cast(str, reason)], {"guard_planner_status": original}
            )
        plan_.extras["guard"] = repairs + [reason]
        plan_.extras["guard_planner_status"] = plan_.status
        plan_.status = status
        plan_.speed_mps = 0.0
        decision.command = command
        return decision
    if repairs:
        decision.plan.extras["guard"] = list(repairs)
    if command is not decision.command and command != decision.command:
        decision.command = command
    return decision
