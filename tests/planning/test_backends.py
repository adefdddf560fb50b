"""The compiled hot path (numba, extra ``fast``) decides as the numpy reference does (issue 16).

Both planners get the same random observations (paths with corners, people with and without
uncertainty, the robot anywhere near the corridor, with and without the shield behind it) and must
take the same decision every cycle: same status, same way round (obstacle, side, early/late) and speed,
commands equal to 1e-9. Two cycles per case, so last cycle's choice (hysteresis, keep_previous_way,
calm escape) is exercised too.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.compiled import ENVIRONMENT_VARIABLE, numba_available, resolve
from viapath.planning import make_planner
from viapath.safety.shielded import ShieldedPlanner

pytestmark = pytest.mark.skipif(not numba_available(), reason="numba (extra 'fast') is not installed")

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


def _planner(path, backend: str, shield: bool):
    planner = make_planner("viapath", path, nominal_speed_mps=0.2, compute=backend)
    return ShieldedPlanner(planner) if shield else planner


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


@settings(max_examples=1000, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(cases())
def test_numba_decides_as_numpy(case):
    path = PATHS[case[0]]
    reference, compiled = _planner(path, "numpy", case[7]), _planner(path, "numba", case[7])
    for observation in _observations(case):
        a, b = reference.plan(observation), compiled.plan(observation)
        assert a.plan.status == b.plan.status
        inner_a = getattr(reference, "inner", reference)
        inner_b = getattr(compiled, "inner", compiled)
        assert inner_a._previous == inner_b._previous  # same way round and speed (or both none)
        assert abs(a.command.speed_mps - b.command.speed_mps) <= 1e-9
        assert abs(a.command.turn_rate_radps - b.command.turn_rate_radps) <= 1e-9
        assert np.allclose(a.plan.target, b.plan.target, rtol=0.0, atol=1e-9)
        assert (a.plan.extras["backend"], b.plan.extras["backend"]) == ("numpy", "numba")


def test_kernels_match_reference_on_edge_cases():
    """The contact kernel against numpy where the cone is capped mid-leg, legs start inside a disc, the
    relative speed is zero and the cone outgrows the relative speed (a < 0)."""
    from viapath.compiled import planning as kernels
    from viapath.geometry import legs_first_contact

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
        got = kernels.legs_first_contact(
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


def test_backend_choice(monkeypatch):
    monkeypatch.delenv(ENVIRONMENT_VARIABLE, raising=False)
    assert resolve("auto") == "numba"
    assert resolve("numpy") == "numpy"
    monkeypatch.setenv(ENVIRONMENT_VARIABLE, "numpy")
    assert resolve("auto") == "numpy"
    assert resolve("numba") == "numba"  # an explicit option wins over the environment
    monkeypatch.setenv(ENVIRONMENT_VARIABLE, "fortran")
    with pytest.raises(ValueError, match=ENVIRONMENT_VARIABLE):
        resolve("auto")


def test_track_kernel_matches_reference():
    """The compiled roll-out against :func:`viapath.kinematics.track`, from random states towards random
    targets (sharp turns, targets behind, at rest and at speed)."""
    from viapath.compiled.arithmetic import Arithmetic
    from viapath.kinematics import UnicycleState, track
    from viapath.observation import MotionLimits

    rng = np.random.default_rng(5)
    limits = MotionLimits()
    compiled = Arithmetic("numba")
    worst = 0.0
    for _ in range(200):
        state = UnicycleState(
            *rng.uniform(-2, 2, 2), rng.uniform(-np.pi, np.pi), rng.uniform(0, 0.6), rng.uniform(-2, 2)
        )
        target, speed = rng.uniform(-3, 3, 2), rng.uniform(0, 0.6)
        expected = track(state, target, speed, limits, 0.1, 20, 2.5)
        got = compiled.track(state, target, speed, limits, 0.1, 20, 2.5)
        worst = max(worst, float(np.max(np.abs(expected - got))))
    assert worst <= 1e-12


def test_planners_command_says_which_path_runs(monkeypatch):
    import json

    from typer.testing import CliRunner

    from viapath.cli import app

    for environment, expected in (("", "numba"), ("numpy", "numpy")):
        monkeypatch.setenv(ENVIRONMENT_VARIABLE, environment)
        result = CliRunner().invoke(app, ["planners", "viapath", "--json"])
        assert result.exit_code == 0, result.output
        compute = [option for option in json.loads(result.output) if option["name"] == "compute"]
        assert compute and compute[0]["resolved"] == expected and compute[0]["default"] == "auto"
        text = CliRunner().invoke(app, ["planners", "viapath"]).output
        assert f"(here: {expected})" in text


def test_via_options_kernel_matches_reference():
    """Via points of random (node, obstacle) pairs: nodes inside the disc, obstacles faster and slower
    than the robot (two roots or one), the cone capped before and after the passing time."""
    from viapath.compiled import planning as kernels
    from viapath.geometry import via_options

    rng = np.random.default_rng(11)
    p = 500
    starts = rng.uniform(-3, 3, (p, 2))
    times = rng.uniform(0, 5, p)
    speeds = rng.uniform(0.05, 0.6, p)
    positions = rng.uniform(-3, 3, (p, 2))
    positions[:20] = starts[:20]  # the node sits on the obstacle: no tangent
    velocities = rng.uniform(-1.5, 1.5, (p, 2))
    radii = rng.uniform(0.4, 0.9, p)
    growth = np.where(rng.random(p) < 0.5, 0.0, rng.uniform(0, 0.2, p))
    with np.errstate(divide="ignore"):
        until = np.where(growth > 0, 0.15 / np.where(growth > 0, growth, 1.0), np.inf)
    envelope = np.where(rng.random(p) < 0.5, 0.0, rng.uniform(0, 0.3, p))
    expected = via_options(starts, times, speeds, positions, velocities, radii, growth, until, envelope, 30.0)
    got = kernels.via_options(starts, times, speeds, positions, velocities, radii, growth, until, envelope, 30.0)
    assert np.array_equal(expected[0], got[0]) and np.array_equal(expected[1], got[1])
    for a, b in zip(expected[2:], got[2:]):
        assert np.allclose(a, b, rtol=0.0, atol=1e-12)
    late = np.isin(expected[1], (2, 3))
    assert late.any() and (~late).any() and len(np.unique(expected[0])) < p  # both roots; some pairs have none


@pytest.mark.parametrize("path", PATHS, ids=["straight", "corner", "zigzag"])
def test_corridor_kernels_match_reference(path):
    """Corridor checks of random legs (inside, across a junction, leaving) against the numpy reference."""
    from viapath.compiled.arithmetic import Arithmetic
    from viapath.planning.viapath.checks import LegChecks

    rng = np.random.default_rng(13)
    low, high = path.waypoints.min(axis=0) - 1.5, path.waypoints.max(axis=0) + 1.5
    starts, ends = rng.uniform(low, high, (600, 2)), rng.uniform(low, high, (600, 2))
    compiled = Arithmetic("numba")
    for tolerance in (1e-9, 0.3):
        expected = path.legs_inside(starts, ends, 0.05, tolerance)
        assert np.array_equal(compiled.legs_inside(path, starts, ends, 0.05, tolerance), expected)
        assert expected.any() and not expected.all()
    for subgoal_index in range(len(path.waypoints)):
        checks = LegChecks(
            path=path,
            position=np.zeros(2),
            heading_rad=0.0,
            speed_mps=0.0,
            turn_rate_radps=0.0,
            subgoal=path.waypoints[subgoal_index],
            subgoal_index=subgoal_index,
            is_final_subgoal=False,
            obstacles=None,
            check_radii=None,
            growth=None,
            growth_until_s=None,
            via_radii=None,
            horizon_s=10.0,
            stop_short_m=0.0,
            continuation=None,
            corridor_tolerance_m=1e-9,
            corridor_check_spacing_m=0.05,
        )
        expected = checks.goal_legs_inside(starts)
        got = compiled.goal_legs_inside(path, starts, checks.subgoal, subgoal_index, 0.05, 1e-9)
        assert np.array_equal(got, expected)
        assert expected.any() and not expected.all()


def test_escape_scores_match_reference():
    """The escape's scores of every command on both paths, in crowds that overlap the robot (the
    separation term) or only threaten it (the time to contact)."""
    from dataclasses import replace

    from viapath.compiled.arithmetic import Arithmetic
    from viapath.planning.viapath.checks import LegChecks
    from viapath.planning.viapath.escape import escape_scores

    rng = np.random.default_rng(17)
    path = PATHS[1]
    planner = make_planner("viapath", path, nominal_speed_mps=0.2, compute="numpy")
    overlapped = 0
    for _ in range(60):
        n = int(rng.integers(1, 15))
        positions = rng.uniform(-1.5, 1.5, (n, 2)) + [1.0, 0.0]
        velocities = rng.uniform(-1, 1, (n, 2))
        sigma = rng.uniform(0, 0.1, n)
        observation = Observation(
            0.0,
            RobotState(np.array([1.0, 0.2]), rng.uniform(-3, 3), rng.uniform(0, 0.5)),
            Obstacles(positions, velocities, np.full(n, 0.3), position_sigma_m=sigma, velocity_sigma_mps=sigma),
        )
        planner.reset()
        situation = planner.situation(observation)
        checks = LegChecks.of(situation, planner.config, planner.subgoals, planner.subgoal_policy, 0.25)
        _commands, ends, expected = escape_scores(checks, planner.limits, planner.config)
        _, got_ends, got = escape_scores(
            replace(checks, arithmetic=Arithmetic("numba", whole_steps=False)), planner.limits, planner.config
        )
        assert _same_bits(got, expected) and _same_bits(got_ends, ends)  # the small kernels: the same values
        overlapped += bool(np.any(np.hypot(*(positions - [1.0, 0.2]).T) < checks.check_radii))
    assert 5 < overlapped < 60  # both kinds of crowd came up


@pytest.mark.parametrize("path", PATHS, ids=["straight", "corner", "zigzag"])
def test_goal_legs_kernel_matches_reference(path):
    """kernels.goal_legs (the whole LegChecks.goal_legs in one call) equals the numpy code bit for bit:
    with and without the continuation past the subgoal, the braking envelope, a blocked subgoal's stop
    short, a finite and an infinite horizon, people with and without uncertainty, and none."""
    from dataclasses import replace

    from viapath.compiled.arithmetic import NUMPY, Arithmetic
    from viapath.planning.viapath.checks import LegChecks

    rng = np.random.default_rng(7)
    compared = 0
    for trial in range(60):
        n = int(rng.integers(0, 9))
        robot = RobotState(
            np.array([rng.uniform(-0.5, 3.0), rng.uniform(-1.3, 1.3)]),
            rng.uniform(-0.8, 0.8),
            rng.uniform(0.0, 0.5),
            0.0,
        )
        positions = robot.position + rng.uniform(-4.0, 6.0, (n, 2))
        velocities = rng.uniform(-1.2, 1.2, (n, 2))
        uncertain = trial % 2 == 0
        obstacles = Obstacles(
            positions,
            velocities,
            rng.uniform(0.2, 0.35, n),
            position_sigma_m=rng.uniform(0.0, 0.05, n) if uncertain else None,
            velocity_sigma_mps=rng.uniform(0.0, 0.1, n) if uncertain else None,
        )
        planner = make_planner("viapath", path, nominal_speed_mps=0.2, compute="numpy")
        situation = planner.situation(Observation(0.0, robot, obstacles))
        base = LegChecks.of(situation, planner.config, planner.subgoals, planner.subgoal_policy, 0.25, NUMPY)
        k = int(rng.integers(1, 12))
        starts = robot.position + rng.uniform(-2.0, 3.0, (k, 2))
        starts[0] = robot.position
        times = rng.uniform(0.0, 6.0, k) * (rng.random(k) < 0.7)
        speeds = rng.choice([0.1, 0.2, 0.3, 0.4, 0.5, 0.6], k)
        continuations = [base.continuation, None]
        if base.continuation is None and path.segment_lengths_m.size > 1:
            continuations[0] = (path.segment_directions[1], path.segment_lengths_m[1])
        for continuation in continuations:
            for envelope in (0.0, 2.0):
                for stop_short in (0.0, 0.6):
                    checks = replace(
                        base,
                        continuation=continuation,
                        envelope_accel_mps2=envelope,
                        envelope_period_s=0.1,
                        max_accel_mps2=0.8,
                        stop_short_m=stop_short,
                    )
                    compiled = replace(checks, arithmetic=Arithmetic("numba"))
                    for horizon in (None, np.inf, 3.0):
                        expected = checks.goal_legs(starts, times, speeds, horizon)
                        found = compiled.goal_legs(starts, times, speeds, horizon)
                        for a, b in zip(expected, found):
                            assert a.shape == b.shape and a.dtype == b.dtype
                            np.testing.assert_array_equal(a, b)
                        compared += 1
    assert compared == 60 * 2 * 2 * 2 * 3


def _tree_inputs(case, backend, path=None):
    """The arguments the planner hands candidates.grow in the first cycle of ``case``."""
    from dataclasses import replace

    from viapath.compiled.arithmetic import Arithmetic
    from viapath.planning.viapath.candidates import RootLegs
    from viapath.planning.viapath.checks import LegChecks

    path_index, _, _, _, _, _, _, shield, _ = case
    planner = _planner(PATHS[path_index] if path is None else path, "numpy", shield)
    inner = getattr(planner, "inner", planner)
    observation = next(_observations(case))
    situation = inner.situation(observation)
    checks = LegChecks.of(
        situation, inner.config, inner.subgoals, inner.subgoal_policy, inner.robot_radius_m, Arithmetic(backend)
    )
    if shield:
        checks = replace(
            checks,
            envelope_accel_mps2=inner.shield.config.person_accel_mps2,
            envelope_period_s=inner.shield.dt_s,
            max_accel_mps2=inner.limits.max_accel_mps2,
        )
    speeds, nominal_index = inner.speed_set(observation.robot.speed_mps)
    return checks, RootLegs.of(checks, speeds, nominal_index), inner._slow_checks(checks), inner.config


@settings(max_examples=600, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(cases(), st.sampled_from([(3, 12), (3, 2), (1, 0), (5, 1)]))
def test_tree_kernel_builds_the_same_candidates(case, limits):
    """kernels.grow (the whole candidate tree in one call) builds the numpy grow's candidates exactly:
    the same nodes in the same order (so the same ties), the same leaves and arrays, bit for bit; with
    the default depth and root limit and with others (a root limit of 1-2 takes the sorted branch)."""
    from viapath.planning.viapath.planner import grow_step as grow

    depth, root_limit = limits
    found = []
    for backend in ("numpy", "numba"):
        checks, roots, slow, config = _tree_inputs(case, backend)
        config = config.replace(max_depth=depth, max_root_obstacles=root_limit)
        found.append(grow(checks, roots, config, slow))
    reference, compiled = found
    assert (reference is None) == (compiled is None)
    if reference is None:
        return
    for name in reference.nodes:
        np.testing.assert_array_equal(reference.nodes[name], compiled.nodes[name], err_msg=name)
    for name in ("leaves", "total_length_m", "speed_mps", "slow_s", "slow_speed_mps", "first_direction", "ways"):
        np.testing.assert_array_equal(getattr(reference, name), getattr(compiled, name), err_msg=name)


U_TURN = DesignatedPath([[0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [0.0, 3.0]], half_width_m=0.8)


@pytest.mark.parametrize("path_index", [1, 3], ids=["corner", "u-turn"])
def test_tree_kernel_builds_the_same_corner_candidates(path_index):
    """The same with the subgoal past a corner of the path (a blocked subgoal given up, or the robot pushed
    back): the straight leg cuts the corridor and the path's corners become via points (_corner_nodes),
    at every speed, each chained on from the root of its speed."""
    from dataclasses import replace

    from viapath.compiled.arithmetic import Arithmetic
    from viapath.planning.viapath.candidates import CORNER, RootLegs
    from viapath.planning.viapath.planner import grow_step as grow

    path = PATHS[path_index] if path_index < len(PATHS) else U_TURN
    last = 2  # the subgoal past the first corner (on the U-turn, another segment follows)
    rng = np.random.default_rng(11)
    corner_nodes = 0
    for trial in range(150):
        n = int(rng.integers(0, 6))
        # Where the straight leg to the last waypoint cuts the corridor: near the start of either path.
        robot = np.array([rng.uniform(-0.3, 1.0), rng.uniform(-0.7, 0.7)])
        case = (
            path_index,
            (robot[0], robot[1], rng.uniform(-0.5, 0.5), rng.uniform(0.0, 0.4), 0.0),
            robot + rng.uniform(-3.0, 5.0, (n, 2)),
            rng.uniform(-1.0, 1.0, (n, 2)),
            rng.uniform(0.2, 0.35, n),
            None,
            None,
            bool(trial % 2),
            np.zeros((n, 2)),
        )
        found = []
        for backend in ("numpy", "numba"):
            checks, _, slow, config = _tree_inputs(case, backend, path)
            checks = replace(checks, subgoal=path.waypoints[last].copy(), subgoal_index=last, continuation=None)
            slow = replace(
                slow, subgoal=checks.subgoal, subgoal_index=last, continuation=None, arithmetic=Arithmetic(backend)
            )
            roots = RootLegs.of(checks, np.array([0.1, 0.2, 0.3, 0.5]), 1)
            found.append(grow(checks, roots, config, slow))
        reference, compiled = found
        assert (reference is None) == (compiled is None)
        if reference is None:
            continue
        for name in reference.nodes:
            np.testing.assert_array_equal(reference.nodes[name], compiled.nodes[name], err_msg=name)
        np.testing.assert_array_equal(reference.leaves, compiled.leaves)
        np.testing.assert_array_equal(reference.total_length_m, compiled.total_length_m)
        corner_nodes += int(np.sum(reference.nodes["way"][:, 0] == CORNER))
    assert corner_nodes > 50  # the corners were there to compare


def test_whole_step_kernels_wait_for_their_compilation(monkeypatch):
    """``auto`` takes the whole-step kernels (goal_legs, grow: seconds to compile the first time) only once
    they are compiled; an explicit numba takes them at once. Either way the decisions are the same."""
    from viapath.compiled import arithmetic
    from viapath.planning.viapath.planner import precompile

    monkeypatch.delenv(ENVIRONMENT_VARIABLE, raising=False)
    monkeypatch.setattr(arithmetic, "whole_steps_compiled", lambda: False)
    assert arithmetic.arithmetic_for("auto") == arithmetic.Arithmetic("numba", whole_steps=False)
    assert arithmetic.arithmetic_for("numba").whole_steps
    monkeypatch.setenv(ENVIRONMENT_VARIABLE, "numba")
    assert arithmetic.arithmetic_for("auto").whole_steps
    monkeypatch.setenv(ENVIRONMENT_VARIABLE, "numpy")
    assert not arithmetic.arithmetic_for("auto").whole_steps
    monkeypatch.delenv(ENVIRONMENT_VARIABLE)
    monkeypatch.setattr(arithmetic, "whole_steps_compiled", lambda: True)
    assert arithmetic.arithmetic_for("auto").whole_steps
    assert precompile()


def test_one_entry_compiles_the_shield_and_the_planner():
    """viapath.precompile.precompile (what viapath bench and the ROS 2 node call) leaves both ready, so that a
    plain ``auto`` takes the compiled shield and the planner's whole-step code from the first cycle."""
    from viapath.compiled.arithmetic import whole_steps_compiled
    from viapath.precompile import precompile

    assert precompile() is True
    assert whole_steps_compiled()


