"""Progress through the static world in the closed loop: a box before a closed door, a box beside the path
before a door, a box just past the corner of an L-shaped corridor; oracle and laser. The robot goes round
the box and waits near the door (or goes on when it opens), never touching anything."""

from __future__ import annotations

import numpy as np
import pytest

from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.planning import make_planner
from viapath.scenarios.loader import scenario_from_dict
from viapath.sim.loop import run_episode
from viapath.static import StaticLayer, box_edges, point_segment_distances, polyline_edges

RADIUS = 0.25
DOOR = [[5.0, -1.3], [5.0, 1.3]]
SIDES = [{"points": [[-1.0, 1.3], [8.0, 1.3]]}, {"points": [[-1.0, -1.3], [8.0, -1.3]]}]
# The tutorial's L-shaped corridor (docs/tutorial/own-scenario.md) with a box just past its corner.
L_WALLS = [
    {"points": [[-1, 1.3], [2, 1.3]]},
    {"points": [[3, 1.3], [3.7, 1.3], [3.7, 5]]},
    {"points": [[-1, -1.3], [2, -1.3]]},
    {"points": [[3, -1.3], [6.3, -1.3], [6.3, 5]]},
]
L_BOX = {"center": [5.5, 2.5], "size": [0.4, 0.4]}


def _corridor(box: dict, door_until_s: float | None, duration_s: float) -> dict:
    door = {"points": DOOR} if door_until_s is None else {"points": DOOR, "until_s": door_until_s}
    return {
        "name": "box-and-door",
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.4, "radius": RADIUS},
        "path": {"waypoints": [[0.0, 0.0], [7.0, 0.0]], "half_width": 1.0},
        "duration_s": duration_s,
        "boxes": [box],
        "walls": [door, *SIDES],
    }


def _gap_to_door(poses: np.ndarray) -> np.ndarray:
    """The robot's surface to the door (m)."""
    return point_segment_distances(poses[:, :2], np.array([DOOR], float))[:, 0] - RADIUS


@pytest.mark.parametrize("perception", ["oracle", "laser"])
def test_a_box_before_a_closed_door_is_passed_and_the_robot_waits_at_the_door_then_goes_on(perception):
    """A box on the path, a door 3 m beyond it that opens at 28 s: the robot goes round the box, waits
    within 0.5 m of the door while it is closed, and reaches the goal after it opens."""
    box = {"center": [2.0, 0.0], "size": [0.4, 0.4]}
    episode = run_episode(scenario_from_dict(_corridor(box, 28.0, 45.0)), perception=perception)
    trace, m = episode.trace, episode.metrics
    assert m["static_contact"] == 0 and not m["collision"] and m["time_outside_corridor_s"] == 0.0
    assert (_gap_to_door(trace.robot_poses[trace.times_s < 28.0]) > 0.0).all()
    waiting = (trace.times_s > 25.0) & (trace.times_s < 28.0)
    gap = _gap_to_door(trace.robot_poses[waiting])
    assert (gap > 0.0).all() and (gap <= 0.5).all(), (gap.min(), gap.max())
    assert (trace.robot_speeds_mps[waiting] < 0.02).all()  # at rest before the door
    assert "blocked" in set(np.asarray(trace.plan_status)[waiting])
    assert m["reached_goal"]  # and on once it opened


@pytest.mark.parametrize("perception", ["oracle", "laser"])
def test_a_box_beside_the_path_before_a_door_that_stays_closed(perception):
    """A box off to one side (still across the robot's way on the path line), a door that never opens: the
    robot goes past the box on its free side and waits within 0.5 m of the door to the end."""
    box = {"center": [2.5, 0.45], "size": [0.6, 0.6]}
    episode = run_episode(scenario_from_dict(_corridor(box, None, 32.0)), perception=perception)
    trace, m = episode.trace, episode.metrics
    assert m["static_contact"] == 0 and not m["collision"] and m["time_outside_corridor_s"] == 0.0
    assert not m["reached_goal"]
    assert (_gap_to_door(trace.robot_poses) > 0.0).all()
    gap = _gap_to_door(trace.robot_poses[trace.times_s > 27.0])
    assert (gap <= 0.5).all(), gap.max()
    assert trace.plan_status[-2] == "blocked"
    assert m["blocked_s"] >= 3.0


@pytest.mark.parametrize("perception", ["oracle", "laser"])
def test_a_box_just_past_the_corner_of_an_l_corridor_is_passed(perception):
    """The tutorial's L-shaped corridor with a box 2.5 m past the corner, 0.5 m right of the path: the robot
    turns the corner and passes the box on its left (the wider side) to the goal."""
    scene = {
        "name": "l-corridor-box",
        "robot": {"start": [0, 0], "heading": 0, "radius": RADIUS, "speed": 0.3},
        "path": {"waypoints": [[0, 0], [5, 0], [5, 4]], "half_width": 1.0},
        "duration_s": 50.0,
        "walls": L_WALLS,
        "boxes": [L_BOX],
    }
    episode = run_episode(scenario_from_dict(scene), perception=perception)
    trace, m = episode.trace, episode.metrics
    assert m["static_contact"] == 0 and not m["collision"] and m["time_outside_corridor_s"] == 0.0
    assert m["reached_goal"]
    beside = np.abs(trace.robot_poses[:, 1] - 2.5) < 0.2
    assert (trace.robot_poses[beside, 0] < 5.3 - RADIUS).all()  # left of the box as it passed


def _cycle(shapes, waypoints, position, heading=0.0):
    path = DesignatedPath(waypoints, half_width_m=1.0)
    planner = make_planner("viapath", path, nominal_speed_mps=0.3)
    robot = RobotState(np.array(position, float), heading, 0.0, 0.0, RADIUS)
    return planner.plan(Observation(0.0, robot, Obstacles.empty(), StaticLayer.of_shapes(shapes)))


def test_a_subgoal_the_flood_reaches_is_not_blocked():
    """The cycle at the start of the L corridor: the tree's legs run on along the next segment past the box, so
    alone it finds nothing; the flood reaches the corner, and the robot drives for it."""
    shapes = [polyline_edges(w["points"]) for w in L_WALLS] + [box_edges(L_BOX["center"], L_BOX["size"])]
    decision = _cycle(shapes, [[0, 0], [5, 0], [5, 4]], [0.0, 0.0])
    assert decision.plan.status in ("straight", "avoid"), decision.plan.status
    assert decision.command.speed_mps > 0.0
    assert "detour" in decision.plan.extras


def test_a_closed_way_sends_the_robot_round_the_box_towards_the_door():
    """The first cycle before the box and the closed door: not a stop at the box but a drive for the farthest
    point the flood reaches, ``blocked_gap_m`` (0.3 m) beyond the check radius short of the door."""
    shapes = [box_edges([2.0, 0.0], [0.4, 0.4]), polyline_edges(DOOR)] + [polyline_edges(w["points"]) for w in SIDES]
    decision = _cycle(shapes, [[0.0, 0.0], [7.0, 0.0]], [0.0, 0.0])
    plan = decision.plan
    assert plan.status == "blocked" and decision.command.speed_mps > 0.0
    wait_at = np.array(plan.extras["wait_at"])
    gap = _gap_to_door(wait_at[None])[0]
    assert 0.3 < gap <= 0.5, gap
    line = np.asarray(plan.waypoints)  # the way there keeps clear of the box
    samples = np.concatenate([np.linspace(a, b, 20) for a, b in zip(line[:-1], line[1:], strict=True)])
    assert point_segment_distances(samples, shapes[0]).min() - RADIUS >= 0.05 - 1e-6
