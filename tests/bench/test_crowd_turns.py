"""benchmarks/crowd_turns.py, which explains a generated person's turn by the social-force terms: the split must add
up to the person's own velocity change, the generator's inputs must be the ones the suite used, and the distance to
a route must be the brute-force one."""

from __future__ import annotations

import numpy as np
import pytest

from tests._scripts import load_benchmark
from viapath.bench.suites import generate_suite


@pytest.fixture(scope="module")
def turns():
    return load_benchmark("crowd_turns")


def test_the_terms_add_up_to_the_persons_own_velocity_change(turns):
    """Two people crossing close by: over the 2 s window the drive, people and wall terms, integrated on the
    simulated states, give the velocity change across the heading that the simulation made (to 0.01 m/s of a
    0.2 m/s change), and the other person is the one who pushed."""
    inputs = {
        "starts": [[0.0, 0.0], [2.0, -2.0]],
        "routes": [[[8.0, 0.0]], [[2.0, 6.0]]],
        "speeds": [1.0, 1.0],
        "duration_s": 6.0,
    }
    split = turns.force_split(inputs, turns.simulate(inputs), 0, 3.0)
    assert abs(split["drive"] + split["people"] + split["walls"] - split["actual"]) < 0.01
    assert abs(split["actual"]) > 0.1  # they did turn, so the check above could fail
    assert split["walls"] == 0.0
    assert split["pushed_by"] == 1


def test_the_generator_inputs_are_the_suites_own(turns):
    """Simulating the captured inputs again, at every step of the simulator, gives the people the suite wrote (their
    timed waypoints), for a crowd and for a hallway (walls)."""
    for family in ("crowd", "hallway"):
        scenario = generate_suite(family, 1, seed=5)[0]
        trajectory = turns.simulate(turns._generator_inputs(scenario["name"], 5))
        assert len(scenario["obstacles"]) == trajectory.positions.shape[1]
        for person, written in enumerate(scenario["obstacles"]):
            for point, time_s in zip(written["waypoints"], written["times_s"][1:]):
                k = int(round(time_s / 0.05))
                assert np.allclose(point, trajectory.positions[k, person], atol=1e-3)


def test_the_distance_to_a_route_is_the_brute_force_one(turns):
    rng = np.random.default_rng(3)
    for _ in range(50):
        route = rng.uniform(-3.0, 3.0, (3, 2))
        point = rng.uniform(-3.0, 3.0, 2)
        samples = np.concatenate([a + np.linspace(0.0, 1.0, 4001)[:, None] * (b - a) for a, b in zip(route, route[1:])])
        brute = float(np.min(np.hypot(*(samples - point).T)))
        assert turns._off_polyline(point, route) == pytest.approx(brute, abs=2e-3)
