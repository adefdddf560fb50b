"""Progress through the static world in the closed loop: a box before a closed door, a box beside the path
before a door, a box just past the corner of an L-shaped corridor (the built-in scenarios box-before-door,
box-beside-door, l-corridor-box); oracle and laser. The robot goes round
the box and waits near the door (or goes on when it opens), never touching anything."""

from __future__ import annotations

import numpy as np
import pytest

from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.planning import make_planner
from viapath.scenarios.loader import load_scenario
from viapath.sim.loop import run_episode
from viapath.static import StaticLayer, point_segment_distances

RADIUS = 0.25  # the robot's, in each of these scenarios
DOOR = [[5.0, -1.3], [5.0, 1.3]]  # box-before-door's and box-beside-door's door


def _gap_to_door(poses: np.ndarray) -> np.ndarray:
    """The robot's surface to the door (m)."""
    return point_segment_distances(poses[:, :2], np.array([DOOR], float))[:, 0] - RADIUS


@pytest.mark.parametrize("perception", ["oracle", "laser"])
def test_a_box_before_a_closed_door_is_passed_and_the_robot_waits_at_the_door_then_goes_on(perception):
    """A box on the path, a door 3 m beyond it that opens at 28 s: the robot goes round the box, waits
    within 0.5 m of the door while it is closed, and reaches the goal after it opens."""
    episode = run_episode(load_scenario("box-before-door"), perception=perception)
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
    robot goes round the box on its free (right) side and waits within 0.5 m of the door to the end."""
    episode = run_episode(load_scenario("box-beside-door"), perception=perception)
    trace, m = episode.trace, episode.metrics
    assert m["static_contact"] == 0 and not m["collision"] and m["time_outside_corridor_s"] == 0.0
    beside = np.abs(trace.robot_poses[:, 0] - 2.5) < 0.3  # the box spans y 0.15 to 0.75 there
    assert beside.any() and (trace.robot_poses[beside, 1] < 0.15 - RADIUS).all()
    assert not m["reached_goal"]
    assert (_gap_to_door(trace.robot_poses) > 0.0).all()
    gap = _gap_to_door(trace.robot_poses[trace.times_s > 27.0])
    assert (gap <= 0.5).all(), gap.max()
    assert trace.plan_status[-2] == "blocked"
    assert m["blocked_s"] >= 3.0


@pytest.mark.parametrize("perception", ["oracle", "laser"])
def test_a_box_just_past_the_corner_of_an_l_corridor_is_passed(perception):
    """The tutorial's L-shaped corridor with a box 2.5 m past the corner, 0.5 m right of the path: the robot
    turns the corner and goes round the box on the left (the wider side) to the goal."""
    episode = run_episode(load_scenario("l-corridor-box"), perception=perception)
    trace, m = episode.trace, episode.metrics
    assert m["static_contact"] == 0 and not m["collision"] and m["time_outside_corridor_s"] == 0.0
    assert m["reached_goal"]
    beside = np.abs(trace.robot_poses[:, 1] - 2.5) < 0.2
    assert (trace.robot_poses[beside, 0] < 5.3 - RADIUS).all()  # left of the box as it passed


def _first_cycle(name: str):
    """The planner's first cycle of a built-in scenario (the robot at its start, the shapes standing at 0 s)."""
    scenario = load_scenario(name)
    shapes = [edges for edges, _ in scenario.static_shapes()]
    return shapes, _cycle(shapes, scenario.path.waypoints, scenario.robot.start)


def _cycle(shapes, waypoints, position, heading=0.0):
    path = DesignatedPath(waypoints, half_width_m=1.0)
    planner = make_planner("viapath", path, nominal_speed_mps=0.3)
    robot = RobotState(np.array(position, float), heading, 0.0, 0.0, RADIUS)
    return planner.plan(Observation(0.0, robot, Obstacles.empty(), StaticLayer.of_shapes(shapes)))


def test_a_subgoal_the_flood_reaches_is_not_blocked():
    """The cycle at the start of the L corridor: the tree's legs run on along the next segment past the box, so
    alone it finds nothing; the flood reaches the corner, and the robot drives for it."""
    _, decision = _first_cycle("l-corridor-box")
    assert decision.plan.status in ("straight", "avoid"), decision.plan.status
    assert decision.command.speed_mps > 0.0
    assert "detour" in decision.plan.extras


def test_a_closed_way_sends_the_robot_round_the_box_towards_the_door():
    """The first cycle before the box and the closed door: not a stop at the box but a drive for the farthest
    point the flood reaches, ``blocked_gap_m`` (0.3 m) beyond the check radius short of the door."""
    shapes, decision = _first_cycle("box-before-door")
    box = shapes[-1]  # (walls first, then boxes)
    plan = decision.plan
    assert plan.status == "blocked" and decision.command.speed_mps > 0.0
    wait_at = np.array(plan.extras["wait_at"])
    gap = _gap_to_door(wait_at[None])[0]
    assert 0.3 < gap <= 0.5, gap
    line = np.asarray(plan.waypoints)  # the way there keeps clear of the box
    samples = np.concatenate([np.linspace(a, b, 20) for a, b in zip(line[:-1], line[1:], strict=True)])
    assert point_segment_distances(samples, box).min() - RADIUS >= 0.05 - 1e-6


def test_a_robot_waiting_at_a_door_floods_the_corridor_once(monkeypatch):
    """The flood is kept while the static world stays the same: a robot that spends most of the episode
    before a closed door floods the corridor's free space once, not once a cycle."""
    from viapath.planning.viapath import flood

    made = []
    original = flood.FreeSpace.of

    def counted(*arguments):
        made.append(1)
        return original(*arguments)

    monkeypatch.setattr(flood.FreeSpace, "of", staticmethod(counted))
    episode = run_episode(load_scenario("box-beside-door"), perception="oracle")
    blocked_cycles = int(np.sum(np.asarray(episode.trace.plan_status) == "blocked"))
    assert blocked_cycles >= 200 and len(made) == 1, (blocked_cycles, len(made))


@pytest.mark.parametrize("person", [[1.0, -0.3], [1.4, -0.5], [2.0, -0.6], [2.6, -0.5], [3.5, 0.0], [4.2, 0.3]])
def test_the_drive_to_the_door_keeps_clear_of_a_person_standing_on_the_way(person):
    """The closed way with someone standing on or near the flood's way round the box: whatever the robot does,
    the leg it drives (robot to the plan's target) keeps the person's disc and its own apart (brute force
    over points along the leg), and a plan that cannot is a stop."""
    scenario = load_scenario("box-before-door")
    shapes = [edges for edges, _ in scenario.static_shapes()]
    path = DesignatedPath(scenario.path.waypoints, half_width_m=1.0)
    planner = make_planner("viapath", path, nominal_speed_mps=0.4)
    robot = RobotState(np.zeros(2), 0.0, 0.0, 0.0, RADIUS)
    people = Obstacles(np.array([person], float), np.zeros((1, 2)), np.array([0.3]))
    decision = planner.plan(Observation(0.0, robot, people, StaticLayer.of_shapes(shapes)))
    if decision.command.speed_mps == 0.0:
        return
    leg = np.linspace(np.zeros(2), np.asarray(decision.plan.target, float), 200)
    assert np.hypot(*(leg - person).T).min() >= RADIUS + 0.3, decision.plan.status
