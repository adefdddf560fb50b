"""viapath: follow a designated path and avoid moving obstacles by choosing speed as well as direction.

The core (``geometry``, ``path``, ``observation``, ``planning``) is pure numpy and is what goes on a
robot; the simulator, scenarios, I/O and plotting sit around it.

The names below are imported on first use: importing the package (``viapath --help``) decorates no
compiled step, so a command can still choose to run them as plain Python (:func:`viapath.jit.run_plain`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from viapath.observation import Command, Observation, Obstacles, RobotState
    from viapath.path import DesignatedPath

__all__ = ["Command", "DesignatedPath", "Observation", "Obstacles", "RobotState"]
__version__ = "0.1.0"

_HOMES = {
    "Command": "viapath.observation",
    "Observation": "viapath.observation",
    "Obstacles": "viapath.observation",
    "RobotState": "viapath.observation",
    "DesignatedPath": "viapath.path",
}


def __getattr__(name: str) -> Any:
    if name not in _HOMES:
        raise AttributeError(f"module 'viapath' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(_HOMES[name]), name)
    globals()[name] = value
    return value
