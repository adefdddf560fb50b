"""The numpy path's shortcuts for its slowest cycles (docs/CHANGELOG-speed.md, "numpy p99 (wave 6)") change no value.

Each test holds a rewritten function to its earlier form, kept here verbatim as the reference, bit for
bit, on seeded random situations: the robot near the path (three paths), 0-14 people around it, with
and without uncertainty, some overlapping the robot, so that both the escape's terms (time to contact,
separation) and roll-outs that pass, fail and turn on the spot come up.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from tests.test_kinematics import _rollout_reference
from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.geometry import wrap_angle
from viapath.kinematics import UnicycleState
from viapath.observation import Command
from viapath.planning import make_planner
from viapath.planning.base import Plan
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.escape import escape_scores
from viapath.planning.viapath.follow import can_follow
from viapath.planning.viapath.planner import ViaPathConfig

PATHS = [
    DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.0),
    DesignatedPath([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]], half_width_m=1.2),
    DesignatedPath([[0.0, 0.0], [2.5, 0.5], [5.0, -0.5], [8.0, 0.0]], half_width_m=1.5),
]


def _situations(count: int, seed: int):
    """(planner, checks) of ``count`` random situations (a new planner per path, reset each time)."""
    rng = np.random.default_rng(seed)
    planners = [make_planner("viapath", path, nominal_speed_mps=0.2, backend="numpy") for path in PATHS]
    for case in range(count):
        planner = planners[case % len(PATHS)]
        n = int(rng.integers(0, 15))
        robot = np.array([rng.uniform(-0.5, 3.0), rng.uniform(-1.3, 1.3)])
        distance = rng.uniform(0.2 if case % 4 == 0 else 0.6, 5.0, n)
        bearing = rng.uniform(-np.pi, np.pi, n)
        positions = robot + np.stack([distance * np.cos(bearing), distance * np.sin(bearing)], 1)
        velocities = rng.uniform(-1.2, 1.2, (n, 2))
        sigma = rng.uniform(0.0, 0.1, n) if case % 2 else None
        observation = Observation(
            0.0,
            RobotState(robot, rng.uniform(-np.pi, np.pi), rng.uniform(0, 0.5), rng.uniform(-1, 1)),
            Obstacles(
                positions, velocities, rng.uniform(0.2, 0.35, n), position_sigma_m=sigma, velocity_sigma_mps=sigma
            ),
        )
        planner.reset()
        situation = planner.situation(observation)
        yield planner, LegChecks.of(situation, planner.config, planner.subgoals, planner.subgoal_policy, 0.25)


def _same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind == "f" and a.dtype == b.dtype and a.shape == b.shape:
        return bool(np.array_equal(a.view(np.int64), b.view(np.int64)))
    return a.dtype == b.dtype and np.array_equal(a, b)


# -- the escape ------------------------------------------------------------------------------------


def _escape_scores_reference(checks, limits, config, previous=None):
    """:func:`viapath.planning.viapath.escape.escape_scores`' numpy path as first written."""
    position = checks.position
    top = min(max(config.speeds), limits.max_speed_mps) if config.calm_escape else limits.max_speed_mps
    speeds = np.unique(np.concatenate([[0.0], np.minimum(config.speeds, top), [top]]))
    turns = np.linspace(-limits.max_turn_rate_radps, limits.max_turn_rate_radps, 9)
    commands = np.stack([grid.ravel() for grid in np.meshgrid(speeds, turns)], axis=1)
    dt = config.escape_dt_s
    steps = max(1, int(round(config.escape_s / dt)))
    state = UnicycleState(
        float(position[0]),
        float(position[1]),
        float(checks.heading_rad),
        float(checks.speed_mps),
        float(checks.turn_rate_radps),
    )
    positions = _rollout_reference(state, commands, limits, dt, steps)  # (K, S, 2)
    times = dt * np.arange(1, steps + 1)
    excess = checks.path.corridor_excess(positions.reshape(-1, 2)).reshape(len(commands), steps)
    inside = np.all(excess <= checks.corridor_tolerance_m, axis=1)
    within_bound = np.max(excess, axis=1) <= max(config.escape_max_excess_m, checks.corridor_tolerance_m)

    horizon = steps * dt
    travel = float(np.max(np.hypot(*(positions - position).reshape(-1, 2).T)))
    obstacles = checks.obstacles
    gap_all = np.hypot(*(position - obstacles.positions).T) - checks.check_radii
    growth_all = checks.growth * np.minimum(horizon, checks.growth_until_s)
    near = gap_all - growth_all - np.hypot(*obstacles.velocities.T) * horizon - travel <= 0
    positions_obs, velocities_obs = obstacles.positions[near], obstacles.velocities[near]
    gap_now = gap_all[near]
    overlapping = gap_now <= 0
    centres = positions_obs[None] + velocities_obs[None] * times[:, None, None]  # (S, N, 2)
    reach = checks.check_radii[near] + checks.growth[near] * np.minimum(times[:, None], checks.growth_until_s[near])
    offset = positions[:, :, None, :] - centres[None]
    gap = np.hypot(offset[..., 0], offset[..., 1]) - reach[None]  # (K, S, N)
    touching = (gap < 0) & ~overlapping
    first = np.where(touching.any(axis=1), np.argmax(touching, axis=1), steps)  # (K, N)
    time_to_contact = np.min(first, axis=1, initial=steps) * dt
    if overlapping.any():
        gap_min, gap_last = np.min(gap[..., overlapping], axis=1), gap[:, -1, overlapping]
        deeper = gap_min - gap_now[overlapping]
        still_inside = gap_last
        separation = np.sum(np.minimum(deeper, 0.0) + np.minimum(still_inside, 0.0), axis=1)
    else:
        separation = np.zeros(len(commands))
    toward = checks.subgoal - position
    toward = toward / max(float(np.hypot(*toward)), 1e-9)
    # The one line changed since the first form (wave 7): the product written out, as escape.py now has it;
    # ``@`` went to BLAS, whose kernels differ in whether they fuse the multiply-add (episodes unchanged).
    ends = positions[:, -1]
    progress = ((ends[:, 0] - position[0]) * toward[0] + (ends[:, 1] - position[1]) * toward[1]) / config.escape_s
    free = time_to_contact >= steps * dt
    score = (
        1e2 * separation
        + 20.0 * free
        + 2.0 * inside
        + time_to_contact
        - np.where(free, 0.005, 0.5) * commands[:, 0]
        + 0.01 * progress
    )
    if config.calm_escape and previous is not None:
        change = (
            np.abs(commands[:, 0] - previous.speed_mps) / max(top, 1e-9)
            + np.abs(commands[:, 1] - previous.turn_rate_radps) / limits.max_turn_rate_radps
        )
        score = score - config.escape_continuity_s * np.minimum(change, 1.0)
    score = np.where(within_bound | (commands[:, 0] == 0.0), score, -np.inf)
    return commands, positions[:, -1], score


