"""viapath.bench.feasibility, the robot's forward reachable set over the people's recorded future: answers
known by hand (an empty corridor, a wall of people, a gap or a door that opens at a known time), every
contact-free run of the drive inside the set (brute force), and the avoidable search's verdicts."""

import math

import numpy as np
import pytest

from tests.bench.test_avoidable import _head_on_trace
from viapath.bench.avoidable import _touching, drive, judge
from viapath.bench.feasibility import Grid, episode_columns, forward_reachable, scenario_reach
from viapath.observation import MotionLimits
from viapath.path import DesignatedPath
from viapath.static import point_segment_distances

DT, SPEED, CELL, TOLERANCE = 0.1, 0.5, 0.1, 0.1
PATH = DesignatedPath([[0.0, 0.0], [10.0, 0.0]], half_width_m=1.0)


def _sweep(people, radii, steps=400, **keywords):
    people = np.asarray(people, dtype=float)
    if people.ndim == 2:  # one row of people for every step
        people = np.repeat(people[None], steps, axis=0)
    return forward_reachable(
        people.reshape(len(people), -1, 2),
        np.asarray(radii, dtype=float),
        0.25,
        keywords.pop("path", PATH),
        keywords.pop("start", [0.0, 0.0]),
        SPEED,
        DT,
        goal=keywords.pop("goal", [10.0, 0.0]),
        goal_tolerance_m=TOLERANCE,
        cell_m=CELL,
        **keywords,
    )


def _arrival_bounds(distance_m):
    """The relaxed robot's true earliest arrival over ``distance_m`` to the goal's tolerance, and the
    earliest the grid may say: one cell diagonal and one step earlier."""
    exact = math.ceil((distance_m - TOLERANCE) / (SPEED * DT) - 1e-9) * DT
    return exact - CELL * math.sqrt(2) / SPEED - DT, exact


def _wall_of_people(x=5.0, spacing=0.3):
    ys = np.arange(-1.2, 1.21, spacing)
    return np.stack([np.full(len(ys), x), ys], axis=1)


def test_an_empty_corridor_is_crossed_at_top_speed_to_a_cell():
    reach = _sweep(np.zeros((0, 2)), [])
    low, exact = _arrival_bounds(10.0)
    assert reach.feasible and low <= reach.arrival_s <= exact + 1e-9, reach.arrival_s
    # a path with a corner: no faster than the straight line from the start, no slower than along the path
    bent = DesignatedPath([[0.0, 0.0], [5.0, 0.0], [5.0, 5.0]], half_width_m=1.0)
    reach = _sweep(np.zeros((0, 2)), [], path=bent, goal=[5.0, 5.0])
    assert reach.feasible and _arrival_bounds(math.hypot(5, 5))[0] <= reach.arrival_s <= _arrival_bounds(10.0)[1]


def test_a_wall_of_people_for_the_whole_episode_makes_it_infeasible():
    wall = _wall_of_people()
    reach = _sweep(wall, np.full(len(wall), 0.25))
    assert not reach.feasible and reach.arrival_s is None
    assert reach.emptied_s is None  # the robot may wait before the wall: only the goal is out of reach
    # the same people 0.8 m apart leave gaps wider than the robot: feasible, barely slower than empty
    sparse = _wall_of_people(spacing=1.3)
    assert _sweep(sparse, np.full(len(sparse), 0.25)).feasible


@pytest.mark.parametrize("opens_at_s", [15.0, 25.0])
def test_a_gap_that_opens_at_a_known_time_is_crossed_then(opens_at_s):
    wall = _wall_of_people()
    people = np.repeat(wall[None], 500, axis=0)
    people[int(round(opens_at_s / DT)) :] = np.nan  # everyone steps out of the scene
    reach = _sweep(people, np.full(len(wall), 0.25))
    # The robot waits where the wall's inflated discs (0.5 m) begin, 4.5 m from the goal's line... and
    # may stand half a cell closer on the grid: from there 10 - 4.5 m to go after the opening.
    low, exact = _arrival_bounds(10.0 - 4.5)
    assert reach.feasible
    assert opens_at_s + low - 2 * CELL / SPEED <= reach.arrival_s <= opens_at_s + exact + 1e-9, reach.arrival_s


