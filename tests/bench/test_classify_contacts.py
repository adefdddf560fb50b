"""benchmarks/classify_contacts.py's figures for a contact at rest: how long the robot had stood and the room the
corridor left beside it, on a case with known answers: the robot waits at a closed door in a corridor ±0.3 m
wide and a person walks up the path from behind into it (no move lets them pass)."""

from __future__ import annotations

import pytest

from tests._scripts import load_benchmark
from viapath.scenarios import load_scenario
from viapath.sim.loop import run_episode

_NARROW = """
name: narrow
description: a robot waiting at a closed door, a person walking into it from behind
robot: {start: [0.0, 0.0], heading: 0.0, speed: 0.2, radius: 0.25}
path:
  waypoints: [[0.0, 0.0], [6.0, 0.0]]
  half_width: 0.3
walls:
  - {points: [[1.5, -2.0], [1.5, 2.0]], until_s: 30.0}
obstacles:
  - {start: [-4.0, 0.0], velocity: [0.6, 0.0], radius: 0.25, start_time_s: 10.0}
duration_s: 60
"""


@pytest.fixture(scope="module")
def classify():
    return load_benchmark("classify_contacts")


def test_a_contact_at_rest_reports_how_long_the_robot_stood_and_the_room_beside_it(classify, tmp_path):
    file = tmp_path / "narrow.yaml"
    file.write_text(_NARROW)
    contacts = classify._episode_kinds(str(file), 0, "oracle", None, 0.1, 0.0)["contacts"]
    assert len(contacts) == 1 and contacts[0]["at_rest"]
    contact = contacts[0]
    # The same run, read here: walk back from the contact to the last step the robot moved (above 0.05 m/s).
    trace = run_episode(load_scenario(file), seed=0, perception="oracle").trace
    step = int(round(contact["time_s"] / trace.dt_s))
    still = 0
    while step - still - 1 >= 0 and trace.robot_speeds_mps[step - still - 1] <= 0.05:
        still += 1
    assert contact["rest_s"] == pytest.approx((still + 1) * trace.dt_s)
    assert contact["rest_s"] >= 1.0  # it had waited at the door for seconds: the figure tells that
    # One straight segment along x: the room is the half width less the robot's distance from the line y = 0.
    room = 0.3 - abs(trace.robot_poses[step, 1])
    assert contact["corridor_room_m"] == pytest.approx(room, abs=1e-9)
    line = classify.resting_line(contacts)
    edge = "1 on the corridor's edge" if room < 0.1 else "0 on the corridor's edge"
    assert line.startswith(f"1 at rest: {edge}"), line
