"""The per-cycle checks every planner gets, compiled (:mod:`viapath.guard_checks`, the inflation and situation
numbers of :mod:`viapath.planning.base`), against plain numpy specifications written here: the guard's
soundness test of the obstacles (whole-array reductions), its braking test (a brute force over the drive model's
roll-out, :func:`viapath.kinematics.step`), and the safety inflation and corridor excess, bit for bit; and the
guard's common-case shortcut (``guard._plainly_sound``) lets through only observations the full inspection would
hand on unchanged. On random fields with NaN, infinities, negative, zero, boundary and too large values."""

from __future__ import annotations

import math

import numpy as np

from viapath import guard
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


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Bit for bit where a number (the sign of a zero too), NaN where NaN (a NaN's sign bit is the machine's
    business: the compiled arithmetic and numpy may set it differently)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    nan = np.isnan(a)
    return bool(np.array_equal(nan, np.isnan(b)) and np.array_equal(_bits(a[~nan]), _bits(b[~nan])))


def sound_by_reductions(positions, velocities, radii, position_sigma, velocity_sigma, config) -> bool:
    """The specification: a few whole-array reductions (a NaN fails every comparison and max/min propagate
    it, an infinity every bound, so max <= bound and min >= 0 also say "finite")."""
    if len(positions) == 0:
        return True
    return bool(
        np.max(np.abs(positions)) <= config.max_coordinate_m
        and np.max(np.hypot(velocities[:, 0], velocities[:, 1])) <= config.max_obstacle_speed_mps
        and np.min(radii) >= 0
        and np.max(radii) <= config.max_radius_m
        and np.min(velocity_sigma) >= 0
        and np.max(velocity_sigma) <= config.max_velocity_sigma_mps
        and np.min(position_sigma) >= 0
        and np.max(position_sigma) <= config.max_position_sigma_m
    )


def test_obstacles_sound_is_the_whole_array_reductions():
    rng = np.random.default_rng(0)
    cases = [_fields(rng, int(rng.integers(0, 6))) for _ in range(3000)]
    args = [
        (f["positions"], f["velocities"], f["radii"], f["position_sigma"], f["velocity_sigma"], CONFIG) for f in cases
    ]
    answers = [guard._obstacles_sound(*a) for a in args]
    with np.errstate(invalid="ignore"):
        expected = [sound_by_reductions(*a) for a in args]
    assert answers == expected
    assert 0.2 < np.mean(expected) < 0.8  # both answers well represented


def braking_reference(robot, command, limits, period_s, samples=guard.BRAKING_SAMPLES_PER_PERIOD) -> np.ndarray:
    """The drive model's own roll-out: kinematics.step holding the command, then the stop until at rest."""
    from viapath.kinematics import UnicycleState, step

    dt = period_s / samples
    position = robot.position
    state = UnicycleState(
        float(position[0]), float(position[1]), robot.heading_rad, robot.speed_mps, robot.turn_rate_radps
    )
    points = []
    for _ in range(samples):
        state = step(state, command, limits, dt)
        points.append((state.x, state.y))
    top = max(limits.max_speed_mps, abs(state.speed_mps))
    for _ in range(min(1000, int(np.ceil(top / max(limits.max_accel_mps2 * dt, 1e-9))) + 2)):
        if state.speed_mps <= 1e-12:
            break
        state = step(state, Command.stop(), limits, dt)
        points.append((state.x, state.y))
    return np.array(points)


def first_touched_by_brute_force(robot, position, v, w, limits, obstacles, robot_radius_m, config, reachable_m) -> int:
    """The specification of the braking test: among the obstacles within reach now, the first that some
    sample of the roll-out touches while the first sample is closer to it than the robot is now."""
    offsets = obstacles.positions - position
    distance = np.hypot(offsets[:, 0], offsets[:, 1])
    reach = robot_radius_m + obstacles.radii_m + config.brake_margin_m
    near = distance - reach <= reachable_m
    if not near.any():
        return -1
    swept = braking_reference(robot, Command(v, w), limits, config.control_period_s)
    centres = obstacles.positions[near]
    gaps = np.hypot(*(swept[:, None, :] - centres[None]).transpose(2, 0, 1)) - reach[near][None]
    closer = np.hypot(*(swept[0] - centres).T) < distance[near] - 1e-12
    touches = (gaps.min(axis=0) <= 0) & closer
    return int(np.flatnonzero(near)[np.argmax(touches)]) if touches.any() else -1


