"""The planner's option schema as the ROS 2 node sees it.

Source: :mod:`viapath.options` (one :class:`~viapath.options.Option` per tunable value: name,
default, help, unit, bounds, choices, group) and each planner's ``options`` set
(``planner_class(name).options``, common options first). The node declares one ROS parameter per
option, named ``planner.<group>.<name>`` (``planner.horizon_s``, ``planner.weights.k1``), and hands
the values back to the planner, whose own ``OptionSet.validate`` has the last word.
"""

from __future__ import annotations

from typing import Any

from viapath.options import Option

__all__ = ["Option", "planner_kwargs", "planner_options"]


def planner_options(planner_name: str) -> tuple[Option, ...]:
    """The option schema of a registered planner, in its declared order."""
    from viapath.planning import planner_class

    return tuple(planner_class(planner_name).options)


def planner_kwargs(planner_name: str, values: dict[str, Any]) -> dict[str, Any]:
    """Keyword arguments for ``make_planner``: option values keyed by their dotted path (``weights.k1``)."""
    return {"options": dict(values)}
