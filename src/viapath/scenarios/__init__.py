"""Scenarios: the YAML schema, loading with clear errors, and the built-in scenario files."""

from viapath.scenarios.loader import ScenarioError, builtin_names, load_scenario, scenario_from_dict
from viapath.scenarios.models import Scenario

__all__ = ["Scenario", "ScenarioError", "builtin_names", "load_scenario", "scenario_from_dict"]
