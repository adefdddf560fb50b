"""One definition of each shield option (name, default, unit, bounds, help): docs/design.md §7, §8.

The same :class:`~viapath.options.OptionSet` as the planners' options, so the CLI, the ROS 2
parameters and the listings are generated from it.
"""

from __future__ import annotations

from typing import Any

from viapath.options import Option, OptionError, OptionSet, Retired

SHIELD_MODES = ("passive", "passive-friendly")
# The option that once chose the shield's arithmetic (numpy or compiled), and its former name: old files and
# parameters still name them, so they are read and ignored with a warning.
_ONE_ARITHMETIC = "the shield has one implementation, compiled; plain Python when compilation is off"

SHIELD_OPTIONS = OptionSet(
    [
        Option("enabled", True, "filter the planner's command through the passive-safety shield (docs/design.md §7)"),
        Option(
            "mode",
            "passive",
            "passive: the robot is at rest before any person's forecast disc can reach it; "
            "passive-friendly (Mitsch & Platzer 2017): also early enough that the person, braking at "
            "person_accel_mps2 from its forecast velocity, stops before contact",
            choices=SHIELD_MODES,
        ),
        Option(
            "margin_m",
            0.05,
            "clearance added to robot radius + person radius (at most the person's present gap)",
            "m",
            minimum=0.0,
            maximum=2.0,
        ),
        Option(
            "person_accel_mps2",
            1.0,
            "bound on how sharply people change velocity: the forecast disc grows by a_p t^2 / 2",
            "m/s²",
            minimum=0.0,
            maximum=20.0,
        ),
        Option(
            "sigma_multiplier",
            2.0,
            "forecast disc grows by k sigma_v t (and k sigma_p) with the tracker's uncertainty",
            minimum=0.0,
            maximum=10.0,
        ),
        Option(
            "towards_only",
            True,
            "count a meeting only while the robot moves towards the person's forecast "
            "centre (the robot is never the one moving into a person; a person catching up from behind meets it "
            "moving away); false: any meeting before rest counts (docs/design.md §7 to the letter)",
        ),
        Option(
            "keep_in_corridor",
            True,
            "a command is admissible only if its braking sweep keeps the robot's centre inside the designated "
            "path's corridor (a robot already outside may not go further out): the corridor is a hard "
            "constraint, the robot stops inside rather than leave it",
        ),
        Option(
            "samples",
            11,
            "commands sampled per axis (speed, turn rate) of the dynamic window when replacing one",
            minimum=2,
            maximum=101,
        ),
        Option(
            "substep_s",
            0.025,
            "longest sub-interval of the swept-disc test (a control period is split into equal ones)",
            "s",
            minimum=0.001,
            maximum=1.0,
        ),
    ],
    owner="shield",
    retired=[Retired("compute", _ONE_ARITHMETIC), Retired("backend", _ONE_ARITHMETIC)],
)


def check_options(values: dict[str, Any], where: str = "shield") -> dict[str, Any]:
    """Defaults overlaid with ``values``; one clear ValueError naming the option for bad input. A retired name
    (``compute``, ``backend``) is read, with a FutureWarning, and left out."""
    try:
        return dict(SHIELD_OPTIONS.validate(values, where=where))
    except OptionError as error:
        raise ValueError(str(error)) from None