def test_the_braking_test_is_the_brute_force_over_the_drive_models_roll_out():
    """guard._first_touched against its brute force, on robots among people close enough for the braking
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
    answers = [guard._first_touched(*case) for case in cases]
    expected = [first_touched_by_brute_force(*case) for case in cases]
    assert answers == expected
    touched = np.array(expected) >= 0
    assert 0.2 < touched.mean() < 0.8  # both answers well represented


def test_the_compiled_arc_is_kinematics_arc_bit_for_bit():
    from viapath import guard_checks, kinematics

    rng = np.random.default_rng(4)
    for _ in range(20000):
        args = (
            *rng.uniform(-5, 5, 2),
            float(rng.uniform(-4, 4)),
            float(rng.uniform(0, 1)),
            float(rng.choice([0.0, 1e-9, -1e-7, rng.uniform(-2, 2)])),
            float(rng.choice([0.02, 0.1])),
        )
        assert guard_checks._arc(*args) == kinematics._arc(*args)


def inflation_by_numpy(obstacles, robot_radius_m, settings) -> tuple[np.ndarray, ...]:
    """The specification of the inflation, in numpy: radius + margin + k σ_p (the robot's radius added after
    the obstacle's), growth k σ_v, and max_inflation / growth where it grows (inf elsewhere)."""
    margin, k = settings["safety_margin_m"], settings["uncertainty_sigmas"]
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):  # 0 * inf, inf / inf: NaN both ways
        position_term = k * obstacles.position_sigma_m
        growth = k * obstacles.velocity_sigma_mps
        until = np.where(growth > 0, settings["max_inflation_m"] / growth, np.inf)
        return (
            obstacles.radii_m + margin + position_term,
            obstacles.radii_m + robot_radius_m + margin + position_term,
            growth,
            until,
        )


_ROWS = ("obstacle_radii_m", "check_radii", "growth", "growth_until_s")


def test_inflation_is_the_numpy_inflation_bit_for_bit():
    rng = np.random.default_rng(2)
    for _ in range(2000):
        f = _fields(rng, int(rng.integers(1, 6)))
        settings = {
            "safety_margin_m": float(rng.choice([0.0, 0.05, 0.1])),
            "uncertainty_sigmas": float(rng.choice([0.0, 1.0, 2.0, 2.5])),
            "max_inflation_m": float(rng.choice([0.0, 0.15, 0.3])),
        }
        obstacles = Obstacles(f["positions"], f["velocities"], f["radii"], f["position_sigma"], f["velocity_sigma"])
        radius = float(rng.choice([0.2, 0.25, 0.3]))
        inflation = base.Inflation.of(obstacles, radius, settings)
        for name, expected in zip(_ROWS, inflation_by_numpy(obstacles, radius, settings)):
            assert _same(getattr(inflation, name), expected), name


def test_the_situations_inflation_and_corridor_excess_are_the_numpy_ones_bit_for_bit():
    """Planner.situation's one compiled call (situation_numbers) against the numpy inflation and the path's
    own corridor_excess: random paths of 1-4 segments, robots inside, on the edge of and far outside the
    corridor, on segment ends and corners."""
    from viapath.path import DesignatedPath
    from viapath.planning import make_planner

    rng = np.random.default_rng(5)
    outside = 0
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
        f = _fields(rng, int(rng.integers(0, 6)))
        with np.errstate(invalid="ignore"):  # inf % x is NaN
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
        inflation, excess = planner._inflation_and_excess(obstacles, position)
        expected = float(path.corridor_excess(position[None])[0])  # the path's array code
        assert type(excess) is float and _bits(np.array(excess)) == _bits(np.array(expected))
        rows = inflation_by_numpy(obstacles, planner.robot_radius_m, planner.settings)
        for name, row in zip(_ROWS, rows):
            assert _same(getattr(inflation, name), row), name
        outside += excess > 0
    assert 0.2 < outside / 1500 < 0.9  # both inside and outside the corridor, often


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
