"""Warnings about scenarios that are valid but will mislead.

A scenario that cannot run is an error (:mod:`viapath.scenarios.models`, e.g. more than
``MAX_STEPS`` steps); one that runs but whose numbers would be misread gets a warning here, printed
by ``viapath run`` before the episode:

* an obstacle that **starts overlapping** the robot: the contact is not the robot's doing. The
  metrics count it apart (``overlapping_at_appearance``) and not as an at-fault collision
  (:func:`viapath.sim.metrics.at_fault_onsets`); ``collision`` stays true (there was contact);
* a corridor **narrower than the robot** (a half-width below the robot radius): the corridor bounds
  the robot *centre*, so it still holds the robot, but there is no room to pass anyone inside it and
  any escape ends outside it. We chose a warning, not an error: a narrow corridor is a legitimate
  "stay on the line" specification when nobody is in the way.
"""

from __future__ import annotations

import numpy as np


def scenario_warnings(scenario) -> list[str]:
    """Human-readable warnings (field named) for a validated :class:`~viapath.scenarios.models.Scenario`."""
    warnings: list[str] = []
    radius = float(scenario.robot.radius)
    widths = scenario.path.widths()
    field = "path.half_width" if scenario.path.half_widths is None else "path.half_widths"
    narrow = [i for i, w in enumerate(widths) if w < radius]
    if narrow:
        i = narrow[0]
        where = "" if scenario.path.half_widths is None else f"[{i}]"
        warnings.append(
            f"{field}{where} = {widths[i]:g} m is less than the robot radius {radius:g} m: the corridor is narrower "
            "than the robot, so no planner can pass anyone inside it and an escape ends outside it "
            f"({len(narrow)} of {len(widths)} segment(s))"
        )
    try:
        from viapath.sim.obstacles import scenario_obstacle_states

        positions, _, radii = scenario_obstacle_states(scenario, np.array([0.0]))
    except Exception:
        return warnings
    start = np.asarray(scenario.robot.start, dtype=float)
    present = np.isfinite(positions[0]).all(axis=1)
    gap = np.hypot(*(positions[0] - start).T) - radii - radius
    for j in np.flatnonzero(present & (gap < 0)):
        warnings.append(
            f"obstacle {j} starts overlapping the robot ({-gap[j]:.2f} m deep): the contact is counted "
            "in overlapping_at_appearance, not as an at-fault collision"
        )
    return warnings
