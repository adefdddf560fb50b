"""The compiled choice's shortcuts (viapath/planning/viapath/rollout.py: wrap, _clear; legs.py: legs_free) give what the full computation gives.

Each test holds a shortcut to the earlier form, compiled here as the reference, on seeded random cases
and on values placed right at the boundaries the shortcuts decide by: angles at ±pi and multiples of 2 pi
(and one ulp beyond), distances equal to the limit (and within the ±1e-9 band around it), NaN.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

numba = pytest.importorskip("numba")

from viapath.planning.viapath import legs, rollout  # noqa: E402 -- after the importorskip of numba


@numba.njit(cache=False)
def _wrap_reference(angle):
    return math.pi - ((math.pi - angle) % (2.0 * math.pi))


def _clear_by_definition(
    positions, count, dt, robot_x, robot_y, obstacle_positions, obstacle_velocities, radii, growth, growth_until_s
) -> bool:
    """What ``_clear`` answers, stated over every step and obstacle at once: each roll-out position keeps at
    least ``min(reach at t, distance now - 1 mm)`` from each moved obstacle (a NaN limit or distance fails)."""
    t = dt * (np.arange(count) + 1.0)  # (S,)
    centres = obstacle_positions[:, None, :] + obstacle_velocities[:, None, :] * t[None, :, None]  # (N, S, 2)
    until = growth_until_s[:, None]
    capped = np.where(np.isnan(until), until, np.minimum(t[None, :], until))
    reach = radii[:, None] + growth[:, None] * capped
    now = (np.hypot(robot_x - obstacle_positions[:, 0], robot_y - obstacle_positions[:, 1]) - 1e-3)[:, None]
    with np.errstate(invalid="ignore"):
        limit = np.where(np.isnan(reach) | (reach < now), reach, now)
        limit = np.where(np.isnan(now), now, limit)
        distance = np.hypot(positions[None, :count, 0] - centres[..., 0], positions[None, :count, 1] - centres[..., 1])
        return bool(np.all(distance >= limit))


def _bits(value: float) -> int:
    return int(np.float64(value).view(np.int64))


def test_wrap_skips_the_modulo_only_where_it_changes_nothing():
    two_pi = 2.0 * math.pi
    special = [
        0.0,
        -0.0,
        math.pi,
        -math.pi,
        two_pi,
        -two_pi,
        3 * math.pi,
        -3 * math.pi,
        1e-300,
        -1e-300,
        1e-20,
        math.inf,
        -math.inf,
        math.nan,
        1e300,
        -1e300,
    ]
    for k in range(-6, 7):
        for base in (k * math.pi, k * two_pi):
            special += [base, np.nextafter(base, math.inf), np.nextafter(base, -math.inf)]
    rng = np.random.default_rng(3)
    angles = np.concatenate(
        [special, rng.uniform(-20.0, 20.0, 5000), rng.uniform(-4.0, 4.0, 5000), rng.normal(0.0, 1e3, 500)]
    )
    for angle in angles.tolist():
        got, expected = rollout.wrap(angle), _wrap_reference(angle)
        assert _bits(got) == _bits(expected) or (math.isnan(got) and math.isnan(expected)), angle


def _clear_cases(rng, count: int):
    """(arguments of _clear) with some positions exactly at, or within 1e-9 of, the limit."""
    for case in range(count):
        n = int(rng.integers(1, 6))
        steps = int(rng.integers(1, 8))
        dt = 0.2
        robot = rng.uniform(-1.0, 1.0, 2)
        positions_obs = robot + rng.uniform(-3.0, 3.0, (n, 2))
        velocities = rng.uniform(-1.0, 1.0, (n, 2))
        radii = rng.uniform(0.1, 0.8, n)
        growth = np.where(rng.random(n) < 0.5, 0.0, rng.uniform(0.0, 0.3, n))
        until = np.where(rng.random(n) < 0.5, math.inf, rng.uniform(0.0, 1.0, n))
        positions = robot + rng.uniform(-2.0, 2.0, (steps, 2))
        if case % 3 == 0:  # a position placed at the limit of an obstacle, or just inside or outside it
            j = int(rng.integers(n))
            s = int(rng.integers(steps))
            t = dt * (s + 1)
            now = math.hypot(robot[0] - positions_obs[j, 0], robot[1] - positions_obs[j, 1]) - 1e-3
            reach = radii[j] + growth[j] * min(t, until[j])
            limit = min(reach, now)
            scale = limit * (1.0 + rng.choice([0.0, 1e-10, -1e-10, 2e-9, -2e-9, 5e-16, -5e-16]))
            angle = rng.uniform(-math.pi, math.pi)
            centre = positions_obs[j] + velocities[j] * t
            positions[s] = centre + scale * np.array([math.cos(angle), math.sin(angle)])
        if case % 17 == 0:  # NaN: a position, a radius or a person's position
            which = case // 17 % 3
            if which == 0:
                positions[int(rng.integers(steps)), int(rng.integers(2))] = math.nan
            elif which == 1:
                radii[int(rng.integers(n))] = math.nan
            else:
                positions_obs[int(rng.integers(n)), 0] = math.nan
        yield (
            np.ascontiguousarray(positions),
            steps,
            dt,
            float(robot[0]),
            float(robot[1]),
            positions_obs,
            velocities,
            radii,
            growth,
            until,
        )


def test_clear_by_squared_distance_matches_hypot():
    rng = np.random.default_rng(5)
    answers = []
    for arguments in _clear_cases(rng, 600):
        expected = _clear_by_definition(*arguments)
        assert rollout._clear(*arguments) == expected
        answers.append(expected)
    assert any(answers) and not all(answers)  # both answers came up


def test_legs_free_stops_at_the_first_contact_and_agrees():
    rng = np.random.default_rng(7)
    for case in range(300):
        k, n = int(rng.integers(1, 8)), int(rng.integers(0, 6))
        starts = rng.uniform(-2.0, 2.0, (k, 2))
        start_times = rng.uniform(0.0, 2.0, k)
        velocities = rng.uniform(-1.0, 1.0, (k, 2))
        durations = rng.uniform(0.0, 4.0, k)
        positions = rng.uniform(-4.0, 4.0, (n, 2))
        obstacle_velocities = rng.uniform(-1.0, 1.0, (n, 2))
        radii = rng.uniform(0.1, 0.6, n)
        growth = np.where(rng.random(n) < 0.5, 0.0, rng.uniform(0.0, 0.3, n))
        until = np.where(rng.random(n) < 0.5, math.inf, rng.uniform(0.0, 3.0, n))
        if case % 23 == 0 and n:
            radii[0] = math.nan
        horizon = float(rng.uniform(0.5, 5.0))
        checked = np.array([legs.clip(horizon - start_times[i], 0.0, durations[i]) for i in range(k)])
        # Some discs static (velocity 0, checked to the leg's end) on every other case.
        shape_of = np.where(rng.random(n) < 0.5, 0, -1) if case % 2 else np.zeros(0, np.int64)
        if len(shape_of):
            obstacle_velocities[shape_of >= 0] = 0.0
        obstacles = (positions, obstacle_velocities, radii, growth, until)
        contact = legs.first_contacts(
            starts, start_times, velocities, checked, durations, obstacles, np.zeros(k), shape_of
        )
        expected = ~(~np.isinf(contact)).any(axis=1)
        got = legs.legs_free(starts, start_times, velocities, durations, horizon, obstacles, shape_of)
        assert np.array_equal(got, expected)
