"""The planner's compiled choice and its kernels against independent oracles.

Every cycle makes its choice in one compiled call (``compiled.choose``); recording the candidates' polylines or a
critic beyond the paper's changes nothing else of the plan. The leg-contact kernel is held to the numpy contact of
the baselines (:func:`viapath.geometry.legs_first_contact`), the corridor kernels to
:class:`viapath.path.DesignatedPath`, the roll-out check to its definition (tests/planning/test_planner_oracles.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.planning import make_planner
from viapath.planning.viapath import packing as compiled

PATHS = [
    DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0),
    DesignatedPath([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]], half_width_m=1.2),
    DesignatedPath([[0.0, 0.0], [2.5, 0.5], [5.0, -0.5], [8.0, 0.0]], half_width_m=1.5),
]


@st.composite
def cases(draw):
    path_index = draw(st.integers(0, len(PATHS) - 1))
    n = draw(st.integers(0, 12))
    floats = lambda lo, hi: st.floats(lo, hi, allow_nan=False, allow_infinity=False)
    seed = draw(st.integers(0, 2**31 - 1))
    rng = np.random.default_rng(seed)
    # The robot near the path, mostly heading along it; people mostly ahead of it (some behind, some
    # touching it: escapes), so that every kind of plan comes up.
    robot = (
        draw(floats(-0.5, 3.0)),
        draw(floats(-1.3, 1.3)),
        draw(floats(-0.8, 0.8)) * draw(st.sampled_from([1, 4])),
        draw(floats(0.0, 0.5)),
        draw(floats(-1.0, 1.0)),
    )
    distance = rng.uniform(draw(st.sampled_from([0.3, 0.8])), 6.0, n)
    bearing = rng.normal(0.0, draw(st.sampled_from([0.5, 3.0])), n)
    positions = np.array(robot[:2]) + np.stack([distance * np.cos(bearing), distance * np.sin(bearing)], 1)
    speed, direction = rng.uniform(0.0, 1.5, n), rng.uniform(-np.pi, np.pi, n)
    velocities = np.stack([speed * np.cos(direction), speed * np.sin(direction)], 1)
    uncertain = draw(st.booleans())
    sigma_p = rng.uniform(0.0, 0.05, n) if uncertain else None
    sigma_v = rng.uniform(0.0, 0.1, n) if uncertain else None
    shield = draw(st.booleans())
    step = rng.uniform(-0.05, 0.05, (n, 2))  # the second cycle: people moved a little, the robot too
    return path_index, robot, positions, velocities, rng.uniform(0.2, 0.35, n), sigma_p, sigma_v, shield, step


def _observations(case):
    _, robot, positions, velocities, radii, sigma_p, sigma_v, _, step = case
    x, y, heading, speed, turn = robot
    for cycle in range(2):
        obstacles = Obstacles(
            positions + cycle * (step + 0.1 * velocities),
            velocities,
            radii,
            position_sigma_m=sigma_p,
            velocity_sigma_mps=sigma_v,
        )
        state = RobotState(
            np.array([x + 0.02 * cycle * np.cos(heading), y + 0.02 * cycle * np.sin(heading)]), heading, speed, turn
        )
        yield Observation(0.1 * cycle, state, obstacles)


def test_kernels_match_reference_on_edge_cases():
    """The contact kernel against numpy where the cone is capped mid-leg, legs start inside a disc, the
    relative speed is zero and the cone outgrows the relative speed (a < 0)."""
    from viapath.geometry import legs_first_contact
    from viapath.planning.viapath import legs as leg_steps

    rng = np.random.default_rng(3)
    k, n = 400, 7
    starts = rng.uniform(-3, 3, (k, 2))
    starts[:5] = 0.0  # inside obstacle 0 at the start
    times = rng.uniform(0, 4, k)
    velocities = rng.uniform(-0.5, 0.5, (k, 2))
    velocities[5:10] = 0.0
    durations = rng.uniform(0, 8, k)
    positions = rng.uniform(-3, 3, (n, 2))
    positions[0] = 0.0
    obstacle_velocities = rng.uniform(-1, 1, (n, 2))
    obstacle_velocities[1] = 0.0  # with the resting legs: zero relative speed
    radii = rng.uniform(0.3, 0.8, n)
    growth = np.array([0.0, 0.1, 2.0, 0.05, 0.0, 0.3, 1.0])
    with np.errstate(divide="ignore"):
        until = np.where(growth > 0, 0.15 / growth, np.inf)
    envelope = rng.uniform(0.0, 0.3, k) * (rng.uniform(size=k) < 0.5)  # a braking envelope, some legs
    for g, u, legs in (
        (growth, until, None),
        (np.zeros(n), np.full(n, np.inf), None),
        (growth, np.full(n, np.inf), None),
        (growth, until, envelope),
    ):
        expected = legs_first_contact(
            starts, times, velocities, durations, positions, obstacle_velocities, radii, g, u, legs
        )
        got = leg_steps.legs_first_contact(
            starts,
            times,
            velocities,
            durations,
            positions,
            obstacle_velocities,
            radii,
            g,
            u,
            np.zeros(k) if legs is None else legs,
        )
        assert np.array_equal(np.isinf(expected), np.isinf(got))
        assert np.allclose(expected, got, rtol=0.0, atol=1e-12)
        assert np.isfinite(expected).any() and np.isinf(expected).any()  # both kinds of legs are there


@pytest.mark.parametrize("path", PATHS, ids=["straight", "corner", "zigzag"])
def test_corridor_kernels_match_reference(path):
    """Corridor checks of random legs (inside, across a junction, leaving) against the path's own
    (:meth:`DesignatedPath.legs_inside`), for legs to the subgoal too (:func:`_goal_legs_inside`)."""
    from viapath.planning.viapath import legs as leg_steps

    rng = np.random.default_rng(13)
    low, high = path.waypoints.min(axis=0) - 1.5, path.waypoints.max(axis=0) + 1.5
    starts, ends = rng.uniform(low, high, (600, 2)), rng.uniform(low, high, (600, 2))
    for tolerance in (1e-9, 0.3):
        expected = path.legs_inside(starts, ends, 0.05, tolerance)
        assert np.array_equal(compiled.legs_inside(path, starts, ends, 0.05, tolerance), expected)
        assert expected.any() and not expected.all()
    for subgoal_index in range(len(path.waypoints)):
        goal = (path.waypoints[subgoal_index], 0.0, np.zeros(0), np.zeros(3), subgoal_index, 0.05, 1e-9)
        expected = _goal_legs_inside(path, starts, subgoal_index, 1e-9)
        got = leg_steps.goal_legs_inside_all(compiled._corridor(path), starts, goal)
        assert np.array_equal(got, expected)
        assert expected.any() and not expected.all()


def _goal_legs_inside(path, starts, subgoal_index, tolerance_m):
    """Legs to the subgoal inside the corridor: the subgoal ends both capsules next to it, so a leg from a point
    inside one of them is inside that capsule (convex); other legs by :meth:`DesignatedPath.legs_inside`."""
    inside = np.zeros(len(starts), dtype=bool)
    for i in (subgoal_index - 1, subgoal_index):
        if i < len(path.segment_lengths_m):  # (subgoal 0: i = -1, the last segment, as the kernel reads it)
            rel = starts - path.segment_starts[i]
            along = np.clip(rel @ path.segment_directions[i], 0.0, path.segment_lengths_m[i])
            gap = np.hypot(*(rel - along[:, None] * path.segment_directions[i]).T) - path.half_widths_m[i]
            inside |= gap <= tolerance_m
    rest = ~inside
    subgoal = path.waypoints[subgoal_index]
    inside[rest] = path.legs_inside(starts[rest], np.broadcast_to(subgoal, (int(rest.sum()), 2)), 0.05, tolerance_m)
    return inside


def _plans_equal(a, b):
    """Two plans the same, bit for bit ."""
    assert a.status == b.status and a.speed_mps == b.speed_mps
    for name in ("target", "via_points", "waypoints", "candidate_costs"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert (a.subgoal_index, a.candidate_count, a.chosen) == (b.subgoal_index, b.candidate_count, b.chosen)
    assert a.extras == b.extras


@settings(max_examples=150, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(cases())
def test_recorded_polylines_and_a_further_critic_leave_the_plan_as_it_is(case):
    """With ``record_candidates`` every candidate's polyline is in the plan (to the subgoal, the chosen one the
    plan's waypoints), and a critic beyond the paper's that costs nothing (scored between the
    compiled choice's two halves) leaves the plan as it is, bit for bit, its zero term in the cost breakdown."""
    from viapath.planning.viapath.critics import Distance

    class Nothing(Distance):
        name = "nothing"

    path = PATHS[case[0]]
    planners = [
        make_planner("viapath", path, nominal_speed_mps=0.2, record_candidates=record)
        for record in (False, True, False)
    ]
    planners[2].critics = (*planners[2].critics, Nothing(0.0))
    recorded_cycles = 0
    for observation in _observations(case):
        plain, recorded, extra = (planner.plan(observation).plan for planner in planners)
        terms = extra.extras.pop("cost_terms", None)
        if terms is not None:
            assert terms["chosen"].pop("nothing") == 0.0
            assert terms["runner_up"] is None or terms["runner_up"].pop("nothing") == 0.0
            extra.extras["cost_terms"] = terms
        _plans_equal(plain, extra)
        assert plain.candidate_polylines == []
        if recorded.candidate_polylines:
            recorded_cycles += 1
            assert len(recorded.candidate_polylines) == recorded.candidate_count
            if recorded.status in ("avoid", "straight"):
                assert np.array_equal(recorded.candidate_polylines[recorded.chosen], recorded.waypoints)
            for line in recorded.candidate_polylines:  # (a slow candidate's starts where its slow leg ends)
                assert len(line) >= 2 and np.array_equal(line[-1], recorded.waypoints[-1])
    recorded_cycle_counts.append(recorded_cycles)


recorded_cycle_counts: list[int] = []


def test_the_recording_test_saw_candidates():
    """(The test above runs first in this file: it recorded candidates in many of its cycles.)"""
    assert sum(recorded_cycle_counts) >= 25


def test_compiled_choice_scalars_match_reference():
    """The scalar pieces of selection.choose against the reference's operations they stand in for: atan2
    (geometry.angles_of, libm's), wrap_angle (np.mod's sign convention), np.degrees, np.round to mm/s."""
    from viapath.geometry import angles_of, wrap_angle
    from viapath.planning.viapath import rollout

    signed_zeros_and_axes = [[0.0, 0.0], [-0.0, 0.0], [0.0, -0.0], [-1.0, 0.0], [-1.0, -0.0], [0.0, 1.0], [1e-300, 1]]
    vectors = np.concatenate(
        [np.random.default_rng(4).normal(size=(4000, 2)) * np.logspace(-6, 3, 4000)[:, None], signed_zeros_and_axes]
    )
    atan2 = compiled_lambda(lambda values: np.array([math.atan2(y, x) for x, y in values]))
    np.testing.assert_array_equal(atan2(vectors), angles_of(vectors))

    rng = np.random.default_rng(5)
    angles = np.concatenate(
        [
            rng.uniform(-20, 20, 4000),
            [
                0.0,
                -0.0,
                np.pi,
                -np.pi,
                2 * np.pi,
                -2 * np.pi,
                3 * np.pi,
                np.nextafter(np.pi, 4),
                np.nextafter(-np.pi, -4),
                1e-300,
            ],
        ]
    )
    wrap = compiled_lambda(lambda values: np.array([rollout.wrap(v) for v in values]))
    np.testing.assert_array_equal(wrap(angles), wrap_angle(angles))
    degrees = compiled_lambda(lambda values: np.array([v * (180.0 / np.pi) for v in values]))
    np.testing.assert_array_equal(degrees(np.abs(angles)), np.degrees(np.abs(angles)))
    speeds = np.concatenate([rng.uniform(0, 2, 4000), np.arange(0, 2000) / 1000 + 0.0005])
    rint = compiled_lambda(lambda values: np.array([np.rint(v * 1000) for v in values]))
    np.testing.assert_array_equal(rint(speeds), np.round(speeds * 1000))


def test_the_warm_up_reaches_the_choice_and_the_escape():
    """precompile's cycles reach the compiled choice and the escape, and each of their kernels then has one
    compiled signature (the planner's argument types do not vary): the doors Python calls them through (packing's;
    the kernels behind them, loaded from the cache inside the doors, may show none)."""
    from viapath import jit
    from viapath.planning.viapath import step_aside
    from viapath.planning.viapath.planner import precompile, warm_up_crowds

    planner = make_planner("viapath", DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0), nominal_speed_mps=0.2)
    statuses = []
    for people in warm_up_crowds():
        planner.reset()
        statuses.append(
            planner.plan(Observation(0.0, RobotState(np.zeros(2), 0.0, 0.2, 0.0, 0.25), people)).plan.status
        )
    assert statuses[0] in ("avoid", "slow", "wait") and statuses[1] == "escape"
    assert precompile()
    if jit.enabled():
        kernels = (compiled._escape_headings, compiled._escape_scores, compiled._choose)
        aside = (step_aside.roll_outs, step_aside.clearances)  # the step aside's doors (from rest)
        for kernel in (*kernels, compiled._choose_tree, compiled._choose_ranked, *aside):
            assert len(kernel.signatures) == 1, kernel