def test_escape_scores_are_bit_for_bit_the_first_form():
    """1 200 situations (with and without last cycle's escape command, with and without a calm escape)."""
    rng = np.random.default_rng(3)
    overlapped = contact = 0
    hasty = ViaPathConfig(calm_escape=False)
    for case, (planner, checks) in enumerate(_situations(1200, seed=11)):
        config = planner.config if case % 5 else hasty
        previous = Command(*rng.uniform([0.0, -2.0], [0.5, 2.0])) if case % 3 == 0 else None
        got = escape_scores(checks, planner.limits, config, previous)
        expected = _escape_scores_reference(checks, planner.limits, config, previous)
        assert all(_same_bits(a, b) for a, b in zip(got, expected)), f"case {case}"
        gaps = np.hypot(*(checks.position - checks.obstacles.positions).T) - checks.check_radii
        overlapped += bool(np.any(gaps <= 0))
        contact += bool(np.any(expected[2][np.isfinite(expected[2])] < 20.0))
    assert overlapped > 100 and contact > 100  # both terms came up


def test_touching_is_hypot_minus_reach_below_zero():
    """The escape's contact test without hypot where the squared distance is certain: against
    ``np.hypot(dx, dy) - reach < 0`` on 2 000 batches of offsets on the reach's circle to within a few ulps
    (where only hypot can tell), near it, far inside and outside, with reaches tiny (squares underflow),
    huge (squares overflow), zero, negative, infinite and NaN, and offsets NaN, infinite and -0.0."""
    from viapath.planning.viapath.escape import touching

    rng = np.random.default_rng(9)
    special = np.array([0.0, -0.0, 1e-300, 1e-170, 1e-150, 1e150, 1e170, 1e300, -0.3, np.inf, -np.inf, np.nan])
    for case in range(2000):
        reach = rng.uniform(0.2, 1.2, (6, 5)) * 10.0 ** rng.choice([0, 0, 0, -160, -300, 160], (6, 5))
        if case % 4 == 0:
            reach.flat[rng.integers(0, reach.size, 3)] = rng.choice(special, 3)
        angle = rng.uniform(0, 2 * np.pi, (7, 6, 5))
        scale = reach * (1.0 + rng.integers(-4, 5, (7, 6, 5)) * 2.0**-52 * rng.choice([1, 1, 1e3, 1e7, 1e9, 1e12]))
        dx, dy = scale * np.cos(angle), scale * np.sin(angle)
        if case % 3 == 0:
            dx.flat[rng.integers(0, dx.size, 4)] = rng.choice(special, 4)
            dy.flat[rng.integers(0, dy.size, 4)] = rng.choice(special, 4)
        with np.errstate(all="ignore"):
            expected = np.hypot(dx, dy) - reach < 0
            got = touching(dx, dy, reach)
        assert np.array_equal(got, expected), f"case {case}"
    # and exactly on the circle: hypot decides
    reach = np.array([0.5])
    assert not touching(np.array([0.5]), np.array([0.0]), reach)[0]
    assert touching(np.array([np.nextafter(0.5, 0)]), np.array([0.0]), reach)[0]


