"""Pedestrian forecasts and the ETH/UCY displacement-error protocol (issue 11 item 5)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from viapath.forecast import (
    SocialForecastParams,
    constant_velocity_forecast,
    displacement_errors,
    heading_uncertainty_samples,
    protocol_windows,
    social_force_forecast,
    velocity_sigma_mps,
)


def straight_observed(start, velocity, rows, dt_s):
    t = np.arange(rows) * dt_s
    return np.asarray(start, float)[None, :] + t[:, None] * np.asarray(velocity, float)[None, :]


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    x=st.floats(-20, 20),
    y=st.floats(-20, 20),
    vx=st.floats(-2, 2),
    vy=st.floats(-2, 2),
    dt=st.sampled_from([0.4, 2.0 / 3.0, 0.1]),
)
def test_constant_velocity_is_exact_on_straight_line_tracks(x, y, vx, vy, dt):
    track = straight_observed((x, y), (vx, vy), 20, dt)
    predicted = constant_velocity_forecast(track[None, :8], 12, dt)
    ade, fde = displacement_errors(predicted, track[None, 8:])
    assert ade[0] < 1e-9 and fde[0] < 1e-9


def test_constant_velocity_uses_only_the_last_row_step():
    # A track that turns at its last observed row: the forecast follows the last step, not the mean.
    observed = np.array([[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0]]])
    predicted = constant_velocity_forecast(observed, 3, 0.4)
    np.testing.assert_allclose(predicted[0], [[2.0, 2.0], [2.0, 3.0], [2.0, 4.0]])


def test_ade_fde_against_a_brute_force_loop():
    rng = np.random.default_rng(3)
    predicted, truth = rng.normal(size=(7, 12, 2)), rng.normal(size=(7, 12, 2))
    ade, fde = displacement_errors(predicted, truth)
    for i in range(7):
        errors = [
            np.sqrt((predicted[i, k, 0] - truth[i, k, 0]) ** 2 + (predicted[i, k, 1] - truth[i, k, 1]) ** 2)
            for k in range(12)
        ]
        assert ade[i] == pytest.approx(sum(errors) / 12, rel=1e-12)
        assert fde[i] == pytest.approx(errors[-1], rel=1e-12)
    with pytest.raises(ValueError, match="predicted"):
        displacement_errors(predicted, truth[:, :11])


def random_table(rng, people=12, frames=60):
    rows = []
    for pid in range(people):
        first = int(rng.integers(0, frames - 15))
        length = int(rng.integers(10, frames - first + 1))
        for f in range(first, first + length):
            rows.append((f * 10, pid + 1, rng.normal(), rng.normal()))
    table = np.array(rows, float)
    return table[rng.permutation(len(table))]  # unsorted on purpose


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_protocol_windows_against_a_brute_force_enumeration(seed):
    rng = np.random.default_rng(seed)
    table = random_table(rng)
    frames = sorted(set(table[:, 0]))
    lookup = {(f, p): (x, y) for f, p, x, y in table}
    expected = []
    for start in range(len(frames) - 20 + 1):
        window = frames[start : start + 20]
        full = [p for p in sorted(set(table[:, 1])) if all((f, p) in lookup for f in window)]
        if len(full) >= 2:
            expected.append((window, full))
    got = list(protocol_windows(table))
    assert len(got) == len(expected) and len(expected) > 3
    for window, (frames_of, full) in zip(got, expected):
        truth = np.array([[lookup[(f, p)] for f in frames_of] for p in full])
        np.testing.assert_array_equal(window.observed, truth[:, :8])
        np.testing.assert_array_equal(window.future, truth[:, 8:])
        # Everyone present at the last observed frame is seen, scored people first.
        present = [p for p in sorted(set(table[:, 1])) if (frames_of[7], p) in lookup]
        assert len(window.seen_last) == len(present)
        np.testing.assert_array_equal(window.seen_last[: len(full)], truth[:, 7])


def test_protocol_windows_rejects_a_bad_table():
    with pytest.raises(ValueError, match="frame id x y"):
        list(protocol_windows(np.zeros((5, 3))))


def test_social_force_alone_is_constant_velocity():
    last, previous = np.array([[1.0, 2.0]]), np.array([[0.5, 2.1]])
    sf = social_force_forecast(last, previous, 12, 0.4)
    cv = constant_velocity_forecast(np.stack([previous, last], axis=1), 12, 0.4)
    np.testing.assert_allclose(sf, cv, atol=1e-9)


def test_social_force_keeps_two_head_on_walkers_apart_where_constant_velocity_overlaps_them():
    dt = 0.4
    last = np.array([[-2.88, 0.05], [2.88, -0.05]])  # would meet at x = 0 on row 6
    previous = last - np.array([[1.2, 0.0], [-1.2, 0.0]]) * dt
    cv = constant_velocity_forecast(np.stack([previous, last], axis=1), 12, dt)
    sf = social_force_forecast(last, previous, 12, dt)
    gap = lambda p: np.hypot(*(p[0] - p[1]).T).min() - 0.5
    assert gap(cv) < -0.35  # the straight lines go through each other
    assert gap(sf) > 0.0  # the forecast sees the other and passes
    assert sf[0, -1, 0] > 1.5 and sf[1, -1, 0] < -1.5  # and still gets past
    # With no repulsion the roll-out is the constant-velocity one.
    flat = social_force_forecast(last, previous, 12, dt, SocialForecastParams(strength_m2ps2=0.0))
    np.testing.assert_allclose(flat, cv, atol=1e-9)


def test_heading_samples_spread_by_sigma_and_collapse_to_cv_without_it():
    observed = straight_observed((0.0, 0.0), (1.0, 0.5), 8, 0.4)[None]
    rng = np.random.default_rng(0)
    zero = heading_uncertainty_samples(observed, 12, 0.4, 0.0, 5, rng)
    np.testing.assert_allclose(zero[0], constant_velocity_forecast(observed, 12, 0.4), atol=1e-12)
    samples = heading_uncertainty_samples(observed, 12, 0.4, 0.3, 4000, rng)
    step = samples[:, 0, -1] - observed[0, -1]
    angles = np.arctan2(step[:, 1], step[:, 0]) - np.arctan2(0.5, 1.0)
    assert np.std(angles) == pytest.approx(0.3, rel=0.05)
    np.testing.assert_allclose(np.hypot(*step.T), np.hypot(1.0, 0.5) * 12 * 0.4)  # speed is kept


def test_velocity_sigma_grows_with_speed():
    sigma = velocity_sigma_mps(np.array([[0.0, 0.0], [3.0, 4.0]]), 0.05, 0.2)
    np.testing.assert_allclose(sigma, [0.05, 0.05 + 0.2 * 5.0])