@settings(max_examples=200, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(cases())
def test_numba_without_whole_steps_decides_as_numpy(case):
    """The compiled path before its whole-step kernels are compiled (small kernels only) decides as well."""
    from viapath.compiled.arithmetic import Arithmetic

    path = PATHS[case[0]]
    reference, compiled = _planner(path, "numpy", case[7]), _planner(path, "numba", case[7])
    inner = getattr(compiled, "inner", compiled)
    inner.arithmetic = Arithmetic("numba", whole_steps=False)
    for observation in _observations(case):
        a, b = reference.plan(observation), compiled.plan(observation)
        assert a.plan.status == b.plan.status
        assert getattr(reference, "inner", reference)._previous == inner._previous
        assert abs(a.command.speed_mps - b.command.speed_mps) <= 1e-9
        assert abs(a.command.turn_rate_radps - b.command.turn_rate_radps) <= 1e-9


@settings(max_examples=300, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(cases())
def test_numba_decides_as_numpy_with_the_way_back(case):
    """The same with the way back to the path on (return_lookahead_m, the close-to-path preset's 0.5 m):
    its leg to a path point goes through the compiled goal_legs too."""
    path = PATHS[case[0]]
    planners = []
    for backend in ("numpy", "numba"):
        planner = make_planner("viapath", path, nominal_speed_mps=0.2, compute=backend, return_lookahead_m=0.5, k2=0.01)
        planners.append(ShieldedPlanner(planner) if case[7] else planner)
    reference, compiled = planners
    for observation in _observations(case):
        a, b = reference.plan(observation), compiled.plan(observation)
        assert a.plan.status == b.plan.status
        assert a.plan.extras.get("way_back") == b.plan.extras.get("way_back")
        assert getattr(reference, "inner", reference)._previous == getattr(compiled, "inner", compiled)._previous
        assert abs(a.command.speed_mps - b.command.speed_mps) <= 1e-9
        assert abs(a.command.turn_rate_radps - b.command.turn_rate_radps) <= 1e-9


def _plans_equal(a, b):
    """Two plans the same, bit for bit (the backend's name apart)."""
    assert a.status == b.status and a.speed_mps == b.speed_mps
    for name in ("target", "via_points", "waypoints", "candidate_costs"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert (a.subgoal_index, a.candidate_count, a.chosen) == (b.subgoal_index, b.candidate_count, b.chosen)
    assert a.extras == b.extras


@settings(max_examples=600, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(
    cases(),
    st.sampled_from(
        [
            {},
            {"theta_unit": "deg", "preferred_side": "right"},
            {"max_rollouts": 1},
            {"keep_previous_way": False, "hysteresis": 0.2, "slow_times_s": (1.0,)},
        ]
    ),
)
def test_compiled_choice_is_the_numpy_choice(case, options):
    """kernels.choose (roots, step 1, tree, critics, order and roll-outs in one call) against the numpy
    planner: the same plan bit for bit — status, target, via points, every candidate's cost, each critic's
    share of the chosen and the runner-up, turn on the spot, the shield's refusals — and the same command,
    with the paper's options and others (degrees, the other side, a single roll-out, one slow time)."""
    path = PATHS[case[0]]
    planners = []
    for backend in ("numpy", "numba"):
        planner = make_planner("viapath", path, nominal_speed_mps=0.2, compute=backend, **options)
        planners.append(ShieldedPlanner(planner) if case[7] else planner)
    reference, compiled = planners
    assert getattr(compiled, "inner", compiled)._compiled_choice()
    for observation in _observations(case):
        a, b = reference.plan(observation), compiled.plan(observation)
        b.plan.extras["backend"] = a.plan.extras["backend"]
        _plans_equal(a.plan, b.plan)
        assert a.command == b.command
        assert getattr(reference, "inner", reference)._previous == getattr(compiled, "inner", compiled)._previous


def test_compiled_choice_scalars_match_reference():
    """The scalar pieces of kernels.choose against the reference's operations they stand in for: atan2
    (geometry.angles_of, libm's), wrap_angle (np.mod's sign convention), np.degrees, np.round to mm/s."""
    from numba import njit

    from viapath.compiled import planning as kernels
    from viapath.geometry import angles_of, wrap_angle

    signed_zeros_and_axes = [[0.0, 0.0], [-0.0, 0.0], [0.0, -0.0], [-1.0, 0.0], [-1.0, -0.0], [0.0, 1.0], [1e-300, 1]]
    vectors = np.concatenate(
        [np.random.default_rng(4).normal(size=(4000, 2)) * np.logspace(-6, 3, 4000)[:, None], signed_zeros_and_axes]
    )
    atan2 = njit(lambda values: np.array([math.atan2(y, x) for x, y in values]))
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
    wrap = njit(lambda values: np.array([kernels._wrap(v) for v in values]))
    np.testing.assert_array_equal(wrap(angles), wrap_angle(angles))
    degrees = njit(lambda values: np.array([v * (180.0 / np.pi) for v in values]))
    np.testing.assert_array_equal(degrees(np.abs(angles)), np.degrees(np.abs(angles)))
    speeds = np.concatenate([rng.uniform(0, 2, 4000), np.arange(0, 2000) / 1000 + 0.0005])
    rint = njit(lambda values: np.array([np.rint(v * 1000) for v in values]))
    np.testing.assert_array_equal(rint(speeds), np.round(speeds * 1000))


@settings(max_examples=300, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(cases(), st.integers(0, 3), st.sampled_from([100, 200, 300]))
def test_compiled_choice_after_refusals_and_a_vanished_way(case, way, speed_mmps):
    """The compiled choice's rarer branches against numpy: a shield that refuses the paper's step 1 and every
    other candidate it is offered (so the search goes on past the kernel's first candidate that follows,
    in Python), and last cycle's way round set to one round an obstacle that may have vanished (the
    relaxed search with only that way, only_way)."""
    from viapath.planning.viapath.candidates import Choice, Way

    path_index, _, positions, _, _, sigma_p, _, _, _ = case
    planners = [
        make_planner("viapath", PATHS[path_index], nominal_speed_mps=0.2, compute=backend)
        for backend in ("numpy", "numba")
    ]
    offered = [[], []]
    for planner, seen in zip(planners, offered):

        def inside_shield(plan, seen=seen):
            seen.append((plan.status, plan.chosen, plan.target.tolist()))
            return len(seen) % 2 == 0  # refuse every other one: step 1 is always refused

        planner._inside_shield = inside_shield
        if len(positions) and sigma_p is not None:
            planner._previous = Choice(Way(0, (1, -1)[way % 2], way // 2), speed_mmps)
    observation = next(_observations(case))
    a, b = (planner.plan(observation) for planner in planners)
    b.plan.extras["backend"] = a.plan.extras["backend"]
    _plans_equal(a.plan, b.plan)
    assert a.command == b.command and offered[0] == offered[1]
    assert planners[0]._previous == planners[1]._previous


# -- the escape compiled whole (kernels.escape_headings, kernels.escape_scores) ------------------------------------


def _same_bits(a, b) -> bool:
    """Equal arrays of the same dtype and shape, floats compared as bit patterns (-0.0 is not 0.0)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype.kind == "f":
        return bool(np.array_equal(a.view(np.int64), b.view(np.int64)))
    return bool(np.array_equal(a, b))


@st.composite
def escape_cases(draw):
    """A robot in a crowd that may surround, overlap or threaten it, inside the corridor or outside it, with
    the escape's options (calm or not, last cycle's command or none, bounds on the excess)."""
    path_index = draw(st.integers(0, len(PATHS) - 1))
    n = draw(st.integers(0, 14))
    floats = lambda lo, hi: st.floats(lo, hi, allow_nan=False, allow_infinity=False)
    rng = np.random.default_rng(draw(st.integers(0, 2**31 - 1)))
    robot = (
        draw(floats(-1.0, 4.0)),
        draw(floats(-3.0, 3.0)),
        draw(floats(-np.pi, np.pi)),
        draw(st.sampled_from([0.0, 0.05, 0.3, 0.6])),
        draw(st.sampled_from([0.0, -1.0, 0.4, 2.0])),
    )
    # people from touching the robot (distance 0) to 4 m off, all round it or in a ring closing in
    ring = draw(st.booleans())
    distance = rng.uniform(0.0, draw(st.sampled_from([0.7, 1.5, 4.0])), n)
    bearing = np.linspace(0.0, 2 * np.pi, n, endpoint=False) if ring else rng.uniform(-np.pi, np.pi, n)
    unit = np.stack([np.cos(bearing), np.sin(bearing)], 1)
    positions = np.array(robot[:2]) + distance[:, None] * unit
    velocities = -rng.uniform(0.0, 1.0, n)[:, None] * unit if ring else rng.uniform(-1.2, 1.2, (n, 2))
    uncertain = draw(st.booleans())
    sigma = rng.uniform(0.0, 0.1, n) if uncertain else None
    options = {
        "calm_escape": draw(st.booleans()),
        "escape_max_excess_m": draw(st.sampled_from([0.5, 0.0, 2.0])),
        "escape_s": draw(st.sampled_from([3.0, 1.0, 0.05])),
    }
    previous = draw(st.sampled_from([None, (0.0, 0.0), (0.3, -1.0), (0.6, 2.0)]))
    return path_index, robot, positions, velocities, rng.uniform(0.2, 0.35, n), sigma, options, previous


def _escape_checks(case):
    from viapath.observation import Command
    from viapath.planning.viapath.checks import LegChecks

    path_index, robot, positions, velocities, radii, sigma, options, previous = case
    planner = make_planner("viapath", PATHS[path_index], nominal_speed_mps=0.2, compute="numpy", options=options)
    x, y, heading, speed, turn = robot
    observation = Observation(
        0.0,
        RobotState(np.array([x, y]), heading, speed, turn),
        Obstacles(positions, velocities, radii, position_sigma_m=sigma, velocity_sigma_mps=sigma),
    )
    situation = planner.situation(observation)
    checks = LegChecks.of(situation, planner.config, planner.subgoals, planner.subgoal_policy, 0.25)
    return planner, checks, None if previous is None else Command(*previous)


@settings(max_examples=1500, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(escape_cases())
def test_compiled_escape_is_the_reference(case):
    """The compiled escape's commands, ends and scores are escape_scores' (numpy) bit for bit, and its
    standing check is the numpy path's, in every crowd."""
    from dataclasses import replace

    from viapath.compiled.arithmetic import Arithmetic
    from viapath.planning.viapath.escape import escape_fan, escape_scores

    planner, checks, previous = _escape_checks(case)
    commands, ends, scores = escape_scores(checks, planner.limits, planner.config, previous)
    standing = checks.contact_times(
        checks.position[None], np.zeros(1), np.zeros((1, 2)), np.array([planner.config.horizon_s])
    )
    fan = escape_fan(planner.limits, planner.config)
    compiled = Arithmetic("numba").escape(
        replace(checks, arithmetic=Arithmetic("numba")),
        planner.limits,
        planner.config,
        fan,
        previous,
        score_standing=True,
    )
    assert compiled[0] == bool(np.isinf(standing).all())
    assert _same_bits(compiled[1], commands)
    assert _same_bits(compiled[2], ends)
    assert _same_bits(compiled[3], scores)
    # without score_standing, a free standing skips the scores
    skipped = Arithmetic("numba").escape(checks, planner.limits, planner.config, fan, previous)
    assert skipped[0] == compiled[0] and (skipped[1] is None) == compiled[0]


@settings(max_examples=600, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(escape_cases())
def test_compiled_stop_or_escape_decides_as_numpy(case):
    """stop_or_escape's decision (command, status, the end it plans for) is the same on both paths; the
    compiled kernels run only with the whole-step kernels."""
    from dataclasses import replace

    from viapath.compiled.arithmetic import Arithmetic
    from viapath.planning.viapath.escape import escape_fan, stop_or_escape
    from viapath.planning.viapath.planner import escape_step

    planner, checks, previous = _escape_checks(case)
    expected = stop_or_escape(checks, planner.limits, planner.config, previous)
    for backend in (Arithmetic("numba"), Arithmetic("numba", whole_steps=False)):
        got = escape_step(replace(checks, arithmetic=backend), planner.limits, planner.config, previous)
        assert got.command == expected.command
        assert got.plan.status == expected.plan.status
        assert _same_bits(got.plan.target, expected.plan.target)
        assert got.plan.speed_mps == expected.plan.speed_mps
    fan = escape_fan(planner.limits, planner.config)
    assert Arithmetic("numba", whole_steps=False).escape(checks, planner.limits, planner.config, fan, previous) is None
    assert Arithmetic("numpy").escape(checks, planner.limits, planner.config, fan, previous) is None


def test_escape_cases_reach_every_branch():
    """The crowds above bring every kind of escape: standing free and not, people overlapped now (the
    separation) and none near, robots outside the corridor, every command priced out of bounds or not."""
    from viapath.planning.viapath.escape import escape_scores

    seen = set()

    @settings(max_examples=300, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
    @given(escape_cases())
    def collect(case):
        planner, checks, previous = _escape_checks(case)
        standing = checks.contact_times(
            checks.position[None], np.zeros(1), np.zeros((1, 2)), np.array([planner.config.horizon_s])
        )
        seen.add("standing free" if np.isinf(standing).all() else "standing hit")
        gap = np.hypot(*(checks.position - checks.obstacles.positions).T) - checks.check_radii
        seen.add("overlapped" if (gap <= 0).any() else "none overlapped")
        if len(gap) == 0:
            seen.add("nobody")
        if checks.path.corridor_excess(checks.position) > 0:
            seen.add("outside")
        _, _, scores = escape_scores(checks, planner.limits, planner.config, previous)
        seen.add("some out of bounds" if np.isinf(scores).any() else "all in bounds")
        if planner.config.calm_escape and previous is not None:
            seen.add("calm with previous")

    collect()
    assert seen == {
        "standing free",
        "standing hit",
        "overlapped",
        "none overlapped",
        "nobody",
        "outside",
        "some out of bounds",
        "all in bounds",
        "calm with previous",
    }


def _contacts_brute_force(positions, times, people, velocities, radii, growth, until, overlapping):
    """escape_contacts' figures by the full scan, in numpy: every roll-out step against every person."""
    centres = people[None] + velocities[None] * times[:, None, None]  # (S, N, 2)
    reach = radii + growth * np.minimum(times[:, None], until)  # (S, N)
    offsets = positions[:, :, None, :] - centres[None]  # (K, S, N, 2)
    with np.errstate(invalid="ignore"):
        gap = np.hypot(offsets[..., 0], offsets[..., 1]) - reach[None]  # (K, S, N)
        touched = (gap < 0) & ~overlapping[None, None]
    steps = positions.shape[1]
    first = np.where(touched.any(axis=(1, 2)), touched.any(axis=2).argmax(axis=1), steps)
    return first, gap[:, :, overlapping].min(axis=1), gap[:, -1, overlapping]


def test_escape_contacts_skip_only_free_steps():
    """kernels.escape_contacts looks at a person only up to the roll-out's first contact found so far and skips
    the steps in which a gap cannot close: against the full scan (brute force, numpy) on 400 random fans —
    people who close fast, stand still, grow, have a NaN cap, overlap the robot now; robots that
    stand, creep or run; uneven step times — the same first contacts and gaps, bit for bit."""
    from viapath.compiled import planning as kernels

    rng = np.random.default_rng(31)
    for case in range(400):
        k_count, s_count, n_count = int(rng.integers(1, 12)), int(rng.integers(1, 40)), int(rng.integers(0, 12))
        times = 0.1 * np.arange(1, s_count + 1)
        if case % 5 == 0:
            times = np.cumsum(rng.choice([0.1, 0.1, 0.05, 0.2], s_count))
        heading = rng.uniform(-np.pi, np.pi, (k_count, 1))
        speed = rng.choice([0.0, 0.05, 0.5, 1.5, 4.0], (k_count, 1))
        turn = rng.uniform(-1, 1, (k_count, 1)) * times[None]
        steps = np.stack([np.cos(heading + turn), np.sin(heading + turn)], -1) * (speed * 0.1)[..., None]
        positions = np.ascontiguousarray(np.cumsum(steps, axis=1) + rng.uniform(-1, 1, 2))
        people = rng.uniform(-4, 4, (n_count, 2))
        velocities = rng.normal(0, 1, (n_count, 2)) * rng.choice([0.0, 0.5, 2.0, 5.0], (n_count, 1))
        radii = rng.uniform(0.1, 0.8, n_count)
        growth = rng.choice([0.0, 0.0, 0.1, 0.5, 3.0], n_count)
        until = rng.choice([np.inf, 1.0, 0.3, 2.0], n_count)
        if case % 4 == 0 and n_count:  # someone right at the robot's first position, or just outside it
            j = int(rng.integers(0, n_count))
            people[j] = (
                positions[0, 0]
                + rng.choice([-1, 1]) * (radii[j] + rng.choice([-0.05, 1e-7, 0.02])) * np.array([1.0, 0.0])
                - velocities[j] * times[0]
            )
        start = positions[0, 0] - steps[0, 0]
        overlapping = np.hypot(*(start - people).T) - radii <= 0
        if case % 9 == 0 and not overlapping.all():  # a NaN cap: that person is never touched
            until[rng.choice(np.flatnonzero(~overlapping))] = np.nan
        args = (
            positions,
            np.ascontiguousarray(times),
            np.ascontiguousarray(people),
            np.ascontiguousarray(velocities),
            radii,
            growth,
            until,
            overlapping,
            s_count,
        )
        got = kernels.escape_contacts(*args)
        expected = _contacts_brute_force(*args[:-1])
        np.testing.assert_array_equal(got[0], expected[0], err_msg=f"case {case}: first contact")
        assert _same_bits(got[1], expected[1]) and _same_bits(got[2], expected[2]), f"case {case}: gaps"


def test_escape_kernel_pieces_match_numpy():
    """The escape kernel's pieces against what they stand in for: the squared-distance shortcuts (contact,
    corridor, furthest travel) against hypot on points within a few ulps of the limit or of each other (tiny,
    huge, zero, negative and non-finite values too), the pairwise sum against np.sum along a row (0 to 1100
    terms, zeros of both signs)."""
    from numba import njit

    from viapath.compiled import planning as kernels
    from viapath.compiled.arithmetic import _corridor
    from viapath.compiled.sums import pairwise_sum

    within = njit(
        lambda dx, dy, limits: np.array(
            [kernels._within(dx.flat[i], dy.flat[i], limits.flat[i]) for i in range(dx.size)]
        )
    )
    at_most = njit(
        lambda points, a, b, c, d, limit: np.array(
            [kernels._excess_at_most(points[i, 0], points[i, 1], a, b, c, d, limit) for i in range(points.shape[0])]
        )
    )

    rng = np.random.default_rng(23)
    special = np.array([0.0, -0.0, 1e-300, 1e-170, 1e-150, 1e150, 1e170, 1e300, -0.3, np.inf, -np.inf, np.nan])
    ulps = lambda shape: rng.integers(-4, 5, shape) * 2.0**-52 * rng.choice([1, 1, 1e3, 1e7, 1e9, 1e12], shape)
    for case in range(1500):
        # contacts: hypot(dx, dy) - reach < 0 (escape_contacts' test of the people not overlapped now)
        reach = rng.uniform(0.2, 1.2, 30) * 10.0 ** rng.choice([0, 0, 0, -160, -300, 160], 30)
        if case % 4 == 0:
            reach[rng.integers(0, 30, 3)] = rng.choice(special, 3)
        angle = rng.uniform(0, 2 * np.pi, 30)
        scale = reach * (1.0 + ulps(30))
        dx, dy = scale * np.cos(angle), scale * np.sin(angle)
        if case % 3 == 0:
            dx[rng.integers(0, 30, 4)] = rng.choice(special, 4)
            dy[rng.integers(0, 30, 4)] = rng.choice(special, 4)
        with np.errstate(all="ignore"):
            assert np.array_equal(within(dx, dy, reach), np.hypot(dx, dy) - reach < 0), f"case {case}"
        # the corridor: DesignatedPath.corridor_excess(points) <= limit, points on the capsule's edge grown by
        # the limit (beside the segment and round its ends), near it, and far
        path = PATHS[case % len(PATHS)]
        limit = float(rng.choice([0.0, 1e-9, 0.3, 0.5, 2.0, -0.2, 1e-160, 1e200, np.inf, np.nan]))
        segment = rng.integers(0, len(path.segment_lengths_m), 40)
        along = rng.uniform(-0.3, 1.3, 40) * path.segment_lengths_m[segment]
        side = rng.uniform(0, 2 * np.pi, 40)
        radius = (path.half_widths_m[segment] + (limit if np.isfinite(limit) else 0.5)) * (1.0 + ulps(40))
        foot = (
            path.segment_starts[segment]
            + np.clip(along, 0, path.segment_lengths_m[segment])[:, None] * path.segment_directions[segment]
        )
        points = foot + radius[:, None] * np.stack([np.cos(side), np.sin(side)], 1)
        if case % 5 == 0:
            points[rng.integers(0, 40, 3)] = rng.uniform(-1e3, 1e3, (3, 2))
        with np.errstate(all="ignore"):
            expected = path.corridor_excess(points) <= limit
        assert np.array_equal(at_most(np.ascontiguousarray(points), *_corridor(path), limit), expected), f"case {case}"
        # the furthest travel: np.max(np.hypot(...)) of many offsets within a few ulps of each other
        count = int(rng.integers(1, 60))
        size = float(rng.choice([1.0, 0.01, 1e-150, 1e-300, 1e150, 0.0]))
        angle = rng.uniform(0, 2 * np.pi, count)
        length = size * (1.0 + ulps(count))
        positions = (np.stack([length * np.cos(angle), length * np.sin(angle)], 1) + [0.5, -0.25]).reshape(-1, 1, 2)
        if case % 7 == 0:
            positions[rng.integers(0, count), 0] = rng.choice(special, 2)
        with np.errstate(all="ignore"):
            expected = np.max(np.hypot(positions[..., 0] - 0.5, positions[..., 1] + 0.25))
        assert _same_bits(kernels._furthest(positions, 0.5, -0.25), expected), f"case {case}"
    # two offsets whose squares and hypots are in opposite orders (found by a search): the smaller square has
    # the larger hypot, so the furthest is not simply the hypot of the largest square
    pair = np.array([[[0.8789727257469813, -0.4768720450948255]], [[0.2882984376347223, 0.9575406053308535]]])
    squares, hypots = np.sum(pair[:, 0] ** 2, axis=1), np.hypot(pair[:, 0, 0], pair[:, 0, 1])
    assert squares[0] < squares[1] and hypots[0] > hypots[1]
    assert kernels._furthest(pair, 0.0, 0.0) == hypots[0]
    for count in list(range(140)) + [255, 256, 257, 300, 1031, 1100]:
        rows = rng.normal(0.0, 1.0, (4, count)) * rng.choice([1e-8, 1.0, 1e8], (4, count))
        rows[1] = np.where(rng.random(count) < 0.5, -0.0, 0.0)
        rows[2] = np.where(rng.random(count) < 0.5, rows[2], 0.0)
        expected = np.sum(rows, axis=1)
        got = np.array([0.0 + pairwise_sum(np.ascontiguousarray(row), 0, count) for row in rows])
        assert _same_bits(got, expected)


def test_the_warm_up_reaches_every_whole_step_kernel():
    """precompile's cycles reach the choice and the escape (so `auto` finds every whole-step kernel compiled
    after it), and each whole-step kernel then has a compiled signature."""
    from viapath.compiled import planning as kernels
    from viapath.planning.viapath.planner import precompile, warm_up_crowds

    planner = make_planner(
        "viapath", DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0), nominal_speed_mps=0.2, compute="numpy"
    )
    statuses = []
    for people in warm_up_crowds():
        planner.reset()
        statuses.append(
            planner.plan(Observation(0.0, RobotState(np.zeros(2), 0.0, 0.2, 0.0, 0.25), people)).plan.status
        )
    assert statuses[0] in ("avoid", "slow", "wait") and statuses[1] == "escape"
    assert precompile()
    planner = make_planner(
        "viapath", DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0), nominal_speed_mps=0.2, compute="numba"
    )
    for people in warm_up_crowds():  # in this process: compiled now (or loaded from the cache)
        planner.reset()
        planner.plan(Observation(0.0, RobotState(np.zeros(2), 0.0, 0.2, 0.0, 0.25), people))
    for kernel in (kernels.escape_headings, kernels.escape_scores, kernels.choose):
        assert len(kernel.signatures) == 1  # one signature each: the planner's argument types do not vary


@settings(max_examples=600, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(escape_cases(), st.integers(0, 2**31 - 1))
def test_compiled_escape_with_static_rows_decides_as_numpy(case, seed):
    """A cycle with static geometry runs its candidate tree stepwise, but its escape on the planner's whole-step
    kernels: with some of the crowd turned into static discs (velocity 0, σ 0) the escape decides as the numpy
    reference, and the compiled figures are there to decide with (the stepwise backend has none)."""
    from dataclasses import replace

    from viapath.compiled.arithmetic import STEPWISE, Arithmetic
    from viapath.planning.viapath.escape import escape_fan, stop_or_escape
    from viapath.planning.viapath.planner import escape_step
    from viapath.static import STATIC_ID_BASE

    path_index, robot, positions, velocities, radii, _sigma, options, previous = case
    static = np.random.default_rng(seed).random(len(positions)) < 0.6
    velocities = np.where(static[:, None], 0.0, velocities)
    case = (path_index, robot, positions, velocities, radii, None, options, previous)
    planner, checks, previous = _escape_checks(case)
    ids = np.where(static, STATIC_ID_BASE + np.arange(len(static)) // 3, np.arange(len(static)))
    obstacles = replace(checks.obstacles, ids=ids, static_mask=static)
    checks = replace(checks, obstacles=obstacles, arithmetic=STEPWISE["numba"])
    expected = stop_or_escape(replace(checks, arithmetic=Arithmetic("numpy")), planner.limits, planner.config, previous)
    got = escape_step(checks, planner.limits, planner.config, previous, Arithmetic("numba"))
    assert got.command == expected.command
    assert got.plan.status == expected.plan.status
    assert _same_bits(got.plan.target, expected.plan.target)
    fan = escape_fan(planner.limits, planner.config)
    assert Arithmetic("numba").escape(checks, planner.limits, planner.config, fan, previous) is not None


def test_clear_kernel_gives_the_reference_verdicts():
    """The compiled roll-out check answers as LegChecks.clear (numpy) on random situations and roll-outs, with
    one step placed exactly on an obstacle's limit (where the last bit of a distance decides), and both verdicts
    come up."""
    from tests.planning.test_numpy_shortcuts import _situations
    from viapath.compiled.arithmetic import Arithmetic

    compiled = Arithmetic("numba")
    rng = np.random.default_rng(21)
    verdicts = set()
    for case, (_, checks) in enumerate(_situations(400, seed=31)):
        if len(checks.obstacles) == 0:
            continue
        for kind in range(3):
            steps, dt = int(rng.choice([20, 5, 12])), float(rng.choice([0.1, 0.05]))
            positions = checks.position + np.cumsum(rng.normal(0.0, 0.06, (steps, 2)), axis=0)
            if kind == 2:
                centres_x, centres_y, limit = checks._clear_limits(steps, dt)
                s, j, angle = int(rng.integers(steps)), int(rng.integers(len(checks.obstacles))), rng.uniform(0, 6.3)
                positions[s] = [centres_x[s, j], centres_y[s, j]] + abs(limit[s, j]) * np.array(
                    [np.cos(angle), np.sin(angle)]
                )
            expected = checks.clear(positions, dt)
            got = compiled.clear(positions, dt, checks.position, checks.packed_obstacles())
            assert got is expected, f"case {case}, kind {kind}"
            verdicts.add(expected)
    assert verdicts == {True, False}
    assert Arithmetic("numpy").clear(positions, dt, checks.position, checks.packed_obstacles()) is None