# -- the roll-outs of candidates -------------------------------------------------------------------


def _clear_reference(checks, positions, dt):
    """:meth:`LegChecks.clear` as first written."""
    if len(checks.obstacles) == 0:
        return True
    times = dt * np.arange(1, len(positions) + 1)[:, None]
    obstacles = checks.obstacles
    centres = obstacles.positions[None] + obstacles.velocities[None] * times[..., None]
    reach = checks.check_radii + checks.growth * np.minimum(times, checks.growth_until_s)
    distance = np.hypot(*(positions[:, None, :] - centres).transpose(2, 0, 1))
    now = np.hypot(*(checks.position - obstacles.positions).T)
    return bool(np.all(distance >= np.minimum(reach, now - 1e-3)))


def _can_follow_reference(plan, checks, limits, config):
    """:func:`can_follow` as first written (every roll-out made, none remembered)."""
    offset = plan.target - checks.position
    heading_error = abs(float(wrap_angle(math.atan2(offset[1], offset[0]) - checks.heading_rad)))
    speed_change = abs(plan.speed_mps - checks.speed_mps)
    if np.hypot(*offset) < 1e-6 or (
        heading_error <= config.rollout_heading_rad and speed_change <= limits.max_accel_mps2 * config.rollout_dt_s * 2
    ):
        return True
    dt = config.rollout_dt_s
    steps = max(1, int(round(config.rollout_s / dt)))
    state = UnicycleState(
        float(checks.position[0]),
        float(checks.position[1]),
        float(checks.heading_rad),
        checks.speed_mps,
        checks.turn_rate_radps,
    )
    positions = checks.backend.track(state, plan.target, plan.speed_mps, limits, dt, steps, config.heading_gain)
    if not _clear_reference(checks, positions, dt):
        return False
    if np.all(checks.inside(positions)):
        return True
    turn_s = heading_error / limits.max_turn_rate_radps + 1.0
    standing = np.repeat(checks.position[None], max(1, int(np.ceil(turn_s / dt))), axis=0)
    if heading_error > config.turn_in_place_min_rad and _clear_reference(checks, standing, dt):
        plan.extras["turn_in_place"] = True
        return True
    return False


