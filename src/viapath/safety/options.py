"""One definition of each shield option (name, default, unit, bounds, help): DESIGN §7, §8.

The lead's planner option schema (``viapath.options.Option``) is used where it exists; until it is
on main an identical local record stands in, so the tuple below plugs into it unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

try:  # pragma: no cover - depends on what main has merged
    from viapath.options import Option  # type: ignore[attr-defined]
except ImportError:  # pragma: no cover
    @dataclass(frozen=True)
    class Option:  # type: ignore[no-redef]
        """One option: name, default, SI unit, inclusive bounds (None = open), help, allowed choices."""

        name: str
        default: Any
        unit: str = ""
        minimum: float | None = None
        maximum: float | None = None
        help: str = ""
        choices: tuple | None = None


SHIELD_MODES = ("passive", "passive-friendly")

SHIELD_OPTIONS: tuple[Option, ...] = (
    Option("enabled", True, "", None, None,
           "filter the planner's command through the passive-safety shield (DESIGN §7)"),
    Option("mode", "passive", "", None, None,
           "passive: the robot is at rest before any person's forecast disc can reach it; "
           "passive-friendly (Mitsch & Platzer 2017): also early enough that the person, braking at "
           "person_accel_mps2 from its forecast velocity, stops before contact", SHIELD_MODES),
    Option("margin_m", 0.05, "m", 0.0, 2.0,
           "clearance added to robot radius + person radius (at most the person's present gap)"),
    Option("person_accel_mps2", 1.0, "m/s^2", 0.0, 20.0,
           "bound on how sharply people change velocity: the forecast disc grows by a_p t^2 / 2"),
    Option("sigma_multiplier", 2.0, "", 0.0, 10.0,
           "forecast disc grows by k sigma_v t (and k sigma_p) with the tracker's uncertainty"),
    Option("towards_only", True, "", None, None,
           "count a meeting only while the robot moves towards the person's forecast centre (the robot is "
           "never the one moving into a person; a person catching up from behind meets it moving away); "
           "false: any meeting before rest counts (DESIGN §7 to the letter: at rest at every contact)"),
    Option("samples", 11, "", 2, 101,
           "commands sampled per axis (speed, turn rate) of the dynamic window when replacing one"),
    Option("substep_s", 0.025, "s", 0.001, 1.0,
           "longest sub-interval of the swept-disc test (a control period is split into equal ones)"),
)


def option_defaults() -> dict[str, Any]:
    return {option.name: option.default for option in SHIELD_OPTIONS}


def check_options(values: dict[str, Any], where: str = "shield") -> dict[str, Any]:
    """Defaults overlaid with ``values``; one clear ValueError naming the option for bad input."""
    known = {option.name: option for option in SHIELD_OPTIONS}
    unknown = sorted(set(values) - set(known))
    if unknown:
        raise ValueError(f"{where}: unknown option(s) {', '.join(unknown)}; known: {', '.join(known)}")
    merged = option_defaults()
    for name, value in values.items():
        option = known[name]
        if option.choices is not None:
            if value not in option.choices:
                raise ValueError(f"{where}.{name}: expected one of {', '.join(map(str, option.choices))}, found {value!r}")
        elif isinstance(option.default, bool):
            if not isinstance(value, bool):
                raise ValueError(f"{where}.{name}: expected true or false, found {value!r}")
        else:
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"{where}.{name}: expected a number, found {value!r}") from None
            if number != number or number in (float("inf"), float("-inf")):
                raise ValueError(f"{where}.{name}: expected a finite number, found {value!r}")
            if isinstance(option.default, int) and number != int(number):
                raise ValueError(f"{where}.{name}: expected an integer, found {value!r}")
            low, high = option.minimum, option.maximum
            if (low is not None and number < low) or (high is not None and number > high):
                raise ValueError(f"{where}.{name}: expected {low} <= value <= {high} {option.unit}".rstrip()
                                 + f", found {value!r}")
            value = int(number) if isinstance(option.default, int) else number
        merged[name] = value
    return merged
