"""The escape's contacts (viapath/planning/viapath/escape_figures.py: escape_contacts, which skips the steps in
which a gap cannot close) against a full scan of every roll-out step and person, written here with numpy.

Seeded random roll-outs and people, some placed so that roll-outs touch them within a step or two of the
skip's bound, some overlapped now (their smallest and last gaps), growth capped and uncapped.
"""

from __future__ import annotations

import numpy as np

from viapath.planning.viapath.escape_figures import escape_contacts


def _full_scan(positions, times, centres, velocities, radii, growth, until, overlapping, steps):
    """Every step and person: the first step each roll-out is closer than a person's reach (``steps`` if never)
    among those not overlapped now, and the smallest and last gaps to those overlapped now."""
    t = times[None, :, None]  # (1, S, 1)
    at = centres[None, None, :, :] + velocities[None, None, :, :] * t[..., None]  # (1, S, N, 2)
    reach = radii[None, None, :] + growth[None, None, :] * np.minimum(t, until[None, None, :])
    distance = np.hypot(*(positions[:, :, None, :] - at).transpose(3, 0, 1, 2))  # (K, S, N)
    touching = (distance < reach) & ~overlapping[None, None, :]
    any_touch = touching.any(axis=2)  # (K, S)
    first = np.where(any_touch.any(axis=1), any_touch.argmax(axis=1), steps)
    gaps = (distance - reach)[:, :, overlapping]
    return first, gaps.min(axis=1), gaps[:, -1, :]


def _case(rng, k_count, steps, n_count):
    dt = 0.1
    times = dt * np.arange(1, steps + 1)
    headings = rng.uniform(-np.pi, np.pi, (k_count, 1)) + np.cumsum(rng.normal(0.0, 0.1, (k_count, steps)), axis=1)
    speeds = rng.uniform(0.0, 1.2, (k_count, 1))
    moves = np.stack([np.cos(headings), np.sin(headings)], axis=2) * (speeds * dt)[:, :, None]
    positions = np.ascontiguousarray(np.cumsum(moves, axis=1))  # (K, S, 2), from the origin
    centres = rng.uniform(-3.0, 3.0, (n_count, 2))
    # some people on a roll-out's path a little later, so that contacts come near the skip's bound
    chosen = rng.integers(0, k_count, n_count // 3)
    at_step = rng.integers(0, steps, n_count // 3)
    centres[: n_count // 3] = positions[chosen, at_step] + rng.normal(0.0, 0.3, (n_count // 3, 2))
    velocities = rng.normal(0.0, 0.8, (n_count, 2))
    radii = rng.uniform(0.2, 0.6, n_count)
    growth = np.where(rng.random(n_count) < 0.5, rng.uniform(0.0, 0.3, n_count), 0.0)
    until = np.where(rng.random(n_count) < 0.5, rng.uniform(0.0, 2.0, n_count), np.inf)
    overlapping = np.hypot(*centres.T) - radii <= 0.0
    overlapping[rng.random(n_count) < 0.15] = True  # overlapped by the caller's count, wherever they are
    return positions, times, centres, velocities, radii, growth, until, overlapping, steps


def test_escape_contacts_are_those_of_a_full_scan():
    rng = np.random.default_rng(40)
    contacts = overlapped = 0
    for _ in range(60):
        case = _case(rng, int(rng.integers(1, 25)), int(rng.integers(2, 40)), int(rng.integers(0, 20)))
        steps = case[-1]
        first, gap_min, gap_last = escape_contacts(*case)
        expected_first, expected_min, expected_last = _full_scan(*case)
        np.testing.assert_array_equal(first, expected_first)
        np.testing.assert_allclose(gap_min, expected_min, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(gap_last, expected_last, rtol=0.0, atol=1e-12)
        contacts += int(np.sum(first < steps))
        overlapped += gap_min.size
    # the cases reach both halves: roll-outs that touch someone, and people overlapped now
    assert contacts > 50 and overlapped > 50
