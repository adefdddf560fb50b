"""Parameters of the ROS 2 node: generated from the planner's option schema, bad values refused by name.

No rclpy needed: these check :mod:`viapath.ros2.settings` and :mod:`viapath.ros2.options` directly.
"""

from __future__ import annotations

import math

import pytest

from viapath.planning import make_planner, planner_class
from viapath.ros2.options import planner_kwargs
from viapath.ros2.settings import (
    ParameterError,
    all_options,
    describe,
    read_params_file,
    validate,
    write_example_params,
)


def test_every_planner_option_becomes_a_parameter_with_its_default():
    schema = list(planner_class("viapath").options)
    params = {o.name: o for o in all_options("viapath")}
    for option in schema:
        param = params[f"planner.{option.path}"]
        assert param.default == option.default and param.unit == option.unit
        assert (param.minimum, param.maximum, param.choices) == (option.minimum, option.maximum, option.choices)
    assert {
        "planner.horizon_s",
        "planner.weights.k1",
        "planner.speeds",
        "planner_name",
        "scanners.front.mount_x_m",
    } <= set(params)
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
    assert settings.scanners[0].mount_x_m == pytest.approx(0.145) and settings.scanners[1].mount_x_m == pytest.approx(
        -0.145
    )
    assert settings.scanners[1].mount_yaw_rad == pytest.approx(math.pi)


def test_descriptions_carry_unit_and_bounds():
    option = next(o for o in all_options() if o.name == "scan_timeout_s")
    text = describe(option)
    assert "unit: s" in text and "range: [0.05, 10]" in text


@pytest.mark.parametrize(
    "values, named",
    [
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
    ],
)
def test_a_bad_value_is_refused_with_its_name(values, named):
    with pytest.raises(ParameterError) as error:
        validate(values)
    assert f"parameter {named}" in str(error.value)


def test_an_integer_is_accepted_for_a_number_and_converted():
    settings = validate({"half_width_m": 2, "planner.max_depth": 2.0})
    assert settings.half_width_m == 2.0 and isinstance(settings.half_width_m, float)
    assert settings.planner_values["max_depth"] == 2 and isinstance(settings.planner_values["max_depth"], int)
    with pytest.raises(ParameterError, match=r"planner\.max_depth: expected an integer"):
        validate({"planner.max_depth": 2.5})


def test_params_file_round_trip_and_unknown_names(tmp_path):
    example = tmp_path / "robot.yaml"
    write_example_params(example)
    values = read_params_file(example)
    assert validate(values).values == validate({}).values
    bad = tmp_path / "bad.yaml"
    bad.write_text("viapath:\n  ros__parameters:\n    planner:\n      horizon_s: 5.0\n      horizn_s: 3.0\n")
    with pytest.raises(ParameterError, match=r"parameter planner\.horizn_s: unknown"):
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


def test_the_shipped_example_params_file_is_what_the_params_command_writes(tmp_path):
    # "Defaults" in the docs must be the defaults: a new or changed option regenerates the file
    # (cd docs && viapath ros2 params ros2_params.yaml).
    from pathlib import Path

    from viapath.ros2.settings import write_example_params

    shipped = Path(__file__).resolve().parents[2] / "docs" / "ros2_params.yaml"
    written = tmp_path / "ros2_params.yaml"
    write_example_params(written, "viapath")
    assert written.read_text() == shipped.read_text()


def test_every_mistake_is_reported_not_only_the_first(tmp_path):
    path = tmp_path / "two.yaml"
    path.write_text(
        "viapath:\n  ros__parameters:\n    nominal_speed_mps: -1.0\n    odom_topc: x\n"
        "    planner:\n      rollout_s: 1.0e9\n      weights: {k1: -2}\n"
    )
    with pytest.raises(ParameterError) as caught:
        validate(read_params_file(path))
    named = [line.split(":")[0] for line in caught.value.errors]
    assert sorted(named) == sorted(
        [
            "parameter nominal_speed_mps",
            "parameter odom_topc",
            "parameter planner.rollout_s",
            "parameter planner.weights.k1",
        ]
    ), caught.value.errors
    assert str(caught.value).count("\n") == 3


@pytest.mark.parametrize(
    "values, named",
    [
        ({"planner.rollout_s": 1e9}, "planner.rollout_s"),
        ({"planner.rollout_dt_s": 1e-9}, "planner.rollout_dt_s"),
        ({"planner.escape_s": 1e9}, "planner.escape_s"),
        ({"planner.escape_dt_s": 1e-9}, "planner.escape_dt_s"),
        ({"planner.rollout_s": 30.0, "planner.rollout_dt_s": 0.01}, "planner.rollout_s"),  # 3000 steps
        ({"planner.escape_s": 25.0, "planner.escape_dt_s": 0.01}, "planner.escape_s"),
    ],
)
def test_roll_outs_that_would_exhaust_memory_are_refused(values, named):
    with pytest.raises(ParameterError, match=f"parameter {named}:"):
        validate(values)
    validate({"planner.rollout_s": 20.0, "planner.rollout_dt_s": 0.01})  # 2000 steps: the most allowed


from hypothesis import given  # noqa: E402
from hypothesis import settings as hsettings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

NUMERIC = [
    o for o in all_options() if isinstance(o.default, float) and (o.minimum is not None or o.maximum is not None)
]


@hsettings(max_examples=40, deadline=None, derandomize=True)
@given(
    chosen=st.lists(st.sampled_from(NUMERIC), min_size=1, max_size=6, unique_by=lambda o: o.name),
    how=st.sampled_from(["below", "above", "text", "nan"]),
)
def test_generated_parameter_sets_name_every_bad_value(chosen, how):
    values = {}
    for o in chosen:
        if how == "below" and o.minimum is not None:
            values[o.name] = o.minimum - 1.0
        elif how == "above" and o.maximum is not None:
            values[o.name] = o.maximum + 1.0
        elif how == "text":
            values[o.name] = "fast"
        elif how == "nan":
            values[o.name] = float("nan")
    if not values:
        return
    with pytest.raises(ParameterError) as caught:
        validate(values)
    for name in values:
        assert any(line.startswith(f"parameter {name}:") for line in caught.value.errors), (name, caught.value.errors)
