"""Each critic of Eq. 1 on its own, against the paper's arithmetic worked by hand on three candidates.

Candidates (robot heading 0 rad, nominal 0.2 m/s):
  0: straight, 5 m at 0.2 m/s (way: STRAIGHT);
  1: round obstacle 7 on the left, 5.5 m at 0.3 m/s, first leg at 45°;
  2: waits 2 s (slow speed 0) then 5 m at 0.4 m/s, first leg at -90°, round obstacle 7 on the right.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from viapath.geometry import LEFT, RIGHT
from viapath.planning.viapath.candidates import STRAIGHT, Candidates, Choice, Way
from viapath.planning.viapath.critics import (
    Context,
    Distance,
    Heading,
    Hysteresis,
    SidePreference,
    SpeedError,
    Time,
    critics_for,
)
from viapath.planning.viapath.options import VIAPATH_OPTIONS

NOMINAL = 0.2


@pytest.fixture
def candidates() -> Candidates:
    root = -1
    return Candidates(
        nodes={"parent": np.full(3, -1), "position": np.zeros((3, 2))},
        leaves=np.arange(3),
        total_length_m=np.array([5.0, 5.5, 5.0]),
        speed_mps=np.array([0.2, 0.3, 0.4]),
        slow_s=np.array([0.0, 0.0, 2.0]),
        slow_speed_mps=np.array([0.0, 0.0, 0.0]),
        first_direction=np.array([[1.0, 0.0], [math.sqrt(0.5), math.sqrt(0.5)], [0.0, -1.0]]),
        ways=np.array([[STRAIGHT, 0, root], [7, LEFT, root], [7, RIGHT, root]]),
        subgoal=np.array([5.0, 0.0]),
    )


def _context(previous: Choice | None = None) -> Context:
    return Context(heading_rad=0.0, nominal_speed_mps=NOMINAL, previous=previous)


def test_distance_is_k1_times_the_length(candidates):
    np.testing.assert_allclose(Distance(0.1).score(candidates, _context()), [0.5, 0.55, 0.5])


def test_time_is_k2_times_the_travel_time_waiting_included(candidates):
    # 5 / 0.2 = 25 s; 5.5 / 0.3 = 18.33 s; 2 s of waiting + 5 / 0.4 = 14.5 s
    np.testing.assert_allclose(Time(0.01).score(candidates, _context()), [0.25, 0.01 * 5.5 / 0.3, 0.145])


def test_speed_error_is_time_weighted_over_a_wait(candidates):
    # 0 | 0.1 | (2 s · |0 - 0.2| + 12.5 s · |0.4 - 0.2|) / 14.5 s
    expected = [0.0, 0.08 * 0.1, 0.08 * (2 * 0.2 + 12.5 * 0.2) / 14.5]
    np.testing.assert_allclose(SpeedError(0.08).score(candidates, _context()), expected)


def test_standing_costs_per_second_and_breaks_the_tie_with_creeping_at_half_speed():
    # Eq. 1 cannot tell standing 2 s then 0.2 m/s from creeping 4 s at 0.1 m/s then 0.2 m/s: both reach the
    # subgoal 5 m away in 25 + 2 s with 0.4 m·s/s of speed error. The standing second costs.
    tie = Candidates(
        nodes={"parent": np.full(2, -1), "position": np.zeros((2, 2))},
        leaves=np.arange(2),
        total_length_m=np.array([5.0, 5.0]),
        speed_mps=np.array([0.2, 0.2]),
        slow_s=np.array([2.0, 4.0]),
        slow_speed_mps=np.array([0.0, 0.1]),
        first_direction=np.array([[1.0, 0.0], [1.0, 0.0]]),
        ways=np.array([[STRAIGHT, 0, -1], [STRAIGHT, 0, -1]]),
        subgoal=np.array([5.0, 0.0]),
    )
    np.testing.assert_allclose(Time(0.01).score(tie, _context()), [0.27, 0.27])
    plain = SpeedError(0.08).score(tie, _context())
    np.testing.assert_allclose(plain, [0.08 * 0.4 / 27.0] * 2)
    np.testing.assert_allclose(SpeedError(0.08, standing_per_s=0.002).score(tie, _context()), plain + [0.004, 0.0])


def test_heading_is_k4_times_the_turn_onto_the_first_leg(candidates):
    np.testing.assert_allclose(Heading(0.3).score(candidates, _context()), [0.0, 0.3 * math.pi / 4, 0.3 * math.pi / 2])
    np.testing.assert_allclose(Heading(0.3, degrees=True).score(candidates, _context()), [0.0, 0.3 * 45, 0.3 * 90])


def test_side_preference_charges_only_the_other_side(candidates):
    np.testing.assert_array_equal(SidePreference(0.05, LEFT).score(candidates, _context()), [0.0, 0.0, 0.05])
    np.testing.assert_array_equal(SidePreference(0.05, RIGHT).score(candidates, _context()), [0.0, 0.05, 0.0])


def test_hysteresis_rewards_last_cycles_way_and_half_again_its_speed(candidates):
    assert not Hysteresis(0.1).score(candidates, _context()).any()  # no previous cycle: no bonus
    same_way_other_speed = Choice(Way(7, LEFT, -1), 250)
    np.testing.assert_allclose(Hysteresis(0.1).score(candidates, _context(same_way_other_speed)), [0.0, -0.1, 0.0])
    same_way_same_speed = Choice(Way(7, LEFT, -1), 300)
    np.testing.assert_allclose(Hysteresis(0.1).score(candidates, _context(same_way_same_speed)), [0.0, -0.15, 0.0])


def test_the_planners_costs_are_the_critics_summed_in_the_listed_order():
    """The compiled choice sums the paper's critics itself: on a cycle of the paper's side case, every candidate's E
    in the plan is the critics' own scores (above, by hand) summed in critics_for's order, and the chosen
    candidate's breakdown is each critic's score."""
    from tests.planning.test_slow_candidates import _side_case

    planner, checks, _, _, candidates, observation = _side_case(0.2, -0.5)
    config = VIAPATH_OPTIONS.validate({}, where="test")
    assert [c.name for c in critics_for(config)] == ["distance", "time", "speed", "heading", "side", "hysteresis"]
    context = Context(checks.heading_rad, planner.nominal_speed_mps, None)
    terms = [critic.score(candidates, context) for critic in planner.critics]
    plan = planner.plan(observation).plan  # the same cycle again, in the one compiled call
    np.testing.assert_allclose(plan.candidate_costs, sum(terms), rtol=1e-12, atol=1e-12)
    chosen = plan.extras["cost_terms"]["chosen"]
    for critic, values in zip(planner.critics, terms):
        assert chosen[critic.name] == pytest.approx(float(values[plan.chosen]), rel=1e-12, abs=1e-12)
    assert len(candidates) > 5