def test_clear_is_bit_for_bit_the_first_form():
    """The obstacles' part of :meth:`LegChecks.clear` is made once per step count and cycle: its arrays
    against the first form's, bit for bit, and the verdicts of random roll-outs against the first form's:
    near the people (so that both verdicts come up) and with one step exactly on a person's limit (where
    a difference in the last bit of a distance would change the verdict)."""
    rng = np.random.default_rng(5)
    verdicts = set()
    for case, (_, checks) in enumerate(_situations(600, seed=12)):
        for kind in range(4):
            steps, dt = int(rng.choice([20, 5, 12])), float(rng.choice([0.1, 0.1, 0.05]))
            positions = checks.position + np.cumsum(rng.normal(0.0, 0.06, (steps, 2)), axis=0)
            if len(checks.obstacles):
                obstacles = checks.obstacles
                times = dt * np.arange(1, steps + 1)[:, None]
                centres = obstacles.positions[None] + obstacles.velocities[None] * times[..., None]
                reach = checks.check_radii + checks.growth * np.minimum(times, checks.growth_until_s)
                limit = np.minimum(reach, np.hypot(*(checks.position - obstacles.positions).T) - 1e-3)
                cached = checks._clear_limits(steps, dt)
                for a, b in zip(cached, (centres[..., 0], centres[..., 1], limit)):
                    np.testing.assert_array_equal(a, b)
                if kind == 3:  # one step on the boundary of one person's limit
                    s, j, angle = int(rng.integers(steps)), int(rng.integers(len(obstacles))), rng.uniform(0, 2 * np.pi)
                    positions[s] = centres[s, j] + abs(limit[s, j]) * np.array([np.cos(angle), np.sin(angle)])
            expected = _clear_reference(checks, positions, dt)
            assert checks.clear(positions, dt) is expected, f"case {case}"
            verdicts.add(expected)
    assert verdicts == {True, False}


def test_can_follow_remembers_only_what_it_would_compute_again():
    """Plans of a cycle towards random targets, many sharing target and speed (as slow/wait candidates
    and chains through one via point do): each verdict and turn-in-place mark equal those of the first
    form, which rolls every one out afresh."""
    rng = np.random.default_rng(8)
    kinds = set()
    for case, (planner, checks) in enumerate(_situations(500, seed=13)):
        fresh = replace(checks)  # the same checks, nothing remembered
        targets = checks.position + rng.uniform(-2.5, 2.5, (3, 2))
        speeds = rng.choice([0.0, 0.1, 0.2, 0.3, 0.5], 3)
        for _ in range(8):
            target, speed = targets[rng.integers(0, 3)], float(speeds[rng.integers(0, 3)])
            plan, reference = (Plan("avoid", speed, target.copy()) for _ in range(2))
            got = can_follow(plan, checks, planner.limits, planner.config)
            expected = _can_follow_reference(reference, fresh, planner.limits, planner.config)
            assert got is expected and plan.extras == reference.extras, f"case {case}"
            kinds.add((expected, bool(reference.extras.get("turn_in_place"))))
    assert kinds == {(True, False), (True, True), (False, False)}  # passed, turned on the spot, failed


# -- the leg checks and via points of the candidate tree -------------------------------------------


def _via_options_reference(
    starts,
    start_times,
    speeds,
    obstacle_positions,
    obstacle_velocities,
    via_radii,
    growth,
    growth_until_s,
    envelope_m,
    max_time_s,
):
    """:func:`viapath.geometry.via_options` as first written."""
    from viapath.geometry import VIA_SIDES, tangent_vectors, via_times

    velocity = obstacle_velocities
    centre_now = obstacle_positions + velocity * start_times[:, None]
    reach_time = np.hypot(*(centre_now - starts).T) / speeds
    passing_time = np.minimum(start_times + reach_time, growth_until_s)
    radius = via_radii + growth * passing_time + envelope_m
    distance = np.hypot(*(centre_now - starts).T)
    radius = np.maximum(np.minimum(radius, 0.98 * distance), 0.0)
    w, valid = tangent_vectors(starts[:, None, :], centre_now[:, None, :], radius[:, None], VIA_SIDES[None, :2])
    t_early, t_late = via_times(w, velocity[:, None, :], speeds[:, None])
    t_via = np.concatenate([t_early, t_late], axis=1)
    w = np.concatenate([w, w], axis=1)
    ok = np.broadcast_to(valid, t_early.shape)
    ok = np.concatenate([ok, ok], axis=1) & (t_via <= max_time_s)
    pair, option = np.nonzero(ok)
    t_k = t_via[pair, option]
    leg_velocity = (w[pair, option] + velocity[pair] * t_k[:, None]) / t_k[:, None]
    via = starts[pair] + leg_velocity * t_k[:, None]
    return pair, option, t_k, leg_velocity, via


