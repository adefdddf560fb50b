"""The planner's steps hold what they mean, each against what it computes worked out independently (one
command at a time, dense sampling of legs and segments, a fresh copy of the checks with nothing remembered):
the escape's scores, the via points and leg contacts, the corridor checks, the roll-out checks.

Seeded random situations: the robot near the path (three paths), 0-14 people around it, with and without
uncertainty, some overlapping the robot, so that both the escape's terms (time to contact, separation) and
roll-outs that pass, fail and turn on the spot come up. Bit-for-bit sameness of whole runs is the
equality runs' (episodes.csv before and after).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from tests._core_helpers import rollout
from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.geometry import wrap_angle
from viapath.kinematics import UnicycleState
from viapath.observation import Command
from viapath.planning import make_planner
from viapath.planning.base import Plan
from viapath.planning.viapath import packing as compiled
from viapath.planning.viapath.checks import LegChecks
from viapath.planning.viapath.escape import escape_fan
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
    planners = [make_planner("viapath", path, nominal_speed_mps=0.2) for path in PATHS]
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


def _escape_scores_command_by_command(checks, limits, config, previous):
    """What the escape's scores are (:func:`viapath.planning.viapath.packing.escape`), one command at a time from its definition (the escape's module
    docstring): each command's roll-out, its corridor excess point by point, each person's gap along it, the
    first step any person not overlapped now is touched, the overlapped ones' deepest and last gaps, and the
    weighted sum of the terms. (commands, ends, scores) to compare within round-off."""
    position = checks.position
    top = min(max(config.speeds), limits.max_speed_mps) if config.calm_escape else limits.max_speed_mps
    commands = np.array(
        [
            (v, w)
            for w in np.linspace(-limits.max_turn_rate_radps, limits.max_turn_rate_radps, 9)
            for v in sorted({0.0, top, *(min(v, top) for v in config.speeds)})
        ]
    )
    dt, steps = config.escape_dt_s, max(1, int(round(config.escape_s / config.escape_dt_s)))
    state = UnicycleState(*map(float, position), checks.heading_rad, checks.speed_mps, checks.turn_rate_radps)
    obstacles = checks.obstacles
    radii, growth, until = checks.check_radii, checks.growth, checks.growth_until_s
    gap_now = [math.hypot(*(position - p)) - r for p, r in zip(obstacles.positions, radii)]
    toward = (checks.subgoal - position) / max(math.hypot(*(checks.subgoal - position)), 1e-9)
    scores, ends = [], []
    for speed, turn in commands:
        positions = rollout(state, np.array([[speed, turn]]), limits, dt, steps)[0]
        excess = [float(checks.path.corridor_excess(point)) for point in positions]
        first_touch, separation = steps, 0.0
        for j in range(len(obstacles)):
            gaps = []
            for s, point in enumerate(positions):
                time_s = (s + 1) * dt
                centre = obstacles.positions[j] + obstacles.velocities[j] * time_s
                gaps.append(math.hypot(*(point - centre)) - (radii[j] + growth[j] * min(time_s, until[j])))
            if gap_now[j] > 0:
                first_touch = min([first_touch] + [s for s, gap in enumerate(gaps) if gap < 0])
            else:
                separation += min(min(gaps) - gap_now[j], 0.0) + min(gaps[-1], 0.0)
        time_to_contact = first_touch * dt
        free = first_touch == steps
        progress = float(np.dot(positions[-1] - position, toward)) / config.escape_s
        score = 100 * separation + 20 * free + 2 * (max(excess) <= checks.corridor_tolerance_m) + time_to_contact
        score += -(0.005 if free else 0.5) * speed
        score += (config.escape_progress_s if free else 0.01) * progress
        if config.calm_escape and previous is not None:
            change = abs(speed - previous.speed_mps) / max(top, 1e-9)
            change += abs(turn - previous.turn_rate_radps) / limits.max_turn_rate_radps
            score -= config.escape_continuity_s * min(change, 1.0)
        bound = max(config.escape_max_excess_m, checks.corridor_tolerance_m)
        scores.append(score if max(excess) <= bound or speed == 0.0 else -np.inf)
        ends.append(positions[-1])
    return commands, np.array(ends), np.array(scores)


def test_escape_scores_are_those_of_each_command_alone():
    """300 situations (with and without last cycle's escape command, with and without a calm escape): the same
    fan of commands, each command's end and score as worked out for that command alone, within round-off."""
    rng = np.random.default_rng(3)
    overlapped = contact = 0
    hasty = ViaPathConfig(calm_escape=False)
    for case, (planner, checks) in enumerate(_situations(300, seed=11)):
        config = planner.config if case % 5 else hasty
        previous = Command(*rng.uniform([0.0, -2.0], [0.5, 2.0])) if case % 3 == 0 else None
        fan = escape_fan(planner.limits, config)
        _, commands, ends, score = compiled.escape(checks, planner.limits, config, fan, previous, score_standing=True)
        expected = _escape_scores_command_by_command(checks, planner.limits, config, previous)
        assert np.array_equal(commands, expected[0]), f"case {case}"
        np.testing.assert_allclose(ends, expected[1], rtol=0, atol=1e-12, err_msg=f"case {case}")
        np.testing.assert_allclose(score, expected[2], rtol=1e-12, atol=1e-9, err_msg=f"case {case}")
        gaps = np.hypot(*(checks.position - checks.obstacles.positions).T) - checks.check_radii
        overlapped += bool(np.any(gaps <= 0))
        contact += bool(np.any(score[np.isfinite(score)] < 20.0))
    assert overlapped > 20 and contact > 20  # both terms came up


# -- the roll-outs of candidates -------------------------------------------------------------------


def test_clear_is_the_definition():
    """The roll-out's clearance (:func:`viapath.planning.viapath.rollout._clear`, compiled) against its definition
    (:func:`_clear_reference`) on random roll-outs
    near the people (so that both verdicts come up), with one step exactly on a person's limit in a quarter of
    them (where a difference in the last bit of a distance would change the verdict)."""
    rng = np.random.default_rng(5)
    verdicts = set()
    for case, (_, checks) in enumerate(_situations(600, seed=12)):
        for kind in range(4):
            steps, dt = int(rng.choice([20, 5, 12])), float(rng.choice([0.1, 0.1, 0.05]))
            positions = checks.position + np.cumsum(rng.normal(0.0, 0.06, (steps, 2)), axis=0)
            if len(checks.obstacles) and kind == 3:  # one step on the boundary of one person's limit
                obstacles = checks.obstacles
                times = dt * np.arange(1, steps + 1)[:, None]
                centres = obstacles.positions[None] + obstacles.velocities[None] * times[..., None]
                reach = checks.check_radii + checks.growth * np.minimum(times, checks.growth_until_s)
                limit = np.minimum(reach, np.hypot(*(checks.position - obstacles.positions).T) - 1e-3)
                s, j, angle = int(rng.integers(steps)), int(rng.integers(len(obstacles))), rng.uniform(0, 2 * np.pi)
                positions[s] = centres[s, j] + abs(limit[s, j]) * np.array([np.cos(angle), np.sin(angle)])
            expected = _clear_reference(checks, positions, dt)
            assert _clear(checks, positions, dt) is expected, f"case {case}"
            verdicts.add(expected)
    assert verdicts == {True, False}


def _clear(checks, positions, dt):
    """The compiled roll-out's clearance of ``positions``, one per ``dt`` from now, from the obstacles of ``checks``."""
    from viapath.planning.viapath import rollout

    positions = np.ascontiguousarray(positions, dtype=float)
    x, y = (float(v) for v in checks.position)
    return bool(rollout._clear(positions, len(positions), float(dt), x, y, *checks.packed_obstacles()))


def _clear_reference(checks, positions, dt):
    """:func:`_clear` by its definition: every step's distance to every obstacle's centre then, at least
    the obstacle's reach then, or (a close pass) no closer than the robot is now."""
    if len(checks.obstacles) == 0:
        return True
    times = dt * np.arange(1, len(positions) + 1)[:, None]
    obstacles = checks.obstacles
    centres = obstacles.positions[None] + obstacles.velocities[None] * times[..., None]
    reach = checks.check_radii + checks.growth * np.minimum(times, checks.growth_until_s)
    distance = np.hypot(*(positions[:, None, :] - centres).transpose(2, 0, 1))
    now = np.hypot(*(checks.position - obstacles.positions).T)
    return bool(np.all(distance >= np.minimum(reach, now - 1e-3)))


def test_can_follow_remembers_only_what_it_would_compute_again():
    """Plans of a cycle towards random targets, many sharing target and speed (as slow/wait candidates
    and chains through one via point do): each verdict and turn-in-place mark equal those of the same
    checks with nothing remembered (a fresh copy for every plan, which rolls it out afresh); and a plan that
    turns on the spot has a target off its heading by more than the turn-in-place threshold."""
    rng = np.random.default_rng(8)
    kinds = set()
    for case, (planner, checks) in enumerate(_situations(500, seed=13)):
        targets = checks.position + rng.uniform(-2.5, 2.5, (3, 2))
        speeds = rng.choice([0.0, 0.1, 0.2, 0.3, 0.5], 3)
        for _ in range(8):
            target, speed = targets[rng.integers(0, 3)], float(speeds[rng.integers(0, 3)])
            plan, reference = (Plan("avoid", speed, target.copy()) for _ in range(2))
            got = can_follow(plan, checks, planner.limits, planner.config)
            expected = can_follow(reference, replace(checks), planner.limits, planner.config)
            assert got is expected and plan.extras == reference.extras, f"case {case}"
            turned = bool(reference.extras.get("turn_in_place"))
            if turned:
                offset = target - checks.position
                error = abs(float(wrap_angle(math.atan2(offset[1], offset[0]) - checks.heading_rad)))
                assert error > planner.config.turn_in_place_min_rad, f"case {case}"
            kinds.add((expected, turned))
    assert kinds == {(True, False), (True, True), (False, False)}  # passed, turned on the spot, failed


# -- the leg checks and via points of the candidate tree -------------------------------------------


def _check_via_options(arguments, got) -> None:
    """What each via option is: the robot leaves the node at its speed (|leg velocity| = speed) and reaches
    the via point at the option's time (at most the longest), which is then on the edge of the obstacle's
    disc as it has moved by then (radius: the cone at the passing time plus the envelope, below 98 % of the
    node's distance), on the option's side, without having entered the disc on the way (dense sampling)."""
    from viapath.geometry import VIA_SIDES

    starts, start_times, speeds, positions, velocities, via_radii, growth, until, envelope, max_time_s = arguments
    pair, option, t_k, leg_velocity, via = got
    assert np.all(np.diff(pair * 4 + option) > 0)  # row-major, each option once
    centre_now = positions + velocities * start_times[:, None]
    distance = np.hypot(*(centre_now - starts).T)
    radius = via_radii + growth * np.minimum(start_times + distance / speeds, until) + envelope
    radius = np.clip(radius, 0.0, 0.98 * distance)[pair]
    assert np.all((t_k > 0) & (t_k <= max_time_s))
    np.testing.assert_allclose(np.hypot(*leg_velocity.T), speeds[pair], rtol=1e-9)
    np.testing.assert_allclose(via, starts[pair] + leg_velocity * t_k[:, None], rtol=1e-12, atol=1e-12)
    centre_then = centre_now[pair] + velocities[pair] * t_k[:, None]
    np.testing.assert_allclose(np.hypot(*(via - centre_then).T), radius, rtol=1e-7, atol=1e-9)
    relative = (leg_velocity - velocities[pair]) * t_k[:, None]  # the leg seen from the obstacle
    side = np.sign(
        relative[:, 0] * (centre_now[pair, 1] - starts[pair, 1])
        - relative[:, 1] * (centre_now[pair, 0] - starts[pair, 0])
    )
    assert np.all((side == -VIA_SIDES[option]) | (radius < 1e-9))  # left: the obstacle on the right
    fractions = np.linspace(0.0, 1.0, 201)[:, None, None]
    sampled = starts[pair] - centre_now[pair] + fractions * relative  # (201, options, 2)
    assert np.all(np.hypot(sampled[..., 0], sampled[..., 1]) >= radius * (1 - 1e-7) - 1e-9)


def _check_first_contacts(leg, people, leg_radii, got, checked, static) -> None:
    """What each leg's first contact is, by dense sampling of the leg (2 001 instants): before it the leg is
    never inside the person's (growing, capped) disc, at it the leg is on the disc's edge (or inside at the
    start: 0), and a leg with no contact (inf) is never inside; a person's disc up to the leg's ``checked``
    time (the horizon) with the leg's radius added, a static disc (``static``) over the whole leg without it."""
    starts, start_times, velocities, durations = leg
    positions, person_velocities, radii, growth, until = people
    until = np.broadcast_to(until, radii.shape)
    added = np.zeros(len(starts)) if leg_radii is None else leg_radii
    extra = np.where(static[None, :], 0.0, added[:, None])  # (legs, people)
    limit = np.where(static[None, :], durations[:, None], checked[:, None])
    fraction = np.linspace(0.0, 1.0, 2001)[:, None, None]
    tau = fraction * durations[None, :, None]  # (T, legs, 1)
    absolute = start_times[None, :, None] + tau
    robot = starts[None, :, None, :] + velocities[None, :, None, :] * tau[..., None]
    person = positions[None, None] + person_velocities[None, None] * absolute[..., None]
    gap = np.hypot(*np.moveaxis(robot - person, -1, 0))
    gap -= radii + extra + growth * np.minimum(absolute, until)  # (T, legs, people)
    last = np.where(np.isfinite(got), got * (1 - 1e-9) - 1e-9, np.nextafter(limit, np.inf))  # (legs, people)
    before = tau < last[None]
    assert np.all(gap[np.broadcast_to(before, gap.shape)] >= -1e-9)
    assert np.all(got[np.isfinite(got)] <= limit[np.isfinite(got)] * (1 + 1e-9) + 1e-9)
    at = np.isfinite(got) & (got > 0)
    legs, people_at = np.nonzero(at)
    tau_at, absolute_at = got[at], start_times[legs] + got[at]
    offset = (
        starts[legs]
        + velocities[legs] * tau_at[:, None]
        - positions[people_at]
        - person_velocities[people_at] * absolute_at[:, None]
    )
    edge = radii[people_at] + extra[legs, people_at] + growth[people_at] * np.minimum(absolute_at, until[people_at])
    np.testing.assert_allclose(np.hypot(*offset.T), edge, rtol=1e-7, atol=1e-7)
    assert np.all(gap[0][got == 0] <= 1e-9)  # contact at the start: inside already


def via_options(starts, start_times, speeds, positions, velocities, via_radii, growth, until, envelope, max_time_s):
    """The via options of each (node, obstacle) pair as the candidate tree makes them (its arithmetic,
    :func:`viapath.planning.viapath.via.via_pair`, and the tree's legs to them): (pair, option, time, leg velocity,
    via point), pair by pair, option by option."""
    from viapath.planning.viapath.via import via_pair

    rows = []
    t_via, w_via = np.empty(4), np.empty((2, 2))
    for p in range(len(starts)):
        if via_pair(
            *starts[p], start_times[p], speeds[p], *positions[p], *velocities[p], via_radii[p], growth[p], until[p],
            envelope[p], t_via, w_via,
        ):  # fmt: skip
            for o in range(4):
                t = t_via[o]
                if t <= max_time_s:
                    velocity = (w_via[o % 2] + velocities[p] * t) / t
                    rows.append((p, o, t, velocity, starts[p] + velocity * t))
    pair, option, t_k = (np.array([row[i] for row in rows], dtype=int if i < 2 else float) for i in range(3))
    return (
        pair,
        option,
        t_k,
        np.array([r[3] for r in rows]).reshape(-1, 2),
        np.array([r[4] for r in rows]).reshape(-1, 2),
    )


def _first_contacts(leg, people, leg_radii, checked, static):
    """:func:`viapath.planning.viapath.legs.first_contacts` of legs and people given as in the test below."""
    from viapath.planning.viapath import legs as leg_steps
    from viapath.planning.viapath.shapes import NO_SHAPES, static_shapes

    starts, start_times, velocities, durations = leg
    n = len(people[2])
    packed = tuple(
        np.ascontiguousarray(np.broadcast_to(values, (n, 2) if i < 2 else (n,)), float)
        for i, values in enumerate(people)
    )
    shapes = static_shapes(static, np.arange(n) % 3) if static.any() else NO_SHAPES
    added = np.zeros(len(starts)) if leg_radii is None else leg_radii
    return leg_steps.first_contacts(starts, start_times, velocities, checked, durations, packed, added, shapes.shape_of)


def test_via_options_and_leg_contacts_are_what_they_mean():
    """Random nodes (some on or inside an obstacle's disc, some at rest relative to it) against random
    people, cones growing or not, capped or not, with and without a braking envelope, and some static discs: every
    via option meets its obstacle's disc tangentially at the option's time, and each leg's first contact (of the
    legs to those via points and of random legs, a person's up to a horizon, a static disc's to the leg's end) is
    where dense sampling finds it."""
    rng = np.random.default_rng(21)
    options = contacts = static_contacts = 0
    for case in range(600):
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
        found = via_options(*arguments)
        _check_via_options(arguments, found)
        options += len(found[0])

        static = (rng.uniform(size=n) < 0.4) & (case % 2 == 0)
        people = (
            rng.uniform(-4, 4, (n, 2)),
            rng.uniform(-1.2, 1.2, (n, 2)) * ~static[:, None],
            rng.uniform(0.4, 0.8, n),
            rng.uniform(0, 0.2, n) * (case % 2),
            rng.choice([np.inf, 1.5, 3.0], n) if case % 4 else np.inf,
        )
        pair = found[0]
        legs = [
            (starts[pair], times[pair], found[3], found[2]),
            (starts, times, rng.uniform(-0.5, 0.5, (pairs, 2)), rng.uniform(0, 8, pairs)),
        ]
        for leg in legs:
            leg_radii = rng.uniform(0, 0.3, len(leg[0])) if case % 3 == 0 else None
            checked = leg[3] * (rng.uniform(0.2, 1.0, len(leg[0])) if case % 4 == 0 else 1.0)
            contact = _first_contacts(leg, people, leg_radii, checked, static)
            _check_first_contacts(leg, people, leg_radii, contact, checked, static)
            contacts += int(np.isfinite(contact).sum())
            static_contacts += int(np.isfinite(contact[:, static]).sum())
    assert options > 2000 and contacts > 2000 and static_contacts > 300


# -- the corridor ----------------------------------------------------------------------------------


def test_segment_geometry_is_distance_to_each_segment():
    """Few and many points (the escape's 1 620), in 1-D and 2-D batches, some on the waypoints, some with
    coordinates of -0.0, on the three paths: each point's arc position along each segment is its projection
    (the clamped one on the segment), its distance the distance to the nearest of 2 001 points along the segment
    (to within their spacing), and the corridor excess the least distance less the segment's half width."""
    rng = np.random.default_rng(4)
    for case in range(300):
        path = PATHS[case % len(PATHS)]
        shape = [(1,), (20,), (70,), (1620,), (30, 12), (3, 40)][case % 6]
        points = rng.uniform(-3, 9, (*shape, 2))
        flat = points.reshape(-1, 2)
        flat[: len(flat) // 10] = path.waypoints[rng.integers(0, len(path.waypoints), len(flat) // 10)]
        flat[-3:] *= -0.0 if case % 2 else 1.0
        along, clamped, distance = path._segment_geometry(points)
        for k, (start, vector, length) in enumerate(
            zip(path.segment_starts, path.segment_vectors, path.segment_lengths_m)
        ):
            rel = points - start
            np.testing.assert_allclose(along[..., k], (rel @ vector) / length, atol=1e-12)
            assert np.all((clamped[..., k] >= 0) & (clamped[..., k] <= length))
            samples = start + np.linspace(0.0, 1.0, 2001)[:, None] * vector  # (2001, 2)
            dense = np.hypot(*np.moveaxis(points[..., None, :] - samples, -1, 0)).min(axis=-1)
            assert np.all(distance[..., k] <= dense + 1e-12), f"case {case}"
            assert np.all(dense <= distance[..., k] + length / 2000), f"case {case}"
        np.testing.assert_array_equal(path.corridor_excess(points), (distance - path.half_widths_m).min(axis=-1))


def test_legs_inside_is_dense_sampling():
    """Legs within a capsule, across junctions, leaving the corridor, with ends on its edge (the tolerance
    decides), 0 to 100 legs, per-leg tolerances or one: a leg whose points, 1 mm apart, are all inside by
    1 cm more than the tolerance is inside; one with a point outside by 1 cm more is not."""
    rng = np.random.default_rng(10)
    verdicts = set()
    for case in range(600):
        path = PATHS[case % len(PATHS)]
        n = int(rng.integers(0, 100))
        starts, ends = rng.uniform(-2, 9, (n, 2)), rng.uniform(-2, 9, (n, 2))
        if n and case % 3 == 0:  # ends near the corridor's edge
            segment = rng.integers(0, len(path.segment_lengths_m), n)
            normal = path.segment_directions[segment] @ np.array([[0.0, 1.0], [-1.0, 0.0]])
            ends = (
                path.segment_starts[segment]
                + rng.uniform(0, 1, (n, 1)) * path.segment_vectors[segment]
                + path.half_widths_m[segment, None] * normal
            )
        if n and case % 4 == 1:  # short legs, mostly inside
            ends = starts + rng.uniform(-0.5, 0.5, (n, 2))
        tolerance = rng.choice([1e-9, 0.0, 0.2]) if case % 2 else rng.uniform(-0.1, 0.3, n)
        got = path.legs_inside(starts, ends, 0.05, tolerance)
        assert got.shape == (n,) and got.dtype == bool
        if n == 0:
            continue
        length = float(np.hypot(*(ends - starts).T).max())
        fractions = np.linspace(0.0, 1.0, max(2, int(np.ceil(length / 1e-3)) + 1))
        worst = np.array(
            [path.corridor_excess(a + fractions[:, None] * (b - a)).max() for a, b in zip(starts, ends)]
        ) - np.broadcast_to(tolerance, (n,))
        assert np.all(got[worst <= -0.01]), f"case {case}"
        assert not np.any(got[worst > 0.01]), f"case {case}"
        verdicts |= set(got[np.abs(worst) > 0.01].tolist())
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
