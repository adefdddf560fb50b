"""Planners: the paper's (``viapath``) and baselines beside it, all behind one protocol.

The built-in planners register when their modules are imported here. Planners of other packages
come from the entry-point group ``viapath.planners`` (pyproject:
``[project.entry-points."viapath.planners"] mine = "my_pkg.planner"``), loaded on the first look-up;
a broken plug-in warns and leaves the built-ins.
"""

from __future__ import annotations

import importlib.util
import warnings
from importlib import metadata
from typing import Any

from viapath.observation import Decision, Plan
from viapath.options import OptionSet
from viapath.path import DesignatedPath
from viapath.planning import baselines  # noqa: F401  (importing a planner's module registers it)
from viapath.planning import viapath as _viapath  # noqa: F401
from viapath.planning.base import PLANNERS, Planner, Situation

if importlib.util.find_spec("navground") is not None:  # navground's behaviours: only with the extra
    from viapath.planning import navground_peers  # noqa: F401

_plugins_loaded = False


def _load_plugins() -> None:
    global _plugins_loaded
    if _plugins_loaded:
        return
    _plugins_loaded = True
    for entry in metadata.entry_points(group="viapath.planners"):
        try:
            entry.load()
        except Exception as error:  # a broken plug-in must not take the built-in planners down
            warnings.warn(f"planner plug-in {entry.name!r} ({entry.value}) failed to load: {error}", stacklevel=3)


def available_planners() -> list[str]:
    _load_plugins()
    return PLANNERS.names()


def planner_class(name: str) -> type[Planner]:
    _load_plugins()
    return PLANNERS.get(name)


def planner_options(name: str) -> OptionSet:
    """The options of planner ``name`` (name, default, unit, bounds, help), common ones first."""
    return planner_class(name).options


def make_planner(name: str, path: DesignatedPath, **kwargs: Any) -> Planner:
    return planner_class(name)(path, **kwargs)


__all__ = [
    "Decision",
    "Plan",
    "Planner",
    "Situation",
    "available_planners",
    "make_planner",
    "planner_class",
    "planner_options",
]
