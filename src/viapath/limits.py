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

#: field → (smallest, largest) allowed value, both inclusive, in the field's SI unit.
LIMIT_BOUNDS: dict[str, tuple[float, float]] = {
    "max_speed_mps": (0.01, 50.0),
    "max_accel_mps2": (0.01, 100.0),
    "max_turn_rate_radps": (0.01, 100.0),
    "max_turn_accel_radps2": (0.01, 1000.0),
}
ROBOT_RADIUS_BOUNDS_M = (0.0, 10.0)  # > 0: the smallest is excluded
NOMINAL_SPEED_BOUNDS_MPS = (0.01, 50.0)


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
        from viapath.io.safe_read import short_repr

        interval = f"{'(' if above_low else '['}{low:g}, {high:g}]"
        return field, f"expected a finite number in {interval} {unit}, found {short_repr(value)}"
    return None


def limits_errors(limits: Any, where: str = "limits") -> list[tuple[str, str]]:
    """Each field of a :class:`~viapath.observation.MotionLimits` (or anything with those attributes)
    that is missing, not finite or outside :data:`LIMIT_BOUNDS`."""
    units = {
        "max_speed_mps": "m/s",
        "max_accel_mps2": "m/s²",
        "max_turn_rate_radps": "rad/s",
        "max_turn_accel_radps2": "rad/s²",
    }
    errors = []
    for name, bounds in LIMIT_BOUNDS.items():
        error = bounded_error(f"{where}.{name}", getattr(limits, name, None), bounds, units[name])
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
