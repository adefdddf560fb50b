"""The planner protocol (DESIGN §4) and the registry that lets the CLI and benchmark find planners.

A planner is built once per episode with the designated path and the robot's limits, then called
every cycle with an :class:`~viapath.observation.Observation`; it returns a :class:`Decision`:
the command (v, ω) and its plan for display and analysis. Subclasses register by name:

    class MyPlanner(Planner, name="mine"): ...
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from viapath.guard import guard_plan
from viapath.kinematics import steer_towards
from viapath.observation import Command, MotionLimits, Observation
from viapath.path import DesignatedPath, SubgoalPolicy, SubgoalTracker

_REGISTRY: dict[str, type["Planner"]] = {}


@dataclass
class Plan:
    """What a planner intends, for display and analysis. Planners fill what applies to them."""

    status: str  # e.g. "straight", "avoid", "stop", "escape", "goal"
    speed_mps: float
    target: np.ndarray  # the point the robot steers for now
    via_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    waypoints: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # chosen polyline from the robot
    subgoal_index: int = 1
    candidate_count: int = 0
    candidate_costs: np.ndarray = field(default_factory=lambda: np.zeros(0))
    candidate_polylines: list[np.ndarray] = field(default_factory=list)
    chosen: int | None = None
    extras: dict[str, Any] = field(default_factory=dict)


@dataclass
class Decision:
    command: Command
    plan: Plan


class Planner:
    """Base class: subgoal tracking shared by every planner, and registration by name."""

    name: ClassVar[str] = ""

    def __init_subclass__(cls, name: str | None = None, **kwargs):
        super().__init_subclass__(**kwargs)
        if name:
            cls.name = name
            _REGISTRY[name] = cls
        if "plan" in cls.__dict__:  # every planner's cycle goes through the guarded entry (viapath.guard)
            cls.plan = guard_plan(cls.__dict__["plan"])

    def __init__(
        self,
        path: DesignatedPath,
        *,
        nominal_speed_mps: float = 0.2,
        limits: MotionLimits | None = None,
        robot_radius_m: float = 0.25,
        subgoal_policy: SubgoalPolicy | None = None,
    ):
        self.path = path
        self.nominal_speed_mps = float(nominal_speed_mps)
        self.limits = limits or MotionLimits()
        self.robot_radius_m = float(robot_radius_m)
        self.subgoal_policy = subgoal_policy or SubgoalPolicy()
        self.subgoals = SubgoalTracker(path, self.subgoal_policy)

    def reset(self) -> None:
        self.subgoals = SubgoalTracker(self.path, self.subgoal_policy)

    def plan(self, observation: Observation) -> Decision:  # pragma: no cover - interface
        raise NotImplementedError

    def steer(self, observation: Observation, target: np.ndarray, speed_mps: float, heading_gain: float = 2.5) -> Command:
        """Turn towards ``target`` and drive at ``speed_mps``, slowing for large heading errors."""
        robot = observation.robot
        return steer_command(robot.position[0], robot.position[1], robot.heading_rad, target, speed_mps,
                             self.limits, heading_gain)


def steer_command(x: float, y: float, heading_rad: float, target, speed_mps: float, limits: MotionLimits,
                  heading_gain: float = 2.5) -> Command:
    """Turn towards ``target`` and drive at ``speed_mps``, slowing for large heading errors."""
    return Command(*steer_towards(float(x), float(y), float(heading_rad), float(target[0]), float(target[1]),
                                  speed_mps, limits, heading_gain))


def register(cls: type[Planner]) -> type[Planner]:
    _REGISTRY[cls.name] = cls
    return cls


def available_planners() -> list[str]:
    _load_builtin_planners()
    return sorted(_REGISTRY)


def planner_class(name: str) -> type[Planner]:
    _load_builtin_planners()
    try:
        return _REGISTRY[name]
    except KeyError:
        raise KeyError(f"unknown planner {name!r}; available: {', '.join(sorted(_REGISTRY))}") from None


def make_planner(name: str, path: DesignatedPath, **kwargs) -> Planner:
    return planner_class(name)(path, **kwargs)


def _load_builtin_planners() -> None:
    # Importing the modules runs their class definitions, which register them.
    import importlib
    import importlib.util

    import viapath.planning.viapath  # noqa: F401

    if importlib.util.find_spec("viapath.planning.baselines") is not None:
        importlib.import_module("viapath.planning.baselines")
    # Planners of other packages: an entry point in the group "viapath.planners" naming the module
    # that defines them (pyproject: [project.entry-points."viapath.planners"] mine = "my_pkg.planner").
    from importlib.metadata import entry_points

    for entry in entry_points(group="viapath.planners"):
        try:
            entry.load()
        except Exception as error:  # a broken plug-in must not take the built-in planners down
            import warnings

            warnings.warn(f"planner plug-in {entry.name!r} ({entry.value}) failed to load: {error}", stacklevel=2)
