"""The static world in the closed loop: boxes, doors and walls with every planner, oracle and laser."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
from typer.testing import CliRunner

from viapath.cli import app
from viapath.perception.scanner import paper_scanners
from viapath.perception.static_layer import StaticLayerParams, StaticObstacleLayer, thin_runs
from viapath.scenarios.loader import ScenarioError, scenario_from_dict
from viapath.sim.loop import run_episode
from viapath.sim.metrics import static_clearance_per_step, static_contact_onsets
from viapath.static import point_segment_distances

CORRIDOR = {"waypoints": [[0.0, 0.0], [7.0, 0.0]], "half_width": 1.0}


def _scene(**extra) -> dict:
    return {
        "name": "static-test",
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.4, "radius": 0.25},
        "path": CORRIDOR,
        "duration_s": 40.0,
        **extra,
    }


BOX = _scene(
    boxes=[{"center": [3.0, 0.1], "size": [0.6, 0.6], "yaw": 0.3}],
    walls=[[[-1.0, 1.3], [8.0, 1.3]], {"points": [[-1.0, -1.3], [8.0, -1.3]]}],
)


@pytest.mark.parametrize("perception", ["oracle", "laser"])
def test_box_on_the_path_is_passed_without_contact(perception):
    episode = run_episode(scenario_from_dict(BOX), perception=perception)
    m = episode.metrics
    assert m["static_contact"] == 0 and not m["collision"]
    assert m["reached_goal"]
    assert m["min_static_clearance_m"] > 0.0
    assert m["time_outside_corridor_s"] == 0.0


@pytest.mark.parametrize("planner", ["dwa", "vo", "stop", "follow"])
def test_baselines_do_not_drive_into_a_box(planner):
    """Every planner gets the static layer (and the guard under it): none of them touches the box. (The
    box alone: with the walls too, dwa's contact checks against every wall's discs took 80-110 s here.)"""
    episode = run_episode(scenario_from_dict(_scene(boxes=BOX["boxes"], duration_s=25.0)), planner=planner)
    assert episode.metrics["static_contact"] == 0


def test_closed_door_stops_the_robot_short_of_it_and_it_goes_on_when_the_door_opens():
    door = {"points": [[4.0, -1.1], [4.0, 1.1]], "until_s": 20.0}
    episode = run_episode(scenario_from_dict(_scene(walls=[door])))
    trace, m = episode.trace, episode.metrics
    closed = trace.times_s < 20.0
    gap = point_segment_distances(trace.robot_poses[closed, :2], np.array([door["points"]], float))[:, 0] - 0.25
    assert m["static_contact"] == 0
    assert 0.0 < gap.min() <= 1.5  # waited near the door, not far from it
    assert "blocked" in trace.plan_status
    assert np.all(trace.robot_speeds_mps[(trace.times_s > 15.0) & (trace.times_s < 19.9)] < 0.02)  # at rest, waiting
    assert m["reached_goal"]  # and went on once it opened


def test_time_blocked_is_in_the_metrics_and_the_bench_table(tmp_path):
    """``blocked_s``: at least the time the robot stood before the closed door (measured from the speeds),
    at most until it opened; none without the door. The bench's table and --json carry it."""
    from viapath.bench.report import markdown_table, summarize

    door = {"points": [[4.0, -1.1], [4.0, 1.1]], "until_s": 20.0}
    episode = run_episode(scenario_from_dict(_scene(walls=[door])))
    m, trace = episode.metrics, episode.trace
    stood_s = np.count_nonzero((trace.robot_speeds_mps[:-1] < 0.01) & (trace.times_s[:-1] < 20.0)) * trace.dt_s
    assert stood_s > 5.0 and stood_s - 1e-9 <= m["blocked_s"] <= 20.0 + trace.dt_s
    free = run_episode(scenario_from_dict(_scene())).metrics
    assert free["blocked_s"] == 0.0
    rows = [{**metrics, "shield": "off", "error": "", "time_ratio": 1.0} for metrics in (m, free)]
    (summary,) = summarize(rows)
    assert summary["blocked_rate"] == 0.5 and summary["blocked_s_per_episode"] == pytest.approx(m["blocked_s"] / 2)
    header, _, row = markdown_table([summary]).splitlines()
    cells = dict(zip([c.strip() for c in header.split("|")], [c.strip() for c in row.split("|")]))
    assert cells["blocked"] == "50.0%" and cells["blocked [s/ep]"] == f"{m['blocked_s'] / 2:.1f}"