def test_static_geometry_closes_the_corridor_until_a_door_opens():
    door = np.array([[[5.0, -1.5], [5.0, 1.5]]])
    closed = _sweep(np.zeros((0, 2)), [], walls=door)
    assert not closed.feasible and closed.emptied_s is None
    opened = _sweep(np.zeros((0, 2)), [], walls=door, wall_until_s=np.array([20.0]))
    low, exact = _arrival_bounds(10.0 - 4.75)  # waiting 0.25 m (the robot's radius) before the door
    assert opened.feasible and 20.0 + low - 2 * CELL / SPEED <= opened.arrival_s <= 20.0 + exact + 1e-9


def test_a_person_on_the_start_who_stays_there_empties_the_set_at_once():
    reach = _sweep(np.array([[0.0, 0.0]]), [1.0])
    assert not reach.feasible and reach.emptied_s == 0.0


def _sample_free(points, people, reach_m, path, walls, robot_radius_m):
    """(J,) whether the robot centre at ``points[j]`` is clear at sample j: inside the corridor, no
    person's disc inflated by the robot's radius, no static edge nearer than the radius (brute force)."""
    gap = points[:, None, :] - people
    with np.errstate(invalid="ignore"):
        clear = ~(np.hypot(gap[..., 0], gap[..., 1]) < reach_m).any(axis=1)
    inside = path.corridor_excess(points) <= 0.0
    if len(walls):
        clear &= (point_segment_distances(points, walls) >= robot_radius_m).all(axis=1)
    return clear & inside


