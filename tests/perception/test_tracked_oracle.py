"""Perception mode ``tracked``: noisy detections of the true people through the project's Kalman tracker."""

import numpy as np
import pytest

from viapath.perception.base import WorldSnapshot
from viapath.perception.modes import make_perception
from viapath.scenarios import scenario_from_dict

DT = 0.1


def _world(k, positions, velocities, radius=0.25):
    positions = np.asarray(positions, dtype=float).reshape(-1, 2)
    return WorldSnapshot(
        k * DT,
        np.zeros(3),
        0.25,
        positions,
        np.asarray(velocities, float).reshape(-1, 2),
        np.full(len(positions), radius),
    )


def _walk(mode, seed=0, steps=60, position_noise_m=0.03, velocity_noise_mps=0.0, velocity=(1.0, 0.0)):
    """A person walking from (2, 1) at ``velocity``: what the planner is told each cycle."""
    sensing = make_perception(mode, None, position_noise_m, velocity_noise_mps)
    sensing.reset(np.random.default_rng(seed))
    out = []
    for k in range(steps):
        truth = np.array([2.0, 1.0]) + np.asarray(velocity) * k * DT
        out.append((truth, sensing.observe(_world(k, truth, velocity))))
    return out


def test_a_walker_is_reported_from_the_trackers_confirmation_with_learnt_velocity():
    cycles = _walk("tracked")
    reported = [len(seen.positions) for _, seen in cycles]
    assert reported[:2] == [0, 0] and all(n == 1 for n in reported[2:])  # confirmed at the third detection
    late = cycles[20:]
    velocity_error = np.array([seen.velocities[0] - (1.0, 0.0) for _, seen in late])
    position_error = np.array([seen.positions[0] - truth for truth, seen in late])
    assert np.sqrt(np.mean(velocity_error**2)) < 0.12
    assert np.sqrt(np.mean(position_error**2)) < 0.03
    # the σ handed over are the filter's: small once converged, never zero
    assert all(0 < seen.position_sigma_m[0] < 0.03 and seen.velocity_sigma_mps[0] > 0 for _, seen in late)


def _lag_one_correlation(errors):
    return float(np.mean([np.corrcoef(errors[:-1, axis], errors[1:, axis])[0, 1] for axis in (0, 1)]))


def test_tracked_errors_are_filtered_and_correlated_from_cycle_to_cycle_unlike_white_noise():
    # 18 s of walking, after the first 2 s: the filter's position error is below the detections' (σ 0.03 m
    # per axis: 0.042 m RMS), and both its errors carry over from one cycle to the next, where the
    # oracle's white noise is independent every cycle.
    tracked = _walk("tracked", steps=200)[20:]
    white = _walk("oracle", steps=200, velocity_noise_mps=0.05)[20:]
    errors = {}
    for name, cycles in (("tracked", tracked), ("white", white)):
        position = np.array([seen.positions[0] - truth for truth, seen in cycles])
        velocity = np.array([seen.velocities[0] - (1.0, 0.0) for _, seen in cycles])
        errors[name] = position, velocity
    position, velocity = errors["tracked"]
    assert np.sqrt(np.mean(np.sum(position**2, axis=1))) < 0.8 * 0.03 * np.sqrt(2)
    assert _lag_one_correlation(position) > 0.4 and _lag_one_correlation(velocity) > 0.25
    assert abs(_lag_one_correlation(errors["white"][0])) < 0.2 and abs(_lag_one_correlation(errors["white"][1])) < 0.2
    # the velocity error stays within the σ the filter reports (its worst direction)
    sigma = np.array([seen.velocity_sigma_mps[0] for _, seen in tracked])
    assert np.sqrt(np.mean(velocity**2)) < np.mean(sigma)


def test_runs_are_reproducible_by_seed_and_exact_without_noise():
    a = np.array([seen.positions[0] for _, seen in _walk("tracked", seed=3)[5:]])
    b = np.array([seen.positions[0] for _, seen in _walk("tracked", seed=3)[5:]])
    c = np.array([seen.positions[0] for _, seen in _walk("tracked", seed=4)[5:]])
    assert np.array_equal(a, b) and not np.allclose(a, c)
    exact = _walk("tracked", position_noise_m=0.0)[30:]
    assert max(float(np.hypot(*(seen.positions[0] - truth))) for truth, seen in exact) < 1e-3


def test_a_person_standing_still_stays_a_person():
    # The laser's tracker hands a track still for 3 s to the static layer; the oracle's map is the
    # static layer here, so the person must stay a person.
    cycles = _walk("tracked", steps=80, velocity=(0.0, 0.0))
    assert all(len(seen.positions) == 1 for _, seen in cycles[2:])


def test_scenarios_select_it_and_refuse_what_does_not_apply():
    base = {
        "name": "t",
        "dt_s": 0.1,
        "duration_s": 5,
        "robot": {"start": [0, 0], "heading": 0, "speed": 0.2},
        "path": {"waypoints": [[0, 0], [3, 0]], "half_width": 1.0},
    }
    spec = scenario_from_dict({**base, "perception": {"mode": "tracked", "position_noise_m": 0.03}}, "t").perception
    assert spec.mode == "tracked" and spec.position_noise_m == 0.03
    with pytest.raises(ValueError, match="velocity_noise_mps: mode 'tracked' takes its velocities from the tracker"):
        scenario_from_dict({**base, "perception": {"mode": "tracked", "velocity_noise_mps": 0.05}}, "t")
    with pytest.raises(ValueError, match="configure the laser chain; mode 'tracked' takes none"):
        scenario_from_dict({**base, "perception": {"mode": "tracked", "options": {"range_noise": False}}}, "t")
    with pytest.raises(ValueError, match="velocity_noise_mps"):
        make_perception("tracked", None, 0.03, 0.05)