def _legs_first_contact_reference(
    starts,
    start_times,
    velocities,
    durations,
    obstacle_positions,
    obstacle_velocities,
    radii,
    growth=0.0,
    growth_until_s=np.inf,
    leg_radii_m=None,
):
    """:func:`viapath.geometry.legs_first_contact` as first written (with its ``_first_contact``)."""

    def first_contact(px, py, vx, vy, radius, growth, duration):
        if np.any(growth):
            a = vx * vx + vy * vy - growth * growth
            b = px * vx + py * vy - radius * growth
        else:
            a = vx * vx + vy * vy
            b = px * vx + py * vy
        c = px * px + py * py - radius * radius
        discriminant = b * b - a * c
        denominator = np.sqrt(np.maximum(discriminant, 0.0)) - b
        ok = (discriminant >= 0) & (denominator > 0)
        tau = c / np.where(ok, denominator, 1.0)
        tau = np.where(ok & (tau <= duration), tau, np.inf)
        return np.where(c <= 0, 0.0, tau)

    if leg_radii_m is not None:
        radii = np.asarray(radii, dtype=float)[None, :] + np.asarray(leg_radii_m, dtype=float)[:, None]
    t0 = np.asarray(start_times, dtype=float)[:, None]
    duration = np.asarray(durations, dtype=float)[:, None]
    growth = np.asarray(growth, dtype=float)
    ox, oy = obstacle_positions[:, 0], obstacle_positions[:, 1]
    ovx, ovy = obstacle_velocities[:, 0], obstacle_velocities[:, 1]
    px = starts[:, 0:1] - (ox + ovx * t0)
    py = starts[:, 1:2] - (oy + ovy * t0)
    vx = velocities[:, 0:1] - ovx
    vy = velocities[:, 1:2] - ovy
    until = np.asarray(growth_until_s, dtype=float)
    if not np.any(growth) or not np.any(np.isfinite(until)):
        return first_contact(px, py, vx, vy, radii + growth * t0, growth, duration)
    cone_duration = np.clip(until - t0, 0.0, duration)
    early = first_contact(
        px, py, vx, vy, radii + growth * np.minimum(t0, until), np.where(until > t0, growth, 0.0), cone_duration
    )
    full_growth = growth * np.where(np.isfinite(until), until, 0.0)
    late = first_contact(
        px + vx * cone_duration, py + vy * cone_duration, vx, vy, radii + full_growth, 0.0, duration - cone_duration
    )
    late = np.where(t0 + duration >= until, late + cone_duration, np.inf)
    return np.where(np.isfinite(early), early, late)