def test_every_contact_free_run_of_the_drive_stays_inside_the_set():
    # A crowd crossing a corridor with a box in it; 3000 random command sequences of the drive (speed and
    # turn-rate targets changing every 0.5 s). Every run clear of everyone up to a step is in the set at
    # every step until then: the grid never drops a run the robot has.
    rng = np.random.default_rng(4)
    steps, n = 120, 14
    times = np.arange(steps) * DT
    starts = np.stack([rng.uniform(1.0, 9.0, n), rng.choice([-2.5, 2.5], n)], axis=1)
    velocity = np.stack([rng.uniform(-0.4, 0.4, n), -np.sign(starts[:, 1]) * rng.uniform(0.3, 1.2, n)], axis=1)
    people = starts[None] + times[:, None, None] * velocity[None]
    people[rng.random((steps, n)) < 0.02] = np.nan  # people missing in some samples
    radii = rng.uniform(0.15, 0.35, n)
    walls = np.array([[[6.0, -0.2], [6.6, -0.2]], [[6.6, -0.2], [6.6, 0.3]], [[6.6, 0.3], [6.0, 0.3]]])
    reach = _sweep(people, radii, walls=walls, goal=None, keep=True, start=[0.5, 0.0])
    limits = MotionLimits(max_speed_mps=SPEED)
    runs = 3000
    state = np.tile([0.5, 0.0, 0.0, 0.0, 0.0], (runs, 1))
    state[:, 2] = rng.uniform(-math.pi, math.pi, runs)
    holds = int(0.5 / DT)
    targets_v = np.repeat(rng.choice([0.0, 0.25, SPEED], (runs, steps // holds)), holds, axis=1)[:, : steps - 1]
    targets_w = np.repeat(rng.uniform(-1.0, 1.0, (runs, steps // holds)), holds, axis=1)[:, : steps - 1]
    poses, _, _ = drive(state, targets_v, targets_w * limits.max_turn_rate_radps, limits, DT)
    checked = 0
    for run in range(runs):
        points = poses[run, :, :2]
        free = _sample_free(points, people, radii + 0.25, PATH, walls, 0.25)
        clear_until = len(free) if free.all() else int(np.argmin(free))
        inside = np.array([reach.contains(k, points[k]) for k in range(clear_until)])
        assert inside.all(), (run, np.flatnonzero(~inside)[:3])
        checked += clear_until
    assert checked > 0.3 * runs * steps  # most samples were clear, so the claim was tested widely


def test_the_set_and_the_avoidable_search_agree_on_head_on_contacts():
    # The avoidable search's constructed head-on contacts (tests/bench/test_avoidable.py) in a corridor
    # that the person's inflated disc fills (half-width 0.3 m < 0.55 m): only retreating along it helps.
    # A person appearing 1 m ahead at 1.6 m/s: the search finds no sequence of the drive without an
    # at-fault onset, and even the relaxed robot (0.5 m/s backwards) cannot keep clear of them: the set
    # empties. A walker at 0.3 m/s appearing 4 m ahead: avoidable, and the set keeps a clear way.
    path = DesignatedPath([[-10.0, 0.0], [12.0, 0.0]], half_width_m=0.3)
    for distance_m, walker_mps, robot_mps, avoidable in ((1.0, 1.6, 0.3, False), (4.0, 0.3, 0.6, True)):
        trace = _head_on_trace(distance_m, robot_speed_mps=robot_mps, person_speed_mps=walker_mps, brake=False)
        (verdict,) = judge(trace, MotionLimits())
        assert verdict.avoidable is avoidable
        appeared = int(round(verdict.appeared_s / trace.dt_s))
        reach = forward_reachable(
            trace.obstacle_positions[appeared:],
            trace.obstacle_radii_m,
            trace.robot_radius_m,
            path,
            trace.robot_poses[appeared, :2],
            MotionLimits().max_speed_mps,
            trace.dt_s,
            keep=True,
        )
        assert (reach.emptied_s is None) is avoidable, reach
        if not avoidable:
            # every run of the drive from that state touches the person by then (brute force)
            limits = MotionLimits()
            rng = np.random.default_rng(0)
            steps = int(round(reach.emptied_s / trace.dt_s)) + 1
            state = np.tile([*trace.robot_poses[appeared], trace.robot_speeds_mps[appeared], 0.0], (500, 1))
            targets_v = rng.uniform(0, limits.max_speed_mps, (500, steps))
            targets_w = rng.uniform(-1, 1, (500, steps)) * limits.max_turn_rate_radps
            poses, _, _ = drive(state, targets_v, targets_w, limits, trace.dt_s)
            person = trace.obstacle_positions[appeared : appeared + steps + 1, 0]
            offsets = poses[:, :, :2] - person[None]
            touching = _touching(offsets[:, :-1, None], offsets[:, 1:, None], np.array([0.55]))
            assert touching.any(axis=(1, 2)).all()


def test_grid_cells_and_distances():
    grid = Grid(0.0, 0.0, 0.5, 4, 6)
    row, column = grid.cell_of(np.array([[0.1, 0.1], [2.9, 1.9], [3.1, 0.0], [-0.1, 0.0]]))
    assert row.tolist() == [0, 3, -1, -1] and column.tolist() == [0, 5, -1, -1]
    distance = grid.distance_to_cells([0.25, 0.25])
    assert (
        distance[0, 0] == 0.0
        and distance[0, 2] == pytest.approx(0.75)
        and distance[2, 2] == pytest.approx(math.hypot(0.75, 0.75))
    )


def test_scenario_columns_and_reactive_people_are_not_applicable():
    from viapath.scenarios.loader import load_scenario

    scenario = load_scenario("paper-front")
    reach = scenario_reach(scenario)
    assert reach.feasible and reach.arrival_s > 0
    row = episode_columns(scenario, reached_goal=True, collision=False, time_to_goal_s=2 * reach.arrival_s)
    assert row["feasible"] and row["success_feasible"] and row["reach_feasible"]
    assert row["time_ratio_hindsight"] == pytest.approx(2.0)
    row = episode_columns(scenario, reached_goal=True, collision=True, time_to_goal_s=2 * reach.arrival_s)
    assert row["success_feasible"] is False and row["reach_feasible"] is True
    replay = {"replay": {"file": "x.txt", "react": True}}
    reactive = scenario.model_copy(
        update={
            "obstacles": [type(scenario).model_validate({**scenario.model_dump(), "obstacles": [replay]}).obstacles[0]]
        }
    )
    assert all(value is None for value in episode_columns(reactive, True, False, 10.0).values())


@pytest.mark.parametrize("name", ["paper-front", "paper-side", "corner-person", "doorway"])
def test_no_episode_without_contact_arrives_before_the_sets_earliest_arrival(name):
    from viapath.scenarios.loader import load_scenario
    from viapath.sim.loop import run_episode

    scenario = load_scenario(name)
    reach = scenario_reach(scenario)
    metrics = run_episode(scenario).metrics
    assert reach.feasible and metrics["reached_goal"] and not metrics["collision"]
    assert reach.arrival_s <= metrics["time_to_goal_s"]


def test_a_person_present_at_a_single_sample_blocks_nothing():
    # The metrics count a contact in a step with the person present at both ends: a wall of people seen
    # at isolated samples only (every other step) can never be touched.
    wall = _wall_of_people()
    people = np.full((400, len(wall), 2), np.nan)
    people[::2] = wall
    assert _sweep(people, np.full(len(wall), 0.25)).feasible
    people[1::4] = wall  # now present at consecutive samples 0-1, 4-5, ...: touchable there
    assert not _sweep(people, np.full(len(wall), 0.25)).feasible
