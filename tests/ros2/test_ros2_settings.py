"""Parameters of the ROS 2 node: generated from the planner's option schema, bad values refused by name.

No rclpy needed: these check :mod:`viapath.ros2.settings` and :mod:`viapath.ros2.options` directly.
"""

from __future__ import annotations

import math
import pytest

from viapath.planning import make_planner, planner_class
from viapath.ros2.options import planner_kwargs
from viapath.ros2.settings import (ParameterError, all_options, describe, read_params_file, validate,
                                   write_example_params)


def test_every_planner_option_becomes_a_parameter_with_its_default():
    schema = list(planner_class("viapath").options)
    params = {o.name: o for o in all_options("viapath")}
    for option in schema:
        param = params[f"planner.{option.path}"]
        assert param.default == option.default and param.unit == option.unit
        assert (param.minimum, param.maximum, param.choices) == (option.minimum, option.maximum, option.choices)
    assert {"planner.horizon_s", "planner.weights.k1", "planner.speeds", "planner_name", "scanners.front.mount_x_m"} <= set(params)
    assert len([n for n in params if n.startswith("planner.")]) == len(schema)


def test_defaults_rebuild_the_default_planner():
    from viapath.path import DesignatedPath

    settings = validate({})
    path = DesignatedPath([[0.0, 0.0], [5.0, 0.0]], half_width_m=1.0)
    planner = make_planner("viapath", path, **planner_kwargs("viapath", settings.planner_values))
    assert dict(planner.settings) == dict(planner_class("viapath").options.validate({}))
    changed = validate({"planner.weights.k1": 0.3, "planner.speeds": [0.1, 0.3]})
    planner = make_planner("viapath", path, **planner_kwargs("viapath", changed.planner_values))
    assert planner.settings["k1"] == 0.3 and tuple(planner.settings["speeds"]) == (0.1, 0.3)
    assert settings.scanners[0].mount_x_m == pytest.approx(0.145) and settings.scanners[1].mount_x_m == pytest.approx(-0.145)
    assert settings.scanners[1].mount_yaw_rad == pytest.approx(math.pi)


def test_descriptions_carry_unit_and_bounds():
    option = next(o for o in all_options() if o.name == "scan_timeout_s")
    text = describe(option)
    assert "unit: s" in text and "range: [0.05, 10]" in text


@pytest.mark.parametrize("values, named", [
    ({"nominal_speed_mps": -0.2}, "nominal_speed_mps"),
    ({"nominal_speed_mps": float("nan")}, "nominal_speed_mps"),
    ({"max_accel_mps2": "fast"}, "max_accel_mps2"),
    ({"planner.horizon_s": -1.0}, "planner.horizon_s"),
    ({"planner.preferred_side": "up"}, "planner.preferred_side"),
    ({"planner.speeds": [0.1, -0.2]}, "planner.speeds"),
    ({"planner.speeds": [0.0]}, "planner.speeds"),
    ({"planner.weights.k1": -0.1}, "planner.weights.k1"),
    ({"planner.max_depth": 0}, "planner.max_depth"),
    ({"scan_geometry": "whatever"}, "scan_geometry"),
    ({"planner_name": "nope"}, "planner_name"),
    ({"nominal_speed_mps": 0.8, "max_speed_mps": 0.6}, "nominal_speed_mps"),
    ({"scanner_names": ["front", "front"]}, "scanner_names"),
    ({"not_a_parameter": 1.0}, "not_a_parameter"),
    ({"scanners.front.mount_yaw_rad": 7.0}, "scanners.front.mount_yaw_rad"),
    ({"autostart": "yes"}, "autostart"),
    ({"executor": "multi-threaded"}, "executor"),
])
def test_a_bad_value_is_refused_with_its_name(values, named):
    with pytest.raises(ParameterError) as error:
        validate(values)
    assert f"parameter {named}" in str(error.value)


def test_an_integer_is_accepted_for_a_number_and_converted():
    settings = validate({"half_width_m": 2, "planner.max_depth": 2.0})
    assert settings.half_width_m == 2.0 and isinstance(settings.half_width_m, float)
    assert settings.planner_values["max_depth"] == 2 and isinstance(settings.planner_values["max_depth"], int)
    with pytest.raises(ParameterError, match="planner.max_depth: expected an integer"):
        validate({"planner.max_depth": 2.5})


def test_params_file_round_trip_and_unknown_names(tmp_path):
    example = tmp_path / "robot.yaml"
    write_example_params(example)
    values = read_params_file(example)
    assert validate(values).values == validate({}).values
    bad = tmp_path / "bad.yaml"
    bad.write_text("viapath:\n  ros__parameters:\n    planner:\n      horizon_s: 5.0\n      horizn_s: 3.0\n")
    with pytest.raises(ParameterError, match="parameter planner.horizn_s: unknown"):
        validate(read_params_file(bad))
    nested = tmp_path / "nested.yaml"
    nested.write_text("/**:\n  ros__parameters:\n    planner:\n      weights: {k1: 0.2}\n")
    assert validate(read_params_file(nested)).planner_values["weights.k1"] == 0.2
    with pytest.raises(ParameterError, match="no section for node"):
        other = tmp_path / "other.yaml"
        other.write_text("someone_else:\n  ros__parameters: {a: 1}\n")
        read_params_file(other)


def test_the_shipped_example_params_file_is_valid():
    from pathlib import Path

    example = Path(__file__).resolve().parents[2] / "docs" / "ros2_params.yaml"
    assert example.is_file()
    settings = validate(read_params_file(example))
    assert settings.scan_timeout_s == 0.3 and settings.odom_timeout_s == 0.5
