"""Timed waypoints (obstacle passes through points at given times): schema and motion."""

import numpy as np
import pytest

from viapath.scenarios import ScenarioError, scenario_from_dict
from viapath.sim.obstacles import scenario_obstacle_states

BASE = {
    "name": "timed",
    "robot": {"start": [0.0, 0.0]},
    "path": {"waypoints": [[0.0, 0.0], [5.0, 0.0]], "half_width": 1.0},
}


def test_timed_waypoints_interpolate_and_report_piece_velocity():
    obstacle = {"start": [0.0, 1.0], "waypoints": [[1.0, 1.0], [1.0, 3.0]], "times_s": [1.0, 2.0, 6.0]}
    scenario = scenario_from_dict({**BASE, "obstacles": [obstacle]})
    times = np.array([0.0, 1.5, 4.0, 7.0])
    positions, velocities, _ = scenario_obstacle_states(scenario, times)
    np.testing.assert_allclose(positions[:, 0], [[0.0, 1.0], [0.5, 1.0], [1.0, 2.0], [1.0, 3.0]])
    np.testing.assert_allclose(velocities[:, 0], [[0.0, 0.0], [1.0, 0.0], [0.0, 0.5], [0.0, 0.0]])


@pytest.mark.parametrize(
    "bad, words",
    [
        ({"times_s": [0.0, 1.0]}, "one time for start"),
        ({"times_s": [0.0, 2.0, 1.0]}, "increase"),
        ({"times_s": [0.0, 1.0, 2.0], "speed": 1.0}, "no speed"),
    ],
)
def test_timed_waypoints_reject_inconsistent_times(bad, words):
    obstacle = {"start": [0.0, 1.0], "waypoints": [[1.0, 1.0], [1.0, 3.0]], **bad}
    with pytest.raises(ScenarioError, match=words):
        scenario_from_dict({**BASE, "obstacles": [obstacle]})
