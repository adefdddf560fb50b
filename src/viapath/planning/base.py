"""The planner protocol (docs/design.md §4): what every planner is handed and what it returns.

A planner is built once per episode with the designated path, the robot's limits and its options,
then called every cycle with an :class:`~viapath.observation.Observation`; it returns a
:class:`Decision`: the command (v, ω) and its plan for display and analysis.

:meth:`Planner.plan` is a template method, the same for every planner: it keeps the obstacles whose
estimates are usable, tracks the subgoal (paper §2), stops at the goal and works out the one safety
inflation every planner gets (combined radius + margin + σ terms, the velocity cone capped at
``max_inflation_m``) and how far outside the corridor the robot already is. It hands that
:class:`Situation` to :meth:`Planner.decide`, the only method a planner must write. Subclasses
register by name (``class Mine(Planner, name="mine")``); a second planner of the same name is an
error. Options are declared once as an :class:`~viapath.options.OptionSet` in the class attribute
``options`` (the common ones below come first).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from viapath.guard import guard_plan, inspected
from viapath.jit import compiled
from viapath.kinematics import steer_towards
from viapath.observation import Command, MotionLimits, Observation, Obstacles, RobotState
from viapath.observation import Decision as Decision  # re-exported: the planners' results
from viapath.observation import Plan as Plan
from viapath.options import Option, OptionSet, Settings
from viapath.path import DesignatedPath, SubgoalPolicy, SubgoalTracker, corridor_excess_at
from viapath.registry import Registry

PLANNERS: Registry[type[Planner]] = Registry("planner")

COMMON_OPTIONS = OptionSet(
    [
        Option(
            "safety_margin_m",
            0.05,
            "clearance added to every combined robot + obstacle radius",
            "m",
            minimum=0.0,
            maximum=2.0,
        ),
        Option(
            "uncertainty_sigmas",
            2.0,
            "how many σ of position/velocity uncertainty inflate an obstacle",
            "",
            minimum=0.0,
            maximum=10.0,
        ),
        Option(
            "max_inflation_m", 0.15, "cap on the growth of the velocity-uncertainty cone", "m", minimum=0.0, maximum=5.0
        ),
    ],
    owner="planner",
)


@dataclass(frozen=True)
class Inflation:
    """The one safety inflation: obstacle i must be kept ``check_radii[i] + growth[i]·min(t,
    growth_until_s[i])`` from the robot centre at time t from now (docs/design.md §2: the cylinder becomes a
    capped cone). Replanning every cycle corrects a velocity error before it matters far ahead, so the
    cone stops growing once it has added ``max_inflation_m`` (else head-on passes never fit a corridor)."""

    obstacle_radii_m: np.ndarray  # obstacle radius + margin + k·σ_position (the robot's own radius apart)
    check_radii: np.ndarray  # robot + obstacle radius + margin + k·σ_position
    growth: np.ndarray  # k·σ_velocity, m/s
    growth_until_s: np.ndarray  # when the cone stops growing

    @classmethod
    def of(cls, obstacles: Obstacles, robot_radius_m: float, settings: Mapping[str, Any]) -> Inflation:
        if len(obstacles) == 0:
            return _NO_INFLATION
        rows = inflation_rows(
            obstacles.radii_m,
            obstacles.position_sigma_m,
            obstacles.velocity_sigma_mps,
            float(robot_radius_m),
            float(settings["safety_margin_m"]),
            float(settings["uncertainty_sigmas"]),
            float(settings["max_inflation_m"]),
        )
        return cls(rows[0], rows[1], rows[2], rows[3])


@compiled
def inflation_rows(
    radii: np.ndarray,
    position_sigma: np.ndarray,
    velocity_sigma: np.ndarray,
    robot_radius_m: float,
    margin_m: float,
    sigmas: float,
    max_inflation_m: float,
) -> np.ndarray:
    """:class:`Inflation`'s rows (4, N): obstacle radius + margin + k·σ_position; the same with the robot's
    radius added after the obstacle's; the cone's growth k·σ_velocity; when it stops growing (∞ if it does
    not grow, a NaN growth included)."""
    out = np.empty((4, radii.shape[0]))
    for i in range(radii.shape[0]):
        position_term = sigmas * position_sigma[i]
        growth = sigmas * velocity_sigma[i]
        out[0, i] = radii[i] + margin_m + position_term
        out[1, i] = radii[i] + robot_radius_m + margin_m + position_term
        out[2, i] = growth
        out[3, i] = max_inflation_m / growth if growth > 0 else math.inf
    return out


@compiled
def situation_numbers(
    radii: np.ndarray,
    position_sigma: np.ndarray,
    velocity_sigma: np.ndarray,
    robot_radius_m: float,
    margin_m: float,
    sigmas: float,
    max_inflation_m: float,
    x: float,
    y: float,
    starts: np.ndarray,
    directions: np.ndarray,
    lengths_m: np.ndarray,
    half_widths_m: np.ndarray,
) -> tuple[np.ndarray, float]:
    """:func:`inflation_rows` and how far the finite point (x, y) is outside the corridor of these segments
    (:func:`viapath.path.corridor_excess_at`), in the one call :meth:`Planner.situation` makes every cycle."""
    rows = inflation_rows(radii, position_sigma, velocity_sigma, robot_radius_m, margin_m, sigmas, max_inflation_m)
    return rows, corridor_excess_at(x, y, starts, directions, lengths_m, half_widths_m)


# The inflation of no obstacles: one instance serves every empty scene (its arrays hold nothing to change;
# they stay writeable, as the compiled functions are compiled for writeable arrays).
_NO_INFLATION = Inflation(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0))


@dataclass
class Situation:
    """One cycle's facts, the same for every planner: where the robot is, what it heads for, the
    obstacles it must keep clear of (usable estimates only) and how far outside the corridor it is."""

    observation: Observation
    position: np.ndarray
    obstacles: Obstacles
    inflation: Inflation
    subgoal: np.ndarray
    subgoal_index: int
    corridor_excess_m: float  # how far outside the corridor the robot already is (0 inside)

    @property
    def robot(self) -> RobotState:
        return self.observation.robot

    @property
    def corridor_tolerance_m(self) -> float:
        """A robot already outside may come back but not go further out."""
        return self.corridor_excess_m + 1e-9


class Planner:
    """Base class: the per-cycle template, the options, and registration by name."""

    name: ClassVar[str] = ""
    options: ClassVar[OptionSet] = COMMON_OPTIONS
    #: The shield behind the planner, when there is one (set by ``viapath.safety.ShieldedPlanner``); a
    #: planner that plans inside it (docs/design.md §7) checks its candidates' commands with it.
    shield: Any = None

    def __init_subclass__(cls, name: str | None = None, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if name:
            cls.name = name
            PLANNERS.add(name, cls)
        if "plan" in cls.__dict__:  # every planner's cycle goes through the guarded entry (viapath.guard)
            cls.plan = guard_plan(cls.__dict__["plan"])  # type: ignore[method-assign]

    def __init__(
        self,
        path: DesignatedPath,
        *,
        nominal_speed_mps: float = 0.2,
        limits: MotionLimits | None = None,
        robot_radius_m: float = 0.25,
        subgoal_policy: SubgoalPolicy | None = None,
        options: Mapping[str, Any] | None = None,
        **option_values: Any,
    ):
        _check_description(self, nominal_speed_mps, limits or MotionLimits(), robot_radius_m)
        self.path = path
        self.nominal_speed_mps = float(nominal_speed_mps)
        self.limits = limits or MotionLimits()
        self.robot_radius_m = float(robot_radius_m)
        self.subgoal_policy = subgoal_policy or SubgoalPolicy()
        self.subgoals = SubgoalTracker(path, self.subgoal_policy)
        # Every option's value (defaults filled in), validated against the class's schema.
        self.settings: Settings = type(self).options.validate(
            {**dict(options or {}), **option_values}, where=f"planner {self.name or type(self).__name__}"
        )

    def reset(self) -> None:
        self.subgoals = SubgoalTracker(self.path, self.subgoal_policy)

    # -- the cycle (template) --------------------------------------------------------------------

    def plan(self, observation: Observation) -> Decision:
        situation = self.situation(observation)
        if self.subgoals.goal_reached(situation.position):
            subgoal = situation.subgoal
            return Decision(Command.stop(), Plan("goal", 0.0, subgoal.copy(), subgoal_index=situation.subgoal_index))
        return self.decide(situation)

    def situation(self, observation: Observation) -> Situation:
        position = np.asarray(observation.robot.position, dtype=float)
        # Out of the guard's inspection every obstacle is finite already: finite() would keep them all.
        obstacles = observation.obstacles if inspected(observation) else observation.obstacles.finite()
        self.subgoals.update(position, self.robot_radius_m, obstacles.positions, obstacles.radii_m)
        inflation, excess_m = self._inflation_and_excess(obstacles, position)
        return Situation(
            observation=observation,
            position=position,
            obstacles=obstacles,
            inflation=inflation,
            subgoal=self.subgoals.subgoal,
            subgoal_index=self.subgoals.index,
            corridor_excess_m=max(0.0, excess_m),
        )

    def _inflation_and_excess(self, obstacles: Obstacles, position: np.ndarray) -> tuple[Inflation, float]:
        """:meth:`Inflation.of` the obstacles and how far the robot is outside the corridor
        (:func:`viapath.path.corridor_excess_at`): every cycle, in compiled calls."""
        x, y = (float(position[0]), float(position[1])) if position.shape == (2,) else (math.nan, math.nan)
        if not (math.isfinite(x) and math.isfinite(y)):  # the path's own answer for any other position
            return Inflation.of(obstacles, self.robot_radius_m, self.settings), float(
                self.path.corridor_excess(position)
            )
        settings, path = self.settings, self.path
        cached = self.__dict__.get("_inflation_settings")  # (settings, its three numbers): read every cycle
        if cached is None or cached[0] is not settings:
            numbers = (
                float(settings["safety_margin_m"]),
                float(settings["uncertainty_sigmas"]),
                float(settings["max_inflation_m"]),
            )
            cached = self.__dict__["_inflation_settings"] = (settings, numbers)
        margin_m, sigmas, max_inflation_m = cached[1]
        rows, excess_m = situation_numbers(
            obstacles.radii_m,
            obstacles.position_sigma_m,
            obstacles.velocity_sigma_mps,
            self.robot_radius_m,
            margin_m,
            sigmas,
            max_inflation_m,
            x,
            y,
            path.segment_starts,
            path.segment_directions,
            path.segment_lengths_m,
            path.half_widths_m,
        )
        if len(obstacles) == 0:
            return _NO_INFLATION, excess_m
        return Inflation(rows[0], rows[1], rows[2], rows[3]), excess_m

    def episode_metrics(self) -> dict[str, Any]:
        """Metrics of the planner over the episode (e.g. the shield's interventions)."""
        return {}

    def decide(self, situation: Situation) -> Decision:  # pragma: no cover - interface
        raise NotImplementedError(f"{type(self).__name__} must implement decide(situation)")

    # -- helpers for planners ----------------------------------------------------------------------

    def steer(
        self, observation: Observation, target: np.ndarray, speed_mps: float, heading_gain: float = 2.5
    ) -> Command:
        """Turn towards ``target`` and drive at ``speed_mps``, slowing for large heading errors."""
        robot, position = observation.robot, observation.robot.position
        return Command(
            *steer_towards(
                float(position[0]),
                float(position[1]),
                float(robot.heading_rad),
                float(target[0]),
                float(target[1]),
                speed_mps,
                self.limits,
                heading_gain,
            )
        )


def _check_description(planner: Planner, nominal_speed_mps: float, limits: MotionLimits, robot_radius_m: float) -> None:
    """Refuse a robot description no robot has (:mod:`viapath.limits`), naming each bad field."""
    from viapath.limits import planner_description_errors
    from viapath.options import OptionError

    errors = planner_description_errors(nominal_speed_mps, limits, robot_radius_m)
    if errors:
        where = f"planner {planner.name or type(planner).__name__}"
        raise OptionError([(f"{where}: {field}", message) for field, message in errors])


Planner.plan = guard_plan(Planner.plan)  # type: ignore[method-assign]  # the template is the entry of every planner: guarded too