def test_walls_along_the_corridor_cost_no_time():
    open_run = run_episode(scenario_from_dict(_scene()))
    walled = run_episode(scenario_from_dict(_scene(walls=[[[-1.0, 1.2], [8.0, 1.2]], [[-1.0, -1.2], [8.0, -1.2]]])))
    assert walled.metrics["reached_goal"] and walled.metrics["static_contact"] == 0
    assert walled.metrics["time_to_goal_s"] <= 1.05 * open_run.metrics["time_to_goal_s"]


def test_static_contacts_are_counted_from_the_trace():
    """A robot moving through a wall counts one contact (its onset), and clearance is to the wall's edge."""
    poses = np.c_[np.linspace(0.0, 2.0, 21), np.zeros(21), np.zeros(21)]
    trace = SimpleNamespace(
        robot_poses=poses,
        robot_radius_m=0.25,
        times_s=np.arange(21) * 0.1,
        walls=np.array([[[1.0, -1.0], [1.0, 1.0]]]),
        wall_until_s=np.array([np.inf]),
    )
    clearance = static_clearance_per_step(trace)
    # brute force: distance of densely sampled robot positions to the wall, less the radius
    dense = np.c_[np.linspace(0.0, 2.0, 2001), np.zeros(2001)]
    assert np.isclose(clearance.min(), point_segment_distances(dense, trace.walls).min() - 0.25)
    onsets = static_contact_onsets(trace)
    assert onsets.sum() == 1 and clearance[np.argmax(onsets)] < 0 and clearance[np.argmax(onsets) - 1] >= 0
    trace.wall_until_s = np.array([0.5])  # the wall is gone before the robot gets there
    assert static_contact_onsets(trace).sum() == 0


def test_json_has_null_for_metrics_that_do_not_exist(tmp_path):
    import yaml

    scene = tmp_path / "empty.yaml"
    scene.write_text(yaml.safe_dump({**_scene(), "duration_s": 5.0}))
    for perception in ("oracle", "laser"):
        result = CliRunner().invoke(app, ["run", str(scene), "--json", "--perception", perception])
        assert result.exit_code == 0, result.output
        metrics = json.loads(result.stdout)  # nobody and nothing static: no clearance to anything
        assert metrics["min_clearance_m"] is None and metrics["min_static_clearance_m"] is None
        assert "NaN" not in result.stdout and "Infinity" not in result.stdout


def test_scenario_shapes_are_validated_with_the_field_named(tmp_path):
    with pytest.raises(ScenarioError, match=r"boxes\.0\.size"):
        scenario_from_dict(_scene(boxes=[{"center": [1.0, 0.0], "size": [-0.5, 0.5]}]))
    with pytest.raises(ScenarioError, match=r"polygons\.0\.points"):
        scenario_from_dict(_scene(polygons=[{"points": [[0.0, 0.0], [1.0, 0.0]]}]))
    with pytest.raises(ScenarioError, match=r"walls\.0"):
        scenario_from_dict(_scene(walls=[{"points": [[0.0, 0.0], [1.0, 0.0]], "until_s": -1.0}]))


# -- the laser's static layer ------------------------------------------------------------------------


def test_thinned_runs_cover_every_return():
    rng = np.random.default_rng(3)
    x = np.linspace(0.0, 4.0, 300)
    points = np.c_[x, 0.2 * np.sin(x) + rng.normal(0.0, 0.01, 300)]
    run = np.repeat([0, 1, 2], [150, 1, 149])
    segments, runs, radii = thin_runs(points, run, 0.15)
    assert set(runs.tolist()) == {0, 1, 2}
    distance = point_segment_distances(points, segments)
    same_run = run[:, None] == runs[None]
    covered = ((distance <= radii[None] + 1e-12) & same_run).any(axis=1)
    assert covered.all()
    assert len(segments) < 60 and radii.max() < 0.05


def _scan_with_return(scanner, bearing_rad: float, range_m: float, others_m: float = np.inf) -> np.ndarray:
    ranges = np.full(scanner.beam_count, others_m)
    beam = int(round((bearing_rad - scanner.angle_min_rad) / scanner.angle_increment_rad))
    ranges[beam - 2 : beam + 3] = range_m
    return ranges


