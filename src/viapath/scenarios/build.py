"""From a scenario to what runs it: the designated path, the motion limits, the subgoal policy, the
planner (behind the shield when asked) and the perception. The simulator, the ROS 2 simulator node
and the views build from a scenario here, so each of them sees the same path and limits."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from viapath.observation import MotionLimits
from viapath.path import DesignatedPath, SubgoalPolicy
from viapath.scenarios.models import Scenario


def scenario_path(scenario: Scenario) -> DesignatedPath:
    """The designated path with its corridor: one half-width per segment."""
    return DesignatedPath(scenario.path.waypoints, half_widths_m=scenario.path.widths())


def scenario_limits(scenario: Scenario) -> MotionLimits:
    return MotionLimits(**scenario.robot.limits.model_dump())


def scenario_subgoal_policy(scenario: Scenario) -> SubgoalPolicy:
    return SubgoalPolicy(**scenario.subgoals.model_dump())


@dataclass(frozen=True)
class Setup:
    """What runs a scenario: its path, limits and subgoal policy, the planner and the perception."""

    path: DesignatedPath
    limits: MotionLimits
    subgoal_policy: SubgoalPolicy
    planner_name: str
    planner: Any  # a Planner, behind the shield when it is on
    perception_mode: str
    perception: Any  # a Perception, not yet reset


def build(
    scenario: Scenario,
    planner: str | None = None,
    planner_overrides: dict[str, Any] | None = None,
    shield: bool | None = None,
    shield_options: dict[str, Any] | None = None,
    perception: str | None = None,
    position_noise_m: float | None = None,
    velocity_noise_mps: float | None = None,
) -> Setup:
    """The scenario's path, limits, planner and perception; each argument given (not None) wins over the
    scenario's value. ``planner_overrides`` are option values over the scenario's ``planner:`` block;
    ``shield``: None is the planner's default (:func:`viapath.safety.shielded`)."""
    from viapath.perception.modes import make_perception
    from viapath.planning import make_planner
    from viapath.safety import shielded
    from viapath.scenarios.loader import planner_settings

    path = scenario_path(scenario)
    limits = scenario_limits(scenario)
    subgoal_policy = scenario_subgoal_policy(scenario)
    planner_name = planner or scenario.planner.name
    options = {**planner_settings(scenario, planner_name), **(planner_overrides or {})}
    the_planner = make_planner(
        planner_name,
        path,
        nominal_speed_mps=scenario.robot.speed,
        limits=limits,
        robot_radius_m=scenario.robot.radius,
        subgoal_policy=subgoal_policy,
        **options,
    )
    the_planner = shielded(the_planner, shield, scenario.dt_s, shield_options, planner_name)
    mode = perception or scenario.perception.mode
    sensing = make_perception(
        mode,
        scenario.perception.options,
        scenario.perception.position_noise_m if position_noise_m is None else position_noise_m,
        scenario.perception.velocity_noise_mps if velocity_noise_mps is None else velocity_noise_mps,
    )
    return Setup(path, limits, subgoal_policy, planner_name, the_planner, mode, sensing)
