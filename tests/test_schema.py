"""One schema: the robot's description, its motion limits and the subgoal policy are accepted within the
same bounds, with the same defaults, by a scenario file and by the ROS 2 node's parameters, and the
dataclasses the planner takes default to the same values."""

from __future__ import annotations

import dataclasses

import pytest
from annotated_types import Ge, Gt, Le

from viapath.observation import MotionLimits
from viapath.path import SubgoalPolicy
from viapath.ros2.settings import NODE_OPTIONS
from viapath.scenarios.models import LimitsSpec, RobotSpec, SubgoalSpec

# ROS 2 parameter name -> (scenario model, its field name there)
SHARED = {
    "nominal_speed_mps": (RobotSpec, "speed"),
    "robot_radius_m": (RobotSpec, "radius"),
    "max_speed_mps": (LimitsSpec, "max_speed_mps"),
    "max_accel_mps2": (LimitsSpec, "max_accel_mps2"),
    "max_turn_rate_radps": (LimitsSpec, "max_turn_rate_radps"),
    "max_turn_accel_radps2": (LimitsSpec, "max_turn_accel_radps2"),
    "reach_threshold_m": (SubgoalSpec, "reach_threshold_m"),
    "goal_tolerance_m": (SubgoalSpec, "goal_tolerance_m"),
    "bypass_distance_m": (SubgoalSpec, "bypass_distance_m"),
}


def _scenario_bounds(model, name: str):
    """(default, lower bound, lower bound excluded, upper bound) of a pydantic field, from its metadata."""
    info = model.model_fields[name]
    low, excluded, high = None, False, None
    for item in info.metadata:
        if isinstance(item, Ge):
            low, excluded = item.ge, False
        elif isinstance(item, Gt):
            low, excluded = item.gt, True
        elif isinstance(item, Le):
            high = item.le
    return info.default, low, excluded, high


def _ros_bounds(name: str):
    option = next(o for o in NODE_OPTIONS if o.name == name)
    return option.default, option.minimum, option.exclusive_minimum, option.maximum


@pytest.mark.parametrize("name", sorted(SHARED))
def test_ros_parameters_and_scenario_fields_have_the_same_bounds_and_default(name):
    model, field = SHARED[name]
    assert _ros_bounds(name) == _scenario_bounds(model, field)


def test_the_bounds_check_sees_a_difference():
    """The comparison reads real bounds: the scenario's robot radius is not the scenario's speed."""
    assert _scenario_bounds(RobotSpec, "radius") != _scenario_bounds(RobotSpec, "speed")
    assert _scenario_bounds(RobotSpec, "radius")[1:] == (0.0, True, 10.0)


def test_the_planner_dataclasses_default_to_the_scenario_defaults():
    assert dataclasses.asdict(MotionLimits()) == LimitsSpec().model_dump()
    assert dataclasses.asdict(SubgoalPolicy()) == SubgoalSpec().model_dump()


def test_a_scenario_refuses_what_the_node_refuses():
    from viapath.ros2.settings import ParameterError, validate
    from viapath.scenarios import ScenarioError
    from viapath.scenarios.loader import scenario_from_dict

    base = {"name": "x", "robot": {"start": [0, 0]}, "path": {"waypoints": [[0, 0], [5, 0]], "half_width": 1.0}}
    with pytest.raises(ScenarioError, match="reach_threshold_m"):
        scenario_from_dict({**base, "subgoals": {"reach_threshold_m": 20.0}})
    with pytest.raises(ParameterError, match="reach_threshold_m"):
        validate({"reach_threshold_m": 20.0})


def test_the_scenario_models_have_every_option_of_their_set_with_its_bounds():
    from viapath.limits import LIMITS_OPTIONS, ROBOT_OPTIONS, SUBGOAL_OPTIONS

    for model, options in ((LimitsSpec, LIMITS_OPTIONS), (SubgoalSpec, SUBGOAL_OPTIONS)):
        assert list(model.model_fields) == options.names
        for option in options:
            bounds = (option.default, option.minimum, option.exclusive_minimum, option.maximum)
            assert _scenario_bounds(model, option.name) == bounds, option.name
    for field, name in (("speed", "nominal_speed_mps"), ("radius", "robot_radius_m")):
        option = ROBOT_OPTIONS[name]
        assert _scenario_bounds(RobotSpec, field) == (
            option.default,
            option.minimum,
            option.exclusive_minimum,
            option.maximum,
        )


def test_the_scenario_json_schema_types_the_laser_options():
    """The laser chain's options appear in the scenario's JSON schema with their types, defaults and bounds."""
    from viapath.perception.segmentation import SegmentationParams
    from viapath.perception.tracking import TrackerParams
    from viapath.scenarios.models import Scenario

    schema = Scenario.model_json_schema()
    definitions = schema["$defs"]
    options = definitions[definitions["PerceptionSpec"]["properties"]["options"]["$ref"].split("/")[-1]]
    assert options["additionalProperties"] is False
    assert set(options["properties"]) >= {"scanners", "detector", "tracker", "static_layer"}
    min_points = definitions["SegmentationOptions"]["properties"]["min_points"]
    assert (min_points["type"], min_points["minimum"], min_points["default"]) == (
        "integer",
        2,
        SegmentationParams().min_points,
    )
    confirm_hits = definitions["TrackerOptions"]["properties"]["confirm_hits"]
    assert (confirm_hits["minimum"], confirm_hits["maximum"], confirm_hits["default"]) == (
        1,
        62,
        TrackerParams().confirm_hits,
    )
    assert "fit_compute" not in definitions["DetectorOptions"]["properties"]


@pytest.mark.parametrize("name", ["fit_compute", "fit_backend"])
def test_the_node_reads_the_retired_fit_parameter_with_a_warning(name):
    """The circle fit's former choice of arithmetic is read, whatever its value, with a FutureWarning, and the
    node's settings are those without it."""
    from viapath.ros2.settings import validate

    with pytest.warns(FutureWarning, match=f"option {name!r} no longer does anything"):
        settings = validate({name: "numpy", "detector": "legs"})
    assert settings.detector == "legs" and not hasattr(settings, name)
