"""The uncertainty cone that stops growing (planning under velocity noise) against dense sampling."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from viapath.geometry import legs_first_contact


def _sampled_first_contact(start, t0, velocity, duration, centre, obstacle_velocity, radius, growth, until):
    tau = np.linspace(0.0, duration, 20001)
    robot = start + velocity * tau[:, None]
    t = t0 + tau
    obstacle = centre + obstacle_velocity * t[:, None]
    reach = radius + growth * np.minimum(t, until)
    touching = np.hypot(*(robot - obstacle).T) <= reach
    return tau[np.argmax(touching)] if touching.any() else np.inf


coordinate = st.floats(-4, 4)


@settings(max_examples=200, deadline=None, derandomize=True)
@given(
    sx=coordinate,
    sy=coordinate,
    t0=st.floats(0, 5),
    vx=st.floats(-0.6, 0.6),
    vy=st.floats(-0.6, 0.6),
    duration=st.floats(0.1, 8),
    ox=coordinate,
    oy=coordinate,
    ovx=st.floats(-1, 1),
    ovy=st.floats(-1, 1),
    radius=st.floats(0.2, 0.8),
    growth=st.floats(0.0, 0.3),
    until=st.floats(0.0, 6.0),
)
def test_capped_cone_contact_matches_sampling(sx, sy, t0, vx, vy, duration, ox, oy, ovx, ovy, radius, growth, until):
    start, velocity = np.array([sx, sy]), np.array([vx, vy])
    centre, obstacle_velocity = np.array([ox, oy]), np.array([ovx, ovy])
    exact = legs_first_contact(
        start[None],
        np.array([t0]),
        velocity[None],
        np.array([duration]),
        centre[None],
        obstacle_velocity[None],
        np.array([radius]),
        np.array([growth]),
        until,
    )[0, 0]
    sampled = _sampled_first_contact(start, t0, velocity, duration, centre, obstacle_velocity, radius, growth, until)
    step = duration / 20000
    if np.isinf(sampled):
        # Sampling can miss a graze shorter than one step; the exact answer may then be finite.
        assert np.isinf(exact) or _grazing(start, t0, velocity, exact, centre, obstacle_velocity, radius, growth, until)
    else:
        assert exact <= sampled + 1e-9 and sampled - exact <= 2 * step + 1e-9


def _grazing(start, t0, velocity, tau, centre, obstacle_velocity, radius, growth, until):
    gap = np.hypot(*(start + velocity * tau - centre - obstacle_velocity * (t0 + tau)))
    return abs(gap - (radius + growth * min(t0 + tau, until))) < 1e-6


def test_per_obstacle_cap_equals_one_obstacle_at_a_time():
    rng = np.random.default_rng(7)
    k, n = 40, 6
    starts, velocities = rng.uniform(-3, 3, (k, 2)), rng.uniform(-0.6, 0.6, (k, 2))
    start_times, durations = rng.uniform(0, 4, k), rng.uniform(0, 6, k)
    centres, obstacle_velocities = rng.uniform(-3, 3, (n, 2)), rng.uniform(-1, 1, (n, 2))
    radii, growth = rng.uniform(0.3, 0.7, n), np.array([0.0, 0.1, 0.2, 0.05, 0.3, 0.1])
    until = np.array([np.inf, 1.0, 2.0, 0.0, 3.5, np.inf])
    together = legs_first_contact(
        starts, start_times, velocities, durations, centres, obstacle_velocities, radii, growth, until
    )
    for j in range(n):
        alone = legs_first_contact(
            starts,
            start_times,
            velocities,
            durations,
            centres[j : j + 1],
            obstacle_velocities[j : j + 1],
            radii[j : j + 1],
            growth[j : j + 1],
            until[j],
        )
        np.testing.assert_array_equal(together[:, j], alone[:, 0])
    assert np.isfinite(together).any() and np.isinf(together).any()


def test_leg_radii_widen_each_leg_by_its_own_amount():
    """``leg_radii_m`` (a braking envelope per leg) is the same as checking each leg alone against
    discs that much larger."""
    rng = np.random.default_rng(7)
    k, n = 60, 5
    starts = rng.uniform(-3, 3, (k, 2))
    start_times = rng.uniform(0, 2, k)
    velocities = rng.uniform(-0.6, 0.6, (k, 2))
    durations = rng.uniform(0, 6, k)
    centres = rng.uniform(-3, 3, (n, 2))
    obstacle_velocities = rng.uniform(-1, 1, (n, 2))
    radii = rng.uniform(0.3, 0.7, n)
    growth = rng.uniform(0, 0.3, n)
    until = rng.uniform(0.5, 3.0, n)
    extra = rng.uniform(0, 0.4, k) * (rng.uniform(size=k) < 0.5)
    together = legs_first_contact(
        starts, start_times, velocities, durations, centres, obstacle_velocities, radii, growth, until, extra
    )
    for i in range(k):
        alone = legs_first_contact(
            starts[i : i + 1],
            start_times[i : i + 1],
            velocities[i : i + 1],
            durations[i : i + 1],
            centres,
            obstacle_velocities,
            radii + extra[i],
            growth,
            until,
        )
        assert np.array_equal(together[i], alone[0])
    plain = legs_first_contact(
        starts, start_times, velocities, durations, centres, obstacle_velocities, radii, growth, until
    )
    assert np.all(together <= plain) and np.any(together < plain)  # larger discs are met no later, some sooner
