"""The numpy social-force crowd (Helbing & Molnár 1995)."""

import numpy as np

from viapath.sim.social_force import simulate_crowd


def _pair_distances(positions):
    diff = positions[:, :, None, :] - positions[:, None, :, :]
    distance = np.hypot(diff[..., 0], diff[..., 1])
    n = positions.shape[1]
    distance[:, np.arange(n), np.arange(n)] = np.inf
    return distance


def test_two_walkers_head_on_pass_without_overlap_and_arrive():
    crowd = simulate_crowd([[0.0, 0.0], [10.0, 0.1]], [[[10.0, 0.0]], [[0.0, 0.1]]], [1.2, 1.2], 16.0, radii_m=0.25)
    distance = _pair_distances(crowd.positions)
    assert distance.min() > 0.5  # two radii of 0.25 m: no overlap
    # They swapped sides (passed each other) and ended near their goals.
    assert np.hypot(*(crowd.positions[-1, 0] - [10.0, 0.0])) < 0.5
    assert np.hypot(*(crowd.positions[-1, 1] - [0.0, 0.1])) < 0.5
    # While passing, they stepped aside: the lateral gap grew beyond the initial 0.1 m.
    passing = np.argmin(np.abs(crowd.positions[:, 0, 0] - crowd.positions[:, 1, 0]))
    assert abs(crowd.positions[passing, 0, 1] - crowd.positions[passing, 1, 1]) > 0.3


def test_walker_alone_reaches_desired_speed_and_walls_repel():
    alone = simulate_crowd([[0.0, 0.0]], [[[20.0, 0.0]]], [1.3], 5.0)
    assert abs(np.hypot(*alone.velocities[-1, 0]) - 1.3) < 0.05
    # A wall 0.4 m to the left pushes a walker towards -y.
    walled = simulate_crowd([[0.0, 0.0]], [[[20.0, 0.0]]], [1.3], 5.0, walls=[[[-5.0, 0.4], [30.0, 0.4]]])
    assert walled.positions[-1, 0, 1] < -0.05


def test_crowd_of_twelve_keeps_apart():
    rng = np.random.default_rng(3)
    starts = np.column_stack([rng.uniform(-6, 6, 12), rng.uniform(-6, 6, 12)])
    crowd = simulate_crowd(starts, [[[-x, -y]] for x, y in starts], rng.uniform(0.8, 1.4, 12), 20.0, radii_m=0.25)
    assert _pair_distances(crowd.positions).min() > 0.45