def test_a_static_cycle_asks_the_tree_alone_with_the_warm_ups_types():
    """The way round static geometry asks whether static geometry alone closes the candidate tree
    (:func:`tree_is_empty`) with the static discs' shapes; precompile asked it without any: the same compiled
    signature, so a robot whose map first leaves it no candidate does not stop to compile."""
    from viapath import jit
    from viapath.planning.viapath.choice import tree_is_empty
    from viapath.planning.viapath.planner import precompile
    from viapath.static import StaticLayer

    assert precompile()
    path = DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0)
    planner = make_planner("viapath", path, nominal_speed_mps=0.2)
    wall = StaticLayer.of_shapes([np.array([[2.0, -1.5], [2.0, 1.5]])])  # across the corridor: the tree is empty
    robot = RobotState(np.zeros(2), 0.0, 0.0, 0.0, 0.25)
    planner.plan(Observation(0.0, robot, Obstacles.empty(), wall))
    before = list(compiled._choose_tree.signatures) if jit.enabled() else []
    assert tree_is_empty(planner, planner._checks, *planner.speed_set(0.0))
    if jit.enabled():
        assert list(compiled._choose_tree.signatures) == before and len(before) == 1


def compiled_lambda(function):
    """``function`` compiled as the kernels are (plain Python with compilation off)."""
    from viapath.jit import compiled as compile_function

    return compile_function(cache=False)(function)  # (a lambda: nothing to cache)


def test_pairwise_sum_is_numpys_sum():
    """The compiled sums (the escape's separation, the detector's convexity test) are np.sum's bit for bit along a
    row of 0 to 1100 values, small, large, signed zeros and zeros among them."""
    from viapath.sums import pairwise_sum

    rng = np.random.default_rng(8)
    for count in [*range(140), 255, 256, 257, 300, 1031, 1100]:
        rows = rng.normal(0.0, 1.0, (4, count)) * rng.choice([1e-8, 1.0, 1e8], (4, count))
        rows[1] = np.where(rng.random(count) < 0.5, -0.0, 0.0)
        rows[2] = np.where(rng.random(count) < 0.5, rows[2], 0.0)
        expected = np.sum(rows, axis=1)
        got = np.array([0.0 + pairwise_sum(np.ascontiguousarray(row), 0, count) for row in rows])
        assert np.array_equal(got.view(np.int64), expected.view(np.int64))
