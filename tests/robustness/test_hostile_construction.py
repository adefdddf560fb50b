"""Hostile input, second round: planners are built only from a description a robot can have, an
implausibly large obstacle is never shrunk, and no option inside its bounds makes a cycle unbounded.

On main a NaN robot radius switched off the last brake (the robot drove at 0.2 m/s into an
obstacle 3 cm ahead), an obstacle radius above 10 m was cut to 10 m (every planner drove into its
edge), a zero nominal speed raised ZeroDivisionError, accelerations of 0 or 1e-9 were accepted
(one shielded plan() then took seconds) and rollout_s=1e9 or rollout_dt_s=1e-9 ended in MemoryError."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.robustness._helpers import LIMITS, corridor, fresh, one_obstacle, planners, robot
from viapath.limits import LIMIT_BOUNDS
from viapath.observation import MotionLimits, Observation
from viapath.options import MAX_STEPS_PER_ROLLOUT, OptionError
from viapath.planning import make_planner, planner_class

_CASES = settings(max_examples=30, deadline=None, database=None, suppress_health_check=list(HealthCheck))
_BAD_NUMBERS = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -0.0, 1e-9, 1e308, "fast", None]),
    st.floats(max_value=0.0, allow_nan=False),
    st.floats(min_value=1e4, allow_infinity=False),
)


@_CASES
@given(
    name=st.sampled_from(planners()),
    radius=_BAD_NUMBERS.filter(lambda r: not (isinstance(r, float) and 0.0 < r <= 10.0)),
)
def test_a_bad_robot_radius_is_refused_naming_the_field(name, radius):
    with pytest.raises(OptionError, match="robot_radius_m: expected a finite number"):
        make_planner(name, corridor(), nominal_speed_mps=0.2, limits=LIMITS, robot_radius_m=radius)


@_CASES
@given(name=st.sampled_from(planners()), speed=_BAD_NUMBERS)
def test_a_bad_nominal_speed_is_refused_naming_the_field(name, speed):
    with pytest.raises(OptionError, match="nominal_speed_mps: expected a finite number"):
        make_planner(name, corridor(), nominal_speed_mps=speed, limits=LIMITS, robot_radius_m=0.25)


@_CASES
@given(
    name=st.sampled_from(planners()),
    field=st.sampled_from(sorted(LIMIT_BOUNDS)),
    value=st.one_of(_BAD_NUMBERS, st.floats(0.0, 0.0099)),
)
def test_bad_motion_limits_are_refused_naming_the_field(name, field, value):
    limits = MotionLimits(**{**LIMITS.__dict__, field: value})
    with pytest.raises(OptionError, match=f"limits.{field}: expected a finite number"):
        make_planner(name, corridor(), nominal_speed_mps=0.2, limits=limits, robot_radius_m=0.25)


@pytest.mark.parametrize("name", planners())
def test_a_radius_made_nan_after_construction_stops_the_robot(name):
    planner = fresh(name)
    planner.robot_radius_m = math.nan  # max(nan, r) is nan: no brake would fire
    decision = planner.plan(Observation(0.0, robot(speed=0.2), one_obstacle((0.53, 0.0))))
    assert decision.command.speed_mps == 0.0 and decision.plan.status == "guard-stop"


@_CASES
@given(
    name=st.sampled_from(planners()), radius=st.floats(10.001, 1e5), gap=st.floats(0.01, 0.5), side=st.floats(-0.5, 0.5)
)
def test_an_implausibly_large_obstacle_is_never_shrunk(name, radius, gap, side):
    """Just ahead of the robot, its edge ``gap`` away: the robot stops and the plan says why."""
    planner = fresh(name)
    centre = (0.25 + gap + radius, side)
    decision = planner.plan(Observation(0.0, robot(speed=0.2), one_obstacle(centre, radius=radius)))
    assert decision.command.speed_mps == 0.0
    assert decision.plan.status == "guard-stop"
    assert any("radii_m[0]" in reason for reason in decision.plan.extras["guard"])


def _numeric(option) -> bool:
    return option.kind in (int, float, tuple)


@pytest.mark.parametrize("name", planners())
def test_every_numeric_option_is_bounded(name):
    """The class, not the examples: a new option without a maximum (or a step without a lower bound
    above 0) fails here."""
    for option in planner_class(name).options:
        if not _numeric(option):
            continue
        assert option.maximum is not None, f"{name}: {option.name} has no maximum"
        if option.name.endswith("dt_s") or "spacing" in option.name:
            assert option.minimum is not None and option.minimum >= 0.001, f"{name}: {option.name} step unbounded below"


@_CASES
@given(name=st.sampled_from(planners()), data=st.data())
def test_every_duration_over_its_step_is_at_most_the_cap(name, data):
    options = planner_class(name).options
    for duration, step in options.steps:
        a, b = options[duration], options[step]
        values = {
            duration: data.draw(st.floats(max(a.minimum, 1e-3), a.maximum)),
            step: data.draw(st.floats(b.minimum, b.maximum)),
        }
        if values[duration] / values[step] > MAX_STEPS_PER_ROLLOUT:
            with pytest.raises(OptionError, match=f"planner.{duration}: "):
                options.validate(values, where="planner")
        else:
            options.validate(values, where="planner")


@pytest.mark.parametrize(
    "values",
    [
        {"rollout_s": 1e9},
        {"rollout_dt_s": 1e-9},
        {"escape_s": 1e9},
        {"escape_dt_s": 1e-9},
        {"rollout_s": 30.0, "rollout_dt_s": 0.01},
        {"escape_s": 25.0, "escape_dt_s": 0.012},
        {"corridor_check_spacing_m": 1e-9},
        {"speeds": [0.1] * 1000},
        {"slow_times_s": [1e9]},
    ],
)
def test_viapath_options_that_made_a_cycle_unbounded_are_refused(values):
    with pytest.raises(OptionError):
        make_planner("viapath", corridor(), nominal_speed_mps=0.2, limits=LIMITS, robot_radius_m=0.25, **values)


def test_the_largest_accepted_roll_outs_plan_a_cycle():
    from viapath.safety.shielded import shielded

    largest = dict(rollout_s=20.0, rollout_dt_s=0.01, escape_s=20.0, escape_dt_s=0.01, max_rollouts=1000)
    inner = make_planner("viapath", corridor(), nominal_speed_mps=0.2, limits=LIMITS, robot_radius_m=0.25, **largest)
    planner = shielded(inner, True, 0.1)
    decision = planner.plan(Observation(0.0, robot(speed=0.2), one_obstacle((0.9, 0.0), velocity=(-0.5, 0.0))))
    assert np.isfinite([decision.command.speed_mps, decision.command.turn_rate_radps]).all()


_BAD_IDS = st.one_of(
    st.text(min_size=1, max_size=5),
    st.none(),
    st.complex_numbers(allow_nan=False),
    st.floats(min_value=2.0**64, allow_infinity=True),
    st.just(math.nan),
    st.binary(min_size=1, max_size=3),
    st.integers(min_value=2**64, max_value=2**200),
)


@_CASES
@given(bad=_BAD_IDS, position=st.integers(0, 2))
def test_ids_that_are_not_integers_are_the_documented_error(bad, position):
    from viapath.observation import ObservationError, Obstacles

    ids = [0, 1, 2]
    ids[position] = bad
    with pytest.raises(ObservationError, match=r"obstacles\.ids"):
        Obstacles(np.zeros((3, 2)) + [[1, 0]], np.zeros((3, 2)), np.full(3, 0.3), ids=ids)


@_CASES
@given(name=st.sampled_from(planners()), ident=st.integers(-(2**63), 2**63 - 1))
def test_any_int64_id_plans(name, ident):
    """Perception hands int64 ids as they are (Obstacles.of_fresh_arrays); navground takes 32-bit ones."""
    from viapath.observation import Obstacles

    obstacles = Obstacles.of_fresh_arrays(
        np.array([[1.5, 0.3]]),
        np.zeros((1, 2)),
        np.array([0.3]),
        np.zeros(1),
        np.zeros(1),
        np.array([ident], dtype=np.int64),
    )
    decision = fresh(name).plan(Observation(0.0, robot(), obstacles))
    assert np.isfinite([decision.command.speed_mps, decision.command.turn_rate_radps]).all()


@settings(max_examples=12, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(name=st.sampled_from([n for n in planners() if n != "viapath"]), data=st.data())
def test_option_values_inside_their_bounds_plan_a_cycle(name, data):
    _plan_with_options(name, data)


@settings(max_examples=12, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_viapath_option_values_inside_their_bounds_plan_a_cycle(data):
    _plan_with_options("viapath", data)


def _plan_with_options(name, data):
    from tests.robustness._hostile import option_values
    from viapath.observation import Obstacles

    values = data.draw(option_values(planner_class(name).options))
    try:
        planner = make_planner(
            name, corridor(), nominal_speed_mps=0.2, limits=LIMITS, robot_radius_m=0.25, options=values
        )
    except OptionError as error:
        assert "steps; at most" in str(error), error  # only the cross-check may refuse values inside bounds
        return
    obstacles = Obstacles(
        np.array([[1.2, 0.1], [2.0, -0.4], [0.8, 0.9]]),
        np.array([[-0.4, 0.0], [0.0, 0.3], [0.1, -0.2]]),
        np.full(3, 0.3),
    )
    for t in range(3):
        decision = planner.plan(Observation(0.1 * t, robot(x=0.02 * t), obstacles))
        assert np.isfinite([decision.command.speed_mps, decision.command.turn_rate_radps]).all()
