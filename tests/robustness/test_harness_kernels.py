"""The per-cycle harness compiled (:mod:`viapath.compiled.harness`, extra ``fast``) answers exactly as its numpy
code: the guard's soundness test of the obstacles and its braking test, and the safety inflation, bit for
bit; and the guard's common-case shortcut (``guard._plainly_sound``) lets through only observations the full
inspection would hand on unchanged. Each is checked against the numpy code it replaces
(``viapath.compiled.harness_kernels`` patched to None) on random fields with NaN, infinities, negative, zero,
boundary and too large values sprinkled in."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("numba")

from viapath import compiled, guard
from viapath.observation import Command, MotionLimits, Observation, Obstacles, RobotState
from viapath.planning import base

CONFIG = guard.DEFAULT_CONFIG
# Values at, just inside and just outside every bound of the default configuration, and the IEEE specials.
_ODD = [
    np.nan,
    np.inf,
    -np.inf,
    -0.0,
    0.0,
    -1e-300,
    1e-300,
    -0.1,
    0.3,
    0.5,
    np.nextafter(0.5, 1.0),
    1.0,
    np.nextafter(1.0, 2.0),
    10.0,
    np.nextafter(10.0, 11.0),
    1e6,
    np.nextafter(1e6, 2e6),
    -1e6,
    7.0710678118654755,
]


def _fields(rng, n: int) -> dict:
    """Random obstacle fields of n rows, a few entries replaced by odd values (more often when ``rng`` says so)."""
    fields = {
        "positions": rng.uniform(-8, 8, (n, 2)),
        "velocities": rng.uniform(-1.5, 1.5, (n, 2)),
        "radii": rng.uniform(0.1, 0.5, n),
        "position_sigma": rng.uniform(0, 0.3, n) * (rng.random() < 0.5),
        "velocity_sigma": rng.uniform(0, 0.6, n) * (rng.random() < 0.5),
    }
    for values in fields.values():
        flat = values.reshape(-1)
        for _ in range(rng.integers(0, 3) if flat.size else 0):
            flat[rng.integers(flat.size)] = _ODD[rng.integers(len(_ODD))]
    return fields


def _bits(array: np.ndarray) -> np.ndarray:
    """The float64 bit patterns (equal arrays of equal bits: the same zeros' signs, the same NaNs)."""
    return np.ascontiguousarray(array, dtype=np.float64).view(np.int64)


@pytest.fixture
def numpy_only(monkeypatch):
    """Within the block, the harness runs its numpy code (as without numba installed)."""

    def use_numpy():
        monkeypatch.setattr(guard, "compiled_harness", lambda: None)
        monkeypatch.setattr(base, "compiled_harness", lambda: None)

    return use_numpy


def test_obstacles_sound_agrees_with_the_numpy_reductions(numpy_only):
    rng = np.random.default_rng(0)
    cases = [_fields(rng, int(rng.integers(0, 6))) for _ in range(3000)]
    args = [
        (f["positions"], f["velocities"], f["radii"], f["position_sigma"], f["velocity_sigma"], CONFIG) for f in cases
    ]
    assert compiled.harness_kernels() is not None
    compiled_answers = [guard._obstacles_sound(*a) for a in args]
    numpy_only()
    numpy_answers = [guard._obstacles_sound(*a) for a in args]
    assert compiled_answers == numpy_answers
    assert 0.2 < np.mean(numpy_answers) < 0.8  # both answers well represented


def test_the_braking_test_agrees_with_check_commands_numpy_code(monkeypatch):
    """guard._first_touched compiled and in numpy, on robots among people close enough for the braking
    roll-out to decide: the same obstacle (or none) every time."""
    rng = np.random.default_rng(1)
    limits = MotionLimits()
    cases = []
    for _ in range(3000):
        n = int(rng.integers(1, 6))
        obstacles = Obstacles(rng.uniform(-1.2, 1.2, (n, 2)), np.zeros((n, 2)), rng.uniform(0.1, 0.4, n))
        robot = RobotState(
            rng.uniform(-0.2, 0.2, 2),
            float(rng.uniform(-np.pi, np.pi)),
            float(rng.choice([0.0, rng.uniform(0, 0.6), limits.max_speed_mps])),
            float(rng.uniform(-1.0, 1.0)),
            0.25,
        )
        v, w = float(rng.uniform(0, limits.max_speed_mps)), float(rng.uniform(-1, 1) * limits.max_turn_rate_radps)
        reachable = guard.stopping_distance_m(max(limits.max_speed_mps, robot.speed_mps), limits, CONFIG)
        cases.append((robot, np.asarray(robot.position, dtype=float), v, w, limits, obstacles, 0.25, CONFIG, reachable))
    compiled_answers = [guard._first_touched(*case) for case in cases]
    monkeypatch.setattr(guard, "compiled_harness", lambda: None)
    numpy_answers = [guard._first_touched(*case) for case in cases]
    assert compiled_answers == numpy_answers
    touched = np.array(numpy_answers) >= 0
    assert 0.2 < touched.mean() < 0.8  # both answers well represented


def test_the_compiled_arc_is_kinematics_arc_bit_for_bit():
    from viapath import kinematics

    kernels = compiled.harness_kernels()
    rng = np.random.default_rng(4)
    for _ in range(20000):
        args = (
            *rng.uniform(-5, 5, 2),
            float(rng.uniform(-4, 4)),
            float(rng.uniform(0, 1)),
            float(rng.choice([0.0, 1e-9, -1e-7, rng.uniform(-2, 2)])),
            float(rng.choice([0.02, 0.1])),
        )
        assert kernels._arc(*args) == kinematics._arc(*args)


@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")  # numpy's 0·inf and inf/inf, NaN both ways
def test_inflation_is_the_numpy_inflation_bit_for_bit(numpy_only):
    rng = np.random.default_rng(2)
    cases = []
    for _ in range(2000):
        f = _fields(rng, int(rng.integers(1, 6)))
        settings = {
            "safety_margin_m": float(rng.choice([0.0, 0.05, 0.1])),
            "uncertainty_sigmas": float(rng.choice([0.0, 1.0, 2.0, 2.5])),
            "max_inflation_m": float(rng.choice([0.0, 0.15, 0.3])),
        }
        obstacles = Obstacles(f["positions"], f["velocities"], f["radii"], f["position_sigma"], f["velocity_sigma"])
        cases.append((obstacles, float(rng.choice([0.2, 0.25, 0.3])), settings))
    compiled_rows = [base.Inflation.of(*case) for case in cases]
    numpy_only()
    for case, fast in zip(cases, compiled_rows):
        slow = base.Inflation.of(*case)
        for name in ("obstacle_radii_m", "check_radii", "growth", "growth_until_s"):
            assert np.array_equal(_bits(getattr(fast, name)), _bits(getattr(slow, name))), name


@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")
def test_the_situations_inflation_and_corridor_excess_are_the_numpy_ones_bit_for_bit(numpy_only):
    """Planner.situation's one compiled call (situation_numbers) against Inflation.of and the path's
    corridor_excess on their numpy code: random paths of 1-4 segments, robots inside, on the edge of and far
    outside the corridor, on segment ends and corners."""
    from viapath.path import DesignatedPath
    from viapath.planning import make_planner

    rng = np.random.default_rng(5)
    cases = []
    for _ in range(1500):
        waypoints = np.cumsum(rng.uniform(-4, 4, (int(rng.integers(2, 6)), 2)), axis=0)
        half_widths = rng.choice([0.3, 1.0, 1.5, 2.25], len(waypoints) - 1)
        path = DesignatedPath(waypoints, half_widths_m=half_widths)
        kind = rng.integers(3)
        if kind == 0:  # on a waypoint
            position = waypoints[rng.integers(len(waypoints))].copy()
        elif kind == 1:  # anywhere around
            position = rng.uniform(-12, 12, 2)
        else:  # abreast of the first waypoint, up to the corridor's edge on either side
            (dx, dy), normal = path.segment_directions[0], rng.uniform(-1, 1) * half_widths[0]
            position = waypoints[0] + normal * np.array([-dy, dx])
        f = _fields(rng, int(rng.integers(1, 6)))
        obstacles = Obstacles(
            np.abs(f["positions"]) % 5,
            f["velocities"] % 1,
            np.abs(f["radii"]) % 1 + 0.1,
            np.abs(f["position_sigma"]) % 0.3,
            np.abs(f["velocity_sigma"]) % 0.6,
        )
        planner = make_planner(
            "follow",
            path,
            robot_radius_m=float(rng.choice([0.2, 0.25])),
            uncertainty_sigmas=float(rng.choice([0.0, 2.0])),
            max_inflation_m=float(rng.choice([0.0, 0.15])),
        )
        cases.append((planner, obstacles, position))
    fast = [case[0]._inflation_and_excess(case[1], case[2]) for case in cases]
    numpy_only()
    outside = 0
    for case, (fast_inflation, fast_excess) in zip(cases, fast):
        inflation, excess = case[0]._inflation_and_excess(case[1], case[2])
        assert type(fast_excess) is float and _bits(np.array(fast_excess)) == _bits(np.array(excess))
        for name in ("obstacle_radii_m", "check_radii", "growth", "growth_until_s"):
            assert np.array_equal(_bits(getattr(fast_inflation, name)), _bits(getattr(inflation, name))), name
        outside += excess > 0
    assert 0.2 < outside / len(cases) < 0.9  # both inside and outside the corridor, often


def _observation(rng) -> Observation:
    """Observations of every kind the guard meets: sound, with odd values, with other number types."""
    fields = _fields(rng, int(rng.integers(0, 5)))
    obstacles = Obstacles(
        fields["positions"], fields["velocities"], fields["radii"], fields["position_sigma"], fields["velocity_sigma"]
    )
    state = [0.0, 0.3, 0.2, 0.1, 0.25]  # heading, speed, turn rate, radius (and the time first)
    if rng.random() < 0.5:
        state[rng.integers(len(state))] = _ODD[rng.integers(len(_ODD))] * rng.choice([1.0, 100.0])
    position = rng.uniform(-3, 3, 2)
    kind = rng.integers(4)
    if kind == 1:
        position[rng.integers(2)] = _ODD[rng.integers(len(_ODD))] * 1e6
    elif kind == 2:  # other number types: the shortcut leaves them to the full inspection
        state = [np.float32(v) if i % 2 else int(v) if math.isfinite(v) else v for i, v in enumerate(state)]
    elif kind == 3:
        position = position.astype(np.float32)
    time_s, heading, speed, turn, radius = state
    return Observation(time_s, RobotState(position, heading, speed, turn, radius), obstacles)


def test_the_guards_shortcut_lets_through_only_what_the_full_inspection_hands_on(monkeypatch):
    rng = np.random.default_rng(3)
    observations = [_observation(rng) for _ in range(3000)]
    shortcut = [guard._plainly_sound(o, o.robot, o.obstacles, CONFIG) for o in observations]
    monkeypatch.setattr(guard, "_plainly_sound", lambda *args: False)
    full = [guard.inspect_observation(o) for o in observations]
    plain_types = 0
    for observation, taken, inspection in zip(observations, shortcut, full):
        clean = inspection.observation is observation and not inspection.stop_reasons and not inspection.repairs
        if taken:
            assert clean
        robot = observation.robot
        if (
            all(
                type(v) is float or type(v) is np.float64
                for v in (observation.time_s, robot.heading_rad, robot.speed_mps, robot.turn_rate_radps, robot.radius_m)
            )
            and robot.position.dtype == np.float64
        ):
            plain_types += 1
            assert taken == clean  # floats and float64 arrays: every clean one takes the shortcut
    assert sum(shortcut) > 150 and plain_types > 1000


def test_check_command_hands_back_the_command_it_leaves_alone():
    limits = MotionLimits()
    far = Observation(
        0.0,
        RobotState(np.zeros(2), 0.0, 0.3, 0.0, 0.25),
        Obstacles(np.array([[5.0, 0.0]]), np.zeros((1, 2)), np.array([0.3])),
    )
    command = Command(0.3, -0.2)
    assert guard.check_command(command, far, limits, 0.25) == (command, None, None)
    assert guard.check_command(command, far, limits, 0.25)[0] is command
    clipped = Command(limits.max_speed_mps + 1e-10, 0.0)  # within the tolerance: clipped to the limit
    result = guard.check_command(clipped, far, limits, 0.25)[0]
    assert result is not clipped and result.speed_mps == limits.max_speed_mps
    near = Observation(
        0.0,
        RobotState(np.zeros(2), 0.0, 0.3, 0.0, 0.25),
        Obstacles(np.array([[0.6, 0.0]]), np.zeros((1, 2)), np.array([0.3])),
    )
    assert guard.check_command(Command(0.3, 0.0), near, limits, 0.25)[1] == "guard-brake"


def test_a_harness_that_cannot_load_leaves_the_numpy_code_working(monkeypatch):
    """numba installed but failing (no cache directory it may write, a broken install): the guard warns once
    and runs its numpy code; the planner still plans and the guard still brakes."""
    from viapath import DesignatedPath
    from viapath.planning import make_planner

    monkeypatch.setattr(compiled, "_LOADED", {})
    real_import = compiled._import

    def failing_import(name):
        if name == "viapath.compiled.harness":
            raise RuntimeError("cannot cache function: no locator available")
        return real_import(name)

    monkeypatch.setattr(compiled, "_import", failing_import)
    with pytest.warns(RuntimeWarning, match="using the numpy code"):
        assert compiled.harness_kernels() is None
    assert compiled.harness_kernels() is None  # decided once
    planner = make_planner("follow", DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0), nominal_speed_mps=0.3)
    in_front = Observation(
        0.0,
        RobotState(np.zeros(2), 0.0, 0.3, 0.0, 0.25),
        Obstacles(np.array([[0.6, 0.0]]), np.zeros((1, 2)), np.array([0.3])),
    )
    decision = planner.plan(in_front)
    assert decision.plan.status == "guard-brake" and decision.command.speed_mps == 0.0