def test_via_options_and_leg_contacts_are_bit_for_bit_the_first_form():
    """Random nodes (some on or inside an obstacle's disc, some at rest relative to it) against random
    people, cones growing or not, capped or not, with and without a braking envelope: the via options
    and each leg's first contact (of the legs to those via points and of random legs) bit for bit."""
    from viapath.geometry import legs_first_contact, via_options

    rng = np.random.default_rng(21)
    options = contacts = 0
    for case in range(1500):
        pairs, n = int(rng.integers(1, 30)), int(rng.integers(1, 12))
        starts = rng.uniform(-3, 3, (pairs, 2))
        times = rng.uniform(0, 4, pairs) * (case % 3 > 0)
        speeds = rng.choice([0.1, 0.2, 0.3, 0.5], pairs)
        positions = rng.uniform(-4, 4, (pairs, 2))
        if case % 7 == 0:
            positions[: pairs // 2] = starts[: pairs // 2]  # a node on the obstacle
        velocities = rng.uniform(-1.2, 1.2, (pairs, 2)) * (case % 11 > 0)
        radii = rng.uniform(0.4, 0.8, pairs)
        growth = rng.uniform(0, 0.2, pairs) * (case % 2)
        until = rng.choice([np.inf, 1.5, 3.0], pairs)
        envelope = rng.uniform(0, 0.3, pairs) * (case % 5 == 0)
        arguments = (starts, times, speeds, positions, velocities, radii, growth, until, envelope, 30.0)
        got, expected = via_options(*arguments), _via_options_reference(*arguments)
        assert all(_same_bits(a, b) for a, b in zip(got, expected)), f"case {case}"
        options += len(expected[0])

        people = (
            rng.uniform(-4, 4, (n, 2)),
            rng.uniform(-1.2, 1.2, (n, 2)),
            rng.uniform(0.4, 0.8, n),
            rng.uniform(0, 0.2, n) * (case % 2),
            rng.choice([np.inf, 1.5, 3.0], n) if case % 4 else np.inf,
        )
        pair = expected[0]
        legs = [
            (starts[pair], times[pair], expected[3], expected[2]),
            (starts, times, rng.uniform(-0.5, 0.5, (pairs, 2)), rng.uniform(0, 8, pairs)),
        ]
        for leg in legs:
            leg_radii = rng.uniform(0, 0.3, len(leg[0])) if case % 3 == 0 else None
            got = legs_first_contact(*leg, *people, leg_radii)
            expected_contact = _legs_first_contact_reference(*leg, *people, leg_radii)
            assert _same_bits(got, expected_contact), f"case {case}"
            contacts += int(np.isfinite(expected_contact).sum())
    assert options > 5000 and contacts > 5000


# -- the corridor ----------------------------------------------------------------------------------


def _segment_geometry_reference(path, points):
    """:meth:`DesignatedPath._segment_geometry` as first written."""
    rel = points[..., None, :] - path.segment_starts
    along = np.sum(rel * path.segment_directions, axis=-1)
    along_clamped = np.clip(along, 0.0, path.segment_lengths_m)
    closest = path.segment_starts + along_clamped[..., None] * path.segment_directions
    offset = points[..., None, :] - closest
    return along, along_clamped, np.hypot(offset[..., 0], offset[..., 1])


def test_segment_geometry_is_the_first_form():
    """Few and many points (the escape's 1 620), in 1-D and 2-D batches, some on the waypoints, some with
    coordinates of -0.0, on the three paths: the distances bit for bit, the arc positions equal (np.clip
    and np.sum may give a zero another sign), and so every corridor figure the planner uses."""
    rng = np.random.default_rng(4)
    for case in range(600):
        path = PATHS[case % len(PATHS)]
        shape = [(1,), (20,), (70,), (1620,), (30, 12), (3, 40)][case % 6]
        points = rng.uniform(-3, 9, (*shape, 2))
        flat = points.reshape(-1, 2)
        flat[: len(flat) // 10] = path.waypoints[rng.integers(0, len(path.waypoints), len(flat) // 10)]
        flat[-3:] *= -0.0 if case % 2 else 1.0
        got, expected = path._segment_geometry(points), _segment_geometry_reference(path, points)
        assert _same_bits(got[2], expected[2]), f"case {case}"
        assert np.array_equal(got[0], expected[0]) and np.array_equal(got[1], expected[1]), f"case {case}"
        excess = np.min(expected[2] - path.half_widths_m, axis=-1)
        assert _same_bits(path.corridor_excess(points), excess), f"case {case}"


def _legs_inside_reference(path, starts, ends, spacing_m, tolerance_m):
    """:meth:`DesignatedPath.legs_inside` as first written (its ends in two passes)."""
    starts = np.asarray(starts, dtype=float).reshape(-1, 2)
    ends = np.asarray(ends, dtype=float).reshape(-1, 2)
    tolerance = np.broadcast_to(np.asarray(tolerance_m, dtype=float), (len(starts),))
    if len(starts) == 0:
        return np.zeros(0, dtype=bool)
    start_in = _segment_geometry_reference(path, starts)[2] - path.half_widths_m <= tolerance[:, None]
    end_in = _segment_geometry_reference(path, ends)[2] - path.half_widths_m <= tolerance[:, None]
    inside = np.any(start_in & end_in, axis=1)
    unresolved = np.flatnonzero(~inside & start_in.any(axis=1) & end_in.any(axis=1))
    if len(unresolved):
        a, b = starts[unresolved], ends[unresolved]
        longest = float(np.max(np.hypot(*(b - a).T)))
        fractions = np.linspace(0.0, 1.0, max(2, int(np.ceil(longest / spacing_m)) + 1))
        samples = a[:, None, :] + fractions[None, :, None] * (b - a)[:, None, :]
        excess = np.min(_segment_geometry_reference(path, samples)[2] - path.half_widths_m, axis=-1)
        inside[unresolved] = np.all(excess <= tolerance[unresolved, None], axis=1)
    return inside


def test_legs_inside_is_the_first_form():
    """Legs within a capsule, across junctions (sampled), leaving the corridor, with ends on its edge (the
    tolerance decides), 0 to 100 legs, per-leg tolerances or one: the verdicts of the first form."""
    rng = np.random.default_rng(10)
    verdicts = set()
    for case in range(900):
        path = PATHS[case % len(PATHS)]
        n = int(rng.integers(0, 100))
        starts, ends = rng.uniform(-2, 9, (n, 2)), rng.uniform(-2, 9, (n, 2))
        if n and case % 3 == 0:  # ends on the corridor's edge
            segment = rng.integers(0, len(path.segment_lengths_m), n)
            normal = path.segment_directions[segment] @ np.array([[0.0, 1.0], [-1.0, 0.0]])
            ends = (
                path.segment_starts[segment]
                + rng.uniform(0, 1, (n, 1)) * path.segment_vectors[segment]
                + path.half_widths_m[segment, None] * normal
            )
        tolerance = rng.choice([1e-9, 0.0, 0.2]) if case % 2 else rng.uniform(-0.1, 0.3, n)
        got = path.legs_inside(starts, ends, 0.05, tolerance)
        expected = _legs_inside_reference(path, starts, ends, 0.05, tolerance)
        assert np.array_equal(got, expected), f"case {case}"
        verdicts |= set(expected.tolist())
    assert verdicts == {True, False}


def test_wrap_angle_of_one_angle_is_that_of_an_array():
    """:func:`viapath.geometry.wrap_angle` takes one angle (a float or np.float64) with a float's ``%``: bit for
    bit what np.mod gives in an array, on 200 000 angles (many turns, tiny, huge, on ±pi and 2 pi, inf, NaN)."""
    rng = np.random.default_rng(17)
    angles = np.concatenate(
        [
            rng.uniform(-20, 20, 150_000),
            rng.uniform(-1e9, 1e9, 40_000),
            rng.uniform(-1e-300, 1e-300, 10_000),
            [
                np.pi,
                -np.pi,
                0.0,
                -0.0,
                3 * np.pi,
                -3 * np.pi,
                np.nextafter(np.pi, 4),
                np.nextafter(-np.pi, -4),
                2 * np.pi,
                -2 * np.pi,
                np.inf,
                -np.inf,
                np.nan,
            ],
        ]
    )
    with np.errstate(invalid="ignore"):
        expected = wrap_angle(angles)
        for kind in (float, np.float64):
            got = np.array([wrap_angle(kind(angle)) for angle in angles])
            assert _same_bits(got, expected), kind


def test_first_leg_is_where_the_plan_first_heads():
    """The planner asks can_follow's verdict before making a candidate's plan (:meth:`Candidates.first_leg`): the
    target must be the plan's as first made, its polyline's second point (the subgoal at the slow speed for
    a slow/wait candidate), bit for bit, for every candidate of 400 situations."""
    from viapath.planning.viapath.candidates import RootLegs, grow

    kinds = set()
    for planner, checks in _situations(400, seed=14):
        speeds, nominal_index = planner.speed_set(checks.speed_mps)
        candidates = grow(checks, RootLegs.of(checks, speeds, nominal_index), planner.config)
        for k in range(len(candidates) if candidates is not None else 0):
            target, speed = candidates.first_leg(k)
            if candidates.slow_s[k] > 0:
                expected = (checks.subgoal, float(candidates.slow_speed_mps[k]))
            else:
                expected = (candidates.polyline(k)[1], float(candidates.speed_mps[k]))
            assert _same_bits(target, expected[0]) and _same_bits(speed, expected[1])
            kinds.add("slow" if candidates.slow_s[k] > 0 else len(candidates.polyline(k)))
    assert {"slow", 2, 3, 4} <= kinds  # slow/wait, straight, one and two via points


def test_clear_in_parts_is_clear_of_the_whole():
    """The numpy roll-out checks its first half before rolling out the rest (``after_steps``, ``of_steps``): the
    two verdicts together must be the whole roll-out's, split anywhere, with one step exactly on a person's limit
    in a quarter of the cases (600 situations)."""
    rng = np.random.default_rng(18)
    verdicts = set()
    for case, (_, checks) in enumerate(_situations(600, seed=15)):
        steps, dt = int(rng.choice([20, 7, 12])), float(rng.choice([0.1, 0.05]))
        positions = checks.position + np.cumsum(rng.normal(0.0, 0.06, (steps, 2)), axis=0)
        if len(checks.obstacles) and case % 4 == 0:
            centres_x, centres_y, limit = checks._clear_limits(steps, dt)
            s, j, angle = int(rng.integers(steps)), int(rng.integers(len(checks.obstacles))), rng.uniform(0, 2 * np.pi)
            positions[s] = (centres_x[s, j], centres_y[s, j]) + abs(limit[s, j]) * np.array(
                [np.cos(angle), np.sin(angle)]
            )
        whole = _clear_reference(checks, positions, dt)
        split = int(rng.integers(0, steps + 1))
        fresh = replace(checks)  # nothing remembered: the parts make their rows from the whole roll-out's
        parts = fresh.clear(positions[:split], dt, of_steps=steps) and fresh.clear(
            positions[split:], dt, after_steps=split, of_steps=steps
        )
        assert parts is whole, f"case {case}"
        verdicts.add(whole)
    assert verdicts == {True, False}


def test_tree_columns_are_the_pieces_concatenated():
    """The candidate tree's columns, filled in place and grown when full, are its pieces concatenated (as
    the tree first kept them), bit for bit; columns read earlier keep their values (a small capacity, so that
    it grows several times; a cycle rarely reaches the default)."""
    from viapath.planning.viapath.candidates import _Tree, _ways

    rng = np.random.default_rng(19)
    tree, pieces, reads = _Tree(capacity=3), [], []
    for count in (2, 0, 5, 1, 9, 4):
        piece = dict(
            position=rng.normal(size=(count, 2)),
            time_s=rng.uniform(0, 3, count),
            speed=rng.uniform(0, 1, count),
            parent=rng.integers(-1, 5, count),
            length_m=rng.uniform(0, 9, count),
            first_direction=rng.normal(size=(count, 2)),
            way=_ways(count, -2, 1, rng.integers(0, 3, count)),
        )
        if count % 2:
            piece.update(slow_s=rng.uniform(0, 2, count), slow_speed=rng.uniform(0, 0.2, count))
        nodes = tree.extend(**piece)
        start = sum(len(p["position"]) for p in pieces)
        assert np.array_equal(nodes, np.arange(start, start + count))
        pieces.append(piece)
        reads.append((tree.stacked(), len(pieces)))
    for stacked, count in reads:
        for name in _Tree.COLUMNS:
            expected = np.concatenate([p.get(name, np.zeros(len(p["position"]))) for p in pieces[:count]])
            assert _same_bits(stacked[name], expected.astype(stacked[name].dtype)), name
            assert stacked[name].dtype == expected.dtype, name