def test_layer_remembers_what_is_hidden_and_clears_what_free_beams_pass():
    front, _rear = paper_scanners()
    layer = StaticObstacleLayer((front,), StaticLayerParams(memory_s=2.0))
    pose = np.zeros(3)
    seen = layer.update(0.0, pose, [_scan_with_return(front, 0.0, 2.0)], np.zeros((0, 2)), np.zeros(0))
    assert len(seen) >= 1 and np.allclose(seen.segments[:, :, 0], 2.0 + front.mount_x_m, atol=0.01)
    # Hidden behind something nearer: kept.
    hidden = layer.update(0.1, pose, [_scan_with_return(front, 0.0, 1.0)], np.array([[1.2, 0.0]]), np.array([0.3]))
    assert np.isclose(hidden.segments[:, :, 0].max(), 2.0 + front.mount_x_m, atol=0.01)
    # Still hidden, but older than memory_s: forgotten.
    old = layer.update(2.5, pose, [_scan_with_return(front, 0.0, 1.0)], np.array([[1.2, 0.0]]), np.array([0.3]))
    assert old.segments[:, :, 0].max() < 1.5 if len(old) else True
    # Seen again, then a free beam passes where it was: cleared.
    layer.update(3.0, pose, [_scan_with_return(front, 0.0, 2.0)], np.zeros((0, 2)), np.zeros(0))
    cleared = layer.update(3.1, pose, [np.full(front.beam_count, np.inf)], np.zeros((0, 2)), np.zeros(0))
    assert len(cleared) == 0


def test_layer_keeps_what_is_out_of_every_field_of_view_however_old():
    """A box seen ahead, then behind the robot where its one 240° scanner does not look (a blind sector,
    or a silent scanner's field): no beam can clear it, so it stays past ``memory_s`` (a robot standing
    beside a box would otherwise forget the box's side and turn into it); in view again and passed by a
    free beam, it is cleared."""
    front, _rear = paper_scanners()
    layer = StaticObstacleLayer((front,), StaticLayerParams(memory_s=2.0))
    ahead, behind = np.zeros(3), np.array([0.0, 0.0, np.pi])
    none = (np.zeros((0, 2)), np.zeros(0))
    free = [np.full(front.beam_count, np.inf)]
    seen = layer.update(0.0, ahead, [_scan_with_return(front, 0.0, 1.0)], *none)
    box_x = 1.0 + front.mount_x_m
    assert len(seen) >= 1 and np.allclose(seen.segments[:, :, 0], box_x, atol=0.01)
    for t in (1.0, 5.0, 30.0):
        kept = layer.update(t, behind, free, *none)
        assert len(kept) >= 1 and np.allclose(kept.segments[:, :, 0], box_x, atol=0.01), t
    assert len(layer.update(31.0, ahead, free, *none)) == 0


def test_a_tentative_track_on_a_box_does_not_take_the_box_out_of_the_layer():
    """The detector starts tentative tracks on a box's corners now and then; the box the layer knows stays
    in it while one sits there. A confirmed track there is a person: its returns are not static."""
    from viapath.perception.tracking import MultiTargetTracker

    front, _ = paper_scanners()
    layer = StaticObstacleLayer((front,))
    tracker = MultiTargetTracker()
    ranges = _scan_with_return(front, 0.0, 2.0)
    box_x = 2.0 + front.mount_x_m
    assert len(layer.update(0.0, np.zeros(3), [ranges], *tracker.explaining())) >= 1  # no track: a box
    on_the_box = np.array([[box_x + 0.1, 0.0]])
    tracker.step(0.1, on_the_box, 0.03, 0.3)  # born this cycle: tentative
    assert not tracker.confirmed.any()
    kept = layer.update(0.1, np.zeros(3), [ranges], *tracker.explaining())
    assert len(kept) >= 1 and np.allclose(kept.segments[:, :, 0], box_x, atol=0.01)
    for k in range(2, 5):  # confirmed after three hits: the returns are a person's
        tracker.step(0.1 * k, on_the_box, 0.03, 0.3)
    assert tracker.confirmed.all()
    assert len(layer.update(0.4, np.zeros(3), [ranges], *tracker.explaining())) == 0
    # A new person's first returns are explained by their tentative track: never a wall.
    fresh = MultiTargetTracker()
    fresh.step(0.0, on_the_box, 0.03, 0.3)
    assert len(StaticObstacleLayer((front,)).update(0.0, np.zeros(3), [ranges], *fresh.explaining())) == 0


