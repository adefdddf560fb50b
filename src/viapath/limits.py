"""The physical bounds of a robot's description, checked where a planner is built and where a scenario is read.

A planner built with a NaN radius, a zero nominal speed or an acceleration limit of 1e-9 m/s² does
not fail at once: a NaN radius switches off the last brake (``max(nan, r)`` is nan), a zero speed
divides by zero on the first cycle, a tiny acceleration makes every braking roll-out millions of
steps long. So the description is refused where it is given, naming the field and the bounds.

The bounds are wide, physical ones (SI units): a robot slower than 1 cm/s or braking at less than
1 cm/s² is a typo, not a robot; odometry beyond the guard's state bounds is a sensor fault.
"""

from __future__ import annotations

import math
from typing import Any

from viapath.options import Option, OptionSet, short_repr

#: The base's limits (a small indoor robot like the paper's). The bounds are physical ones.
LIMITS_OPTIONS = OptionSet(
    [
        Option("max_speed_mps", 0.6, "speed limit of the base", "m/s", 0.01, 50.0),
        Option("max_accel_mps2", 0.8, "acceleration (and braking) limit of the base", "m/s²", 0.01, 100.0),
        Option("max_turn_rate_radps", 2.0, "turn-rate limit of the base", "rad/s", 0.01, 100.0),
        Option("max_turn_accel_radps2", 6.0, "turn acceleration limit of the base", "rad/s²", 0.01, 1000.0),
    ],
    owner="limits",
)

#: The robot's description besides its limits: the speed it keeps when nothing is in the way and its footprint.
ROBOT_OPTIONS = OptionSet(
    [
        Option("nominal_speed_mps", 0.2, "speed the robot keeps when nothing is in the way", "m/s", 0.01, 50.0),
        Option("robot_radius_m", 0.25, "radius of the robot's footprint", "m", 0.0, 10.0, exclusive_minimum=True),
    ],
    owner="robot",
)

#: When a subgoal of the designated path counts as reached, and when a blocked one is given up (paper §2).
SUBGOAL_OPTIONS = OptionSet(
    [
        Option("reach_threshold_m", 0.2, "an intermediate subgoal is reached within this", "m", 0.01, 10.0),
        Option("goal_tolerance_m", 0.1, "the goal is reached within this", "m", 0.01, 10.0),
        Option("bypass_distance_m", 1.0, "a blocked subgoal is given up within this", "m", 0.0, 100.0),
        Option(
            "blocked_clearance_m",
            0.1,
            "a subgoal is blocked when an obstacle's disc, grown by the robot radius, comes within this of it",
            "m",
        ),
    ],
    owner="subgoals",
)


def _bounds(option: Option) -> tuple[float, float]:
    assert option.minimum is not None and option.maximum is not None
    return option.minimum, option.maximum


#: field → (smallest, largest) allowed value, both inclusive, in the field's SI unit.
LIMIT_BOUNDS: dict[str, tuple[float, float]] = {option.name: _bounds(option) for option in LIMITS_OPTIONS}
ROBOT_RADIUS_BOUNDS_M = _bounds(ROBOT_OPTIONS["robot_radius_m"])  # > 0: the smallest is excluded
NOMINAL_SPEED_BOUNDS_MPS = _bounds(ROBOT_OPTIONS["nominal_speed_mps"])


def _number(value: Any) -> float | None:
    if isinstance(value, bool):
        return None
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        return None
    return number


def bounded_error(
    field: str, value: Any, bounds: tuple[float, float], unit: str, above_low: bool = False
) -> tuple[str, str] | None:
    """(field, message) when ``value`` is not a finite number within ``bounds`` (above the smallest
    rather than at least it, with ``above_low``), else None."""
    low, high = bounds
    number = _number(value)
    if (
        number is None
        or not math.isfinite(number)
        or not number <= high
        or not (number > low if above_low else number >= low)
    ):
        interval = f"{'(' if above_low else '['}{low:g}, {high:g}]"
        return field, f"expected a finite number in {interval} {unit}, found {short_repr(value)}"
    return None


def limits_errors(limits: Any, where: str = "limits") -> list[tuple[str, str]]:
    """Each field of a :class:`~viapath.observation.MotionLimits` (or anything with those attributes)
    that is missing, not finite or outside :data:`LIMIT_BOUNDS`."""
    errors = []
    for option in LIMITS_OPTIONS:
        name = option.name
        error = bounded_error(f"{where}.{name}", getattr(limits, name, None), LIMIT_BOUNDS[name], option.unit)
        if error is not None:
            errors.append(error)
    return errors


def planner_description_errors(nominal_speed_mps: Any, limits: Any, robot_radius_m: Any) -> list[tuple[str, str]]:
    """What is wrong with a planner's nominal speed, limits and robot radius (empty when nothing is)."""
    errors = [
        error
        for error in (
            bounded_error("robot_radius_m", robot_radius_m, ROBOT_RADIUS_BOUNDS_M, "m", above_low=True),
            bounded_error("nominal_speed_mps", nominal_speed_mps, NOMINAL_SPEED_BOUNDS_MPS, "m/s"),
        )
        if error is not None
    ]
    errors += limits_errors(limits)
    return errors
