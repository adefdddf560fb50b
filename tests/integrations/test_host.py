"""What the simulators' viapath behaviours share (viapath.integrations.host), without either simulator."""

from __future__ import annotations

import math

import numpy as np
import pytest

from viapath.integrations.host import (
    Driver,
    behaviour_options,
    bounded_limits,
    read_options,
    read_waypoints,
    static_layer,
)
from viapath.limits import LIMIT_BOUNDS
from viapath.observation import Observation, Obstacles, RobotState
from viapath.options import OptionError
from viapath.planning import planner_options
from viapath.presets import preset_values
from viapath.safety import ShieldedPlanner
from viapath.static import point_segment_distances

SCHEMA = behaviour_options()


def _driver(**options) -> Driver:
    driver = Driver(read_options(SCHEMA, options, where="behavior"))
    driver.start(
        np.array([[0.0, 0.0], [5.0, 0.0]]),
        nominal_speed_mps=0.2,
        limits=bounded_limits(0.6, 0.8, 2.0, 6.0),
        robot_radius_m=0.25,
        dt_s=0.1,
        goal_tolerance_m=0.08,
    )
    return driver


def test_the_schema_is_the_planners_own_plus_the_hosts():
    assert set(planner_options("viapath").names) < set(SCHEMA.names)
    for option in planner_options("viapath"):
        assert SCHEMA[option.name] == option


def test_the_shield_is_on_unless_asked_off():
    assert isinstance(_driver().planner, ShieldedPlanner)
    assert not isinstance(_driver(shield=False).planner, ShieldedPlanner)


def test_a_preset_applies_first_and_options_given_beside_it_win():
    paper = preset_values("paper")
    settings = read_options(SCHEMA, {"preset": "paper", "weights": {"k3": 0.5}}, where="behavior")
    assert settings["k2"] == paper["k2"] != SCHEMA["k2"].default
    assert settings["k3"] == 0.5
    flat = read_options(SCHEMA, {"preset": "paper", "k2": 0.02}, where="behavior")
    assert flat["k2"] == 0.02


def test_bad_options_and_paths_are_refused_naming_the_field():
    with pytest.raises(OptionError, match=r"behavior\.weights\.k1: Input should be greater than or equal to 0"):
        read_options(SCHEMA, {"weights": {"k1": -1}}, where="behavior")
    with pytest.raises(OptionError, match=r"behavior\.nope: unknown option 'nope'"):
        read_options(SCHEMA, {"nope": 1}, where="behavior")
    for bad in ([[0, 0]], [[0, 0], [0, 0]], [[0, 0], [1, float("nan")]], "a path", [[0, 0, 0], [1, 1, 1]]):
        with pytest.raises(OptionError, match=r"behavior\.path: "):
            read_waypoints(bad, "behavior.path")
    assert read_waypoints(None, "p") is None and read_waypoints([], "p") is None


def test_unbounded_limits_become_the_largest_the_schema_allows():
    limits = bounded_limits(0.6, math.inf, 2.0, math.inf)
    assert limits.max_accel_mps2 == LIMIT_BOUNDS["max_accel_mps2"][1]
    assert limits.max_turn_accel_radps2 == LIMIT_BOUNDS["max_turn_accel_radps2"][1]
    assert (limits.max_speed_mps, limits.max_turn_rate_radps) == (0.6, 2.0)


def test_the_static_layer_is_at_each_shapes_true_distance():
    """Brute force: distances from random points to densely sampled outlines of the same shapes."""
    square = np.array([[2.0, -0.5], [3.0, -0.5], [3.0, 0.5], [2.0, 0.5]])
    line = np.array([[-1.0, 1.5], [6.0, 1.5], [6.0, 3.0]])
    circle = (np.array([4.0, -1.0]), 0.4)
    loose = np.array([[[0.0, -2.0], [1.0, -2.5]]])
    layer = static_layer([square], [line], [circle], [loose])
    assert len(np.unique(layer.shape_ids)) == 4
    t = np.linspace(0, 1, 2001)[:, None]
    outline = np.concatenate(
        [a + t * (b - a) for a, b in zip(square, np.roll(square, -1, axis=0))]
        + [a + t * (b - a) for a, b in zip(line[:-1], line[1:])]
        + [circle[0] + circle[1] * np.column_stack([np.cos(2 * np.pi * t[:, 0]), np.sin(2 * np.pi * t[:, 0])])]
        + [loose[0, 0] + t * (loose[0, 1] - loose[0, 0])]
    )
    points = np.random.default_rng(0).uniform([-2, -4], [7, 4], size=(300, 2))
    ours = (point_segment_distances(points, layer.segments) - layer.padding_m).min(axis=1)
    brute = np.hypot(*(points[:, None, :] - outline[None]).transpose(2, 0, 1)).min(axis=1)
    outside_circle = np.hypot(*(points - circle[0]).T) > circle[1]
    assert np.allclose(ours[outside_circle], brute[outside_circle], atol=5e-3)


def test_a_person_ahead_makes_the_command_differ_from_an_empty_scene():
    """The driver hands the observation to viapath: a person crossing ahead changes the command."""
    robot = RobotState(position=np.zeros(2), heading_rad=0.0, speed_mps=0.2)
    free = _driver().command(Observation(0.0, robot))
    person = Obstacles(positions=[[1.0, -0.8]], velocities=[[0.0, 0.4]], radii_m=[0.25])
    crossing = _driver().command(Observation(0.0, robot, person))
    assert free.speed_mps == pytest.approx(0.2, abs=0.05)
    assert (crossing.speed_mps, crossing.turn_rate_radps) != pytest.approx((free.speed_mps, free.turn_rate_radps))
    assert Driver(read_options(SCHEMA, {}, where="b")).command(Observation(0.0, robot)).speed_mps == 0.0  # not started