def test_returns_of_a_tracked_person_are_not_static():
    front, _ = paper_scanners()
    layer = StaticObstacleLayer((front,))
    ranges = _scan_with_return(front, 0.0, 2.0)
    person_at = np.array([[2.0 + front.mount_x_m + 0.1, 0.0]])
    assert len(layer.update(0.0, np.zeros(3), [ranges], person_at, np.array([0.2]))) == 0
    assert len(StaticObstacleLayer((front,)).update(0.0, np.zeros(3), [ranges], np.zeros((0, 2)), np.zeros(0))) >= 1


def test_navground_peers_get_every_shape_as_static_discs():
    pytest.importorskip("navground.core", reason="needs the navground extra")
    from viapath.observation import Observation, Obstacles, RobotState
    from viapath.path import DesignatedPath
    from viapath.planning import make_planner
    from viapath.static import StaticLayer, box_edges

    scenario = scenario_from_dict(BOX)
    path = DesignatedPath(CORRIDOR["waypoints"], half_widths_m=[1.0])
    planner = make_planner("nav-orca", path, nominal_speed_mps=0.4)
    shapes = StaticLayer.of_shapes([edges for edges, _ in scenario.static_shapes()])
    person = Obstacles(np.array([[5.0, 0.0]]), np.array([[-0.3, 0.0]]), np.array([0.25]))
    planner.plan(Observation(0.0, RobotState(np.zeros(2), 0.0, 0.4), person, shapes))
    state = planner.behavior.environment_state
    assert len(state.neighbors) == 1
    discs = np.array([d.position for d in state.static_obstacles])
    assert len(discs) > 0
    # every edge of the box and both walls is covered by the discs handed over
    for edges in [box_edges([3.0, 0.1], [0.6, 0.6], 0.3)]:
        for a, b in edges:
            for f in np.linspace(0, 1, 7):
                point = a + f * (b - a)
                assert np.hypot(*(discs - point).T).min() <= 0.15


def test_a_scan_of_the_wrong_length_is_skipped_and_the_memory_kept():
    front, rear = paper_scanners()
    layer = StaticObstacleLayer((front, rear))
    none = (np.zeros((0, 2)), np.zeros(0))
    free_rear = np.full(rear.beam_count, np.inf)
    seen = layer.update(0.0, np.zeros(3), [_scan_with_return(front, 0.0, 2.0), free_rear], *none)
    assert len(seen) >= 1
    kept = layer.update(0.1, np.zeros(3), [np.full(10, 2.0), free_rear], *none)  # a torn front scan
    assert len(kept) >= 1 and np.allclose(kept.segments[:, :, 0], 2.0 + front.mount_x_m, atol=0.01)


def test_a_robot_within_the_planning_margin_of_a_box_goes_on_round_it():
    """Standing nearer to a box than the via points' radius (but clear of the check radius), the robot finds a
    way round it that never comes nearer than the safety margin."""
    from viapath import DesignatedPath, Observation, Obstacles, RobotState
    from viapath.planning import make_planner
    from viapath.static import StaticLayer, box_edges

    path = DesignatedPath([[0.0, 0.0], [6.0, 0.0]], half_width_m=1.5)
    planner = make_planner("viapath", path, nominal_speed_mps=0.3)
    box = box_edges([2.5, 0.0], [1.0, 0.6])
    margin = planner.config.planning_margin_m
    # The robot's surface within the planning margin of the box's top face, short of its safety margin.
    gap_m = 0.05 + 0.6 * margin
    robot = RobotState(np.array([2.2, 0.3 + 0.25 + gap_m]), 0.0, 0.3)
    static = StaticLayer.of_shapes([box])
    decision = planner.plan(Observation(0.0, robot, Obstacles.empty(), static))
    assert decision.plan.status not in ("blocked", "stop", "wait"), decision.plan.status
    assert decision.command.speed_mps > 0.0
    line = np.asarray(decision.plan.waypoints)
    samples = np.concatenate([np.linspace(a, b, 50) for a, b in zip(line[:-1], line[1:], strict=True)])
    clearance = point_segment_distances(samples, box).min() - 0.25
    assert clearance >= 0.05 - 1e-6, clearance  # never nearer than the safety margin
