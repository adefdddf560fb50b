"""Eq. 1's terms (viapath.planning.viapath.critics), each one compiled function the choice calls, against a plain numpy
specification of each term written here, and against the paper's arithmetic worked by hand on three candidates.

Candidates of the hand-worked cases (robot heading 0 rad, nominal 0.2 m/s):
  0: straight, 5 m at 0.2 m/s (way: STRAIGHT);
  1: round obstacle 7 on the left, 5.5 m at 0.3 m/s, first leg at 45°;
  2: waits 2 s (slow speed 0) then 5 m at 0.4 m/s, first leg at -90°, round obstacle 7 on the right.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from viapath.geometry import LEFT, RIGHT, angles_of, wrap_angle
from viapath.jit import compiled
from viapath.planning.viapath.candidates import CORNER, SLOW, STRAIGHT, Candidates, Choice, Way
from viapath.planning.viapath.critics import (
    PAPER_CRITICS,
    Context,
    Critic,
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


# The specification: each term of E as plain numpy over all candidates, by its definition (paper §3 Eq. 1, and the
# terms beyond the paper: critics.py's module docstring).


def distance_spec(critic: Distance, c: Candidates, context: Context) -> np.ndarray:
    return critic.weight * c.total_length_m


def time_spec(critic: Time, c: Candidates, context: Context) -> np.ndarray:
    return critic.weight * c.travel_time_s


def speed_spec(critic: SpeedError, c: Candidates, context: Context) -> np.ndarray:
    nominal = context.nominal_speed_mps
    error = (c.slow_s * np.abs(c.slow_speed_mps - nominal) + c.driven_s * np.abs(c.speed_mps - nominal)) / (
        c.travel_time_s
    )
    standing_s = np.where(c.slow_speed_mps <= 0.0, c.slow_s, 0.0)
    return critic.weight * error + critic.standing_per_s * standing_s


def heading_spec(critic: Heading, c: Candidates, context: Context) -> np.ndarray:
    theta = np.abs(wrap_angle(angles_of(c.first_direction) - context.heading_rad))
    return critic.weight * (np.degrees(theta) if critic.degrees else theta)


def side_spec(critic: SidePreference, c: Candidates, context: Context) -> np.ndarray:
    side = c.ways[:, 1]
    return critic.weight * ((side != 0) & (side != critic.preferred))


def hysteresis_spec(critic: Hysteresis, c: Candidates, context: Context) -> np.ndarray:
    previous = context.previous
    if previous is None:
        return np.zeros(len(c))
    same_way = previous.way.same(c.ways)
    same_speed = c.speed_mmps == previous.speed_mmps
    return -(critic.weight * (same_way + 0.5 * (same_way & same_speed)))


SPEC = {
    Distance: distance_spec,
    Time: time_spec,
    SpeedError: speed_spec,
    Heading: heading_spec,
    SidePreference: side_spec,
    Hysteresis: hysteresis_spec,
}


def spec_of(critic: Critic, c: Candidates, context: Context) -> np.ndarray:
    return SPEC[type(critic)](critic, c, context)  # type: ignore[operator]


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
    # from a heading of 170°, the first leg at -90° is a turn of 100° (the short way round, across ±180°)
    turned = Context(heading_rad=math.radians(170.0), nominal_speed_mps=NOMINAL, previous=None)
    np.testing.assert_allclose(Heading(1.0, degrees=True).score(candidates, turned), [170.0, 125.0, 100.0])


def test_side_preference_charges_only_the_other_side(candidates):
    np.testing.assert_array_equal(SidePreference(0.05, LEFT).score(candidates, _context()), [0.0, 0.0, 0.05])
    np.testing.assert_array_equal(SidePreference(0.05, RIGHT).score(candidates, _context()), [0.0, 0.05, 0.0])


def test_hysteresis_rewards_last_cycles_way_and_half_again_its_speed(candidates):
    assert not Hysteresis(0.1).score(candidates, _context()).any()  # no previous cycle: no bonus
    same_way_other_speed = Choice(Way(7, LEFT, -1), 250)
    np.testing.assert_allclose(Hysteresis(0.1).score(candidates, _context(same_way_other_speed)), [0.0, -0.1, 0.0])
    same_way_same_speed = Choice(Way(7, LEFT, -1), 300)
    np.testing.assert_allclose(Hysteresis(0.1).score(candidates, _context(same_way_same_speed)), [0.0, -0.15, 0.0])
    other_root = Choice(Way(7, LEFT, 3), 300)  # the same obstacle and side, the other root: another way round
    assert not Hysteresis(0.1).score(candidates, _context(other_root)).any()


def _random_candidates(rng: np.random.Generator, count: int) -> Candidates:
    """Candidates as the tree makes them: a first slow or waiting part for some (standing for some of those), the
    ways round drawn from few values so that some repeat."""
    slow = rng.random(count) < 0.4
    slow_speed = np.where(rng.random(count) < 0.5, 0.0, rng.uniform(0.05, 0.3, count)) * slow
    angle = rng.uniform(-math.pi, math.pi, count)
    obstacle = rng.choice([STRAIGHT, SLOW, CORNER, 0, 1, 2, 17], count)
    return Candidates(
        nodes={"parent": np.full(count, -1), "position": np.zeros((count, 2))},
        leaves=np.arange(count),
        total_length_m=rng.uniform(0.5, 20.0, count),
        speed_mps=rng.choice([0.1, 0.2, 0.3, 0.4, 0.5, 0.6], count) + rng.choice([0.0, 1e-4], count),
        slow_s=np.where(slow, rng.uniform(0.5, 6.0, count), 0.0),
        slow_speed_mps=slow_speed,
        first_direction=np.column_stack([np.cos(angle), np.sin(angle)]),
        ways=np.column_stack([obstacle, rng.integers(-1, 2, count), rng.integers(-1, 2, count)]),
        subgoal=np.array([5.0, 0.0]),
    )


@pytest.mark.parametrize("seed", range(40))
def test_each_compiled_term_is_its_specification_on_random_candidates(seed):
    """Every term's compiled function (by its critic's ``score``) against the numpy specification above, on random
    candidates, weights and contexts, degrees and radians, each side preferred, with and without a previous
    cycle (one of the candidates' own ways and speeds, so that the bonus is earned)."""
    rng = np.random.default_rng(seed)
    c = _random_candidates(rng, int(rng.integers(1, 60)))
    k = int(rng.integers(len(c)))
    previous = None if seed % 3 == 0 else Choice(Way(*map(int, c.ways[k])), int(c.speed_mmps[k]))
    context = Context(float(rng.uniform(-4.0, 4.0)), float(rng.uniform(0.1, 0.6)), previous)
    critics = (
        Distance(rng.uniform(0.0, 2.0)),
        Time(rng.uniform(0.0, 0.1)),
        SpeedError(rng.uniform(0.0, 1.0), standing_per_s=rng.choice([0.0, rng.uniform(0.0, 0.01)])),
        Heading(rng.uniform(0.0, 1.0), degrees=bool(seed % 2)),
        SidePreference(rng.uniform(0.0, 0.1), LEFT if seed % 4 < 2 else RIGHT),
        Hysteresis(rng.uniform(0.0, 0.2)),
    )
    for critic in critics:
        np.testing.assert_array_equal(critic.score(c, context), spec_of(critic, c, context), err_msg=critic.name)
    if previous is not None:
        assert critics[-1].score(c, context)[k] == pytest.approx(-1.5 * critics[-1].weight)


def test_the_planners_costs_are_the_terms_specification_summed_in_the_listed_order():
    """The compiled choice sums the paper's terms itself: on a cycle of the paper's side case, every candidate's E in
    the plan is the specification's terms summed in critics_for's order, and the chosen candidate's breakdown is
    each term's specification."""
    from tests.planning.test_slow_candidates import _side_case

    planner, checks, _, _, candidates, observation = _side_case(0.2, -0.5)
    config = VIAPATH_OPTIONS.validate({}, where="test")
    assert [c.name for c in critics_for(config)] == ["distance", "time", "speed", "heading", "side", "hysteresis"]
    assert tuple(map(type, planner.critics)) == PAPER_CRITICS
    context = Context(checks.heading_rad, planner.nominal_speed_mps, None)
    terms = [spec_of(critic, candidates, context) for critic in planner.critics]
    assert len(candidates) > 5 and all(np.any(values != 0.0) for values in terms[:4])
    plan = planner.plan(observation).plan  # the same cycle again, in the one compiled call
    total = terms[0] + terms[1]
    for values in terms[2:]:
        total = total + values
    np.testing.assert_allclose(plan.candidate_costs, total, rtol=1e-12, atol=1e-12)
    chosen = plan.extras["cost_terms"]["chosen"]
    for critic, values in zip(planner.critics, terms):
        assert chosen[critic.name] == pytest.approx(float(values[plan.chosen]), rel=1e-12, abs=1e-12)
    assert chosen["total"] == pytest.approx(float(total[plan.chosen]), rel=1e-12, abs=1e-12)


# The term that docs/howto/add-cost-term.md adds, as it writes it.
@compiled
def waiting_term(weight: float, slow_s: np.ndarray, out: np.ndarray) -> np.ndarray:
    """k5·T_slow: each second the candidate first slows down or waits."""
    for k in range(out.shape[0]):
        out[k] = weight * slow_s[k]
    return out


@dataclass(frozen=True)
class Waiting(Critic):
    """:func:`waiting_term` as a critic."""

    weight: float
    name = "waiting"

    def score(self, candidates: Candidates, context: Context) -> np.ndarray:
        return waiting_term(self.weight, candidates.slow_s, np.empty(len(candidates)))


def test_a_term_added_after_the_papers_adds_its_share_to_every_candidates_E():
    """The how-to's term, appended to the critics: every candidate's E is the paper's terms, then its term (by
    hand: 0.5 per second of slowing down or waiting), and the chosen candidate's breakdown has it by name."""
    from tests.planning.test_slow_candidates import _side_case

    planner, checks, _, _, candidates, observation = _side_case(0.2, -0.5)
    context = Context(checks.heading_rad, planner.nominal_speed_mps, None)
    terms = [spec_of(critic, candidates, context) for critic in planner.critics]
    paper = planner.plan(observation).plan.candidate_costs
    planner.reset()
    planner.critics = (*planner.critics, Waiting(0.5))
    plan = planner.plan(observation).plan
    waiting = 0.5 * candidates.slow_s
    assert np.count_nonzero(waiting) >= 2
    np.testing.assert_array_equal(plan.candidate_costs, paper + waiting)
    chosen = plan.extras["cost_terms"]["chosen"]
    assert list(chosen) == [*(critic.name for critic in planner.critics), "total"]
    assert chosen["waiting"] == waiting[plan.chosen]
    assert chosen["total"] == pytest.approx(sum(float(values[plan.chosen]) for values in [*terms, waiting]), rel=1e-12)
