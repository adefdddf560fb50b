"""The neutral scene (viapath.viz.scene): x-y-t cylinders where the true future puts them, the plan's
times checked against the planner's own geometry, and the cone's shape."""

from __future__ import annotations

import numpy as np
import pytest

from viapath.observation import Command, Obstacles
from viapath.planning.base import Decision, Plan
from viapath.scenarios import load_scenario
from viapath.sim.obstacles import scenario_obstacle_states
from viapath.viz.scene import ForecastSettings, PersonForecast, SceneBuilder, XYTScene, plan_xyt
from viapath.viz.xyt_plot import episode_and_scenes


def _scenes(name: str, **kwargs):
    scenario = load_scenario(name)
    episode, scenes = episode_and_scenes(
        scenario, "oracle", seed=0, position_noise_m=0.0, velocity_noise_mps=0.0, **kwargs
    )
    return scenario, episode, scenes


@pytest.fixture(scope="module")
def front():
    return _scenes("paper-front")


def test_one_scene_per_planning_cycle(front):
    _, episode, scenes = front
    trace = episode.trace
    # Every row but the last (which has no planning cycle) is one cycle.
    assert len(scenes) == len(trace.times_s) - 1
    np.testing.assert_allclose([s.time_s for s in scenes], trace.times_s[:-1])
    np.testing.assert_allclose(np.array([s.robot_pose for s in scenes]), trace.robot_poses[:-1])


def test_xyt_cylinders_are_where_the_true_future_puts_the_person(front):
    """With exact perception of a constant-velocity person, the cylinder's centre at height t is the
    person's true position t seconds later (from the scenario's motion model, not the planner)."""
    scenario, _episode, scenes = front
    robot_radius = scenario.robot.radius
    checked = 0
    for scene in scenes[::10]:
        if not scene.xyt.persons:
            continue
        offsets = np.linspace(0.0, scene.xyt.settings.horizon_s, 6)
        positions, _, radii = scenario_obstacle_states(scenario, scene.time_s + offsets)
        for index, person in enumerate(scene.xyt.persons):
            np.testing.assert_allclose(person.centre_at(offsets), positions[:, person.id], atol=1e-9)
            rings = scene.xyt.rings(index)
            for ring in rings:
                t = ring[0, 2]
                truth, _, _ = scenario_obstacle_states(scenario, np.array([scene.time_s + t]))
                distance = np.hypot(*(ring[:, :2] - truth[0, person.id]).T)
                np.testing.assert_allclose(distance, radii[person.id] + robot_radius, atol=1e-9)
            checked += 1
    assert checked >= 3


def test_via_points_lie_on_the_inflated_cylinder_at_their_time(front):
    """The via points' times come from the plan's speed; the planner computed each via point on the
    obstacle's disc grown by its margins at the passing time. If the times were wrong, the via
    point would not lie on that cylinder at that height."""
    scenario, _, scenes = front
    from viapath.safety import ShieldConfig
    from viapath.scenarios.loader import planner_settings

    settings = planner_settings(scenario)
    avoiding = [s for s in scenes if len(s.xyt.via_points_xyt)]
    assert avoiding, "paper-front should make the robot pass the person through via points"
    for scene in avoiding[:20]:
        # With the shield behind it (on by default) the planner keeps its braking envelope as well.
        stop_s = 0.1 + scene.plan.speed_mps / scenario.robot.limits.max_accel_mps2
        envelope = 0.5 * ShieldConfig().person_accel_mps2 * stop_s**2
        grown = settings.safety_margin_m + settings.planning_margin_m + envelope
        previous = None
        for x, y, t in scene.xyt.via_points_xyt:
            distances = [np.hypot(*(np.array([x, y]) - p.centre_at(t))) for p in scene.xyt.persons]
            gaps = [abs(d - (p.combined_radius_m + grown)) for d, p in zip(distances, scene.xyt.persons)]
            if min(gaps) >= 1e-6 and previous is not None:
                # A via point chained from one already that close to the person goes round it
                # tangentially: at 98 % of the previous via point's distance (geometry.via_options).
                px, py, pt = previous
                before = [np.hypot(*(np.array([px, py]) - p.centre_at(pt))) for p in scene.xyt.persons]
                gaps = [abs(d - 0.98 * b) for d, b in zip(distances, before)]
            assert min(gaps) < 1e-6
            previous = (x, y, t)
        # The plan starts at the robot at t = 0 and time never runs backwards.
        line = scene.xyt.plan_xyt
        np.testing.assert_allclose(line[0], [*scene.robot_pose[:2], 0.0], atol=1e-9)
        assert np.all(np.diff(line[:, 2]) >= -1e-12)
        assert line[-1, 2] <= scene.xyt.settings.horizon_s + 1e-9


def test_a_plan_that_waits_stands_then_drives_at_the_speed_after():
    start, goal = np.array([0.0, 0.0]), np.array([3.0, 0.0])
    plan = Plan("wait", 0.0, goal, waypoints=np.array([start, goal]), extras={"slow_s": 2.0, "speed_after_mps": 0.5})
    line = plan_xyt(start, plan, horizon_s=10.0)
    # Where the robot is at t: at the start until 2 s, then 0.5 m/s along the line, arriving at 2 + 6 s.
    for t in (0.0, 1.0, 2.0, 4.0, 8.0):
        expected_x = 0.0 if t <= 2.0 else min(3.0, 0.5 * (t - 2.0))
        assert np.interp(t, line[:, 2], line[:, 0]) == pytest.approx(expected_x, abs=1e-9)
    assert line[-1, 2] == pytest.approx(8.0)
    slow = Plan("slow", 0.1, goal, waypoints=np.array([start, goal]), extras={"slow_s": 5.0, "speed_after_mps": 0.4})
    line = plan_xyt(start, slow, horizon_s=6.0)  # 0.5 m in 5 s, then 0.4 m in the last second
    assert line[-1, 2] == pytest.approx(6.0)
    assert line[-1, 0] == pytest.approx(0.9)


def test_cone_grows_until_the_cap_and_its_mesh_is_exact():
    settings = ForecastSettings(horizon_s=10.0, uncertainty_sigmas=2.0, max_inflation_m=0.15)
    person = PersonForecast(7, np.array([1.0, 2.0]), np.array([-0.3, 0.1]), 0.25, 0.5, 0.0, 0.025)
    scene = XYTScene(settings, [person], np.zeros((0, 3)), np.zeros((0, 3)))
    # 2 σ · t = 0.05 t reaches 0.15 m at 3 s.
    np.testing.assert_allclose(person.ring_times_s(settings), [0.0, 3.0, 10.0])
    np.testing.assert_allclose(person.radius_at([0.0, 1.0, 3.0, 10.0], settings), [0.5, 0.55, 0.65, 0.65])
    np.testing.assert_allclose(person.radius_at([10.0], settings, cone=False), [0.5])
    triangles = scene.mesh(0, segments=16)
    vertices = triangles.reshape(-1, 3)
    centres = person.centre_at(vertices[:, 2])
    distance = np.hypot(*(vertices[:, :2] - centres).T)
    expected = person.radius_at(vertices[:, 2], settings)
    # Every vertex is on the surface or at a cap's centre.
    assert np.all((np.abs(distance - expected) < 1e-9) | (distance < 1e-9))
    assert set(np.round(vertices[:, 2], 9)) == {0.0, 3.0, 10.0}


def test_runner_up_and_shield_count():
    settings = ForecastSettings()
    from viapath.path import DesignatedPath

    builder = SceneBuilder(DesignatedPath([[0, 0], [5, 0]], half_width_m=1.0), 0.25, settings)
    from viapath.observation import Observation, RobotState

    observation = Observation(0.0, RobotState(np.zeros(2), 0.0, 0.2), Obstacles.empty())
    plan = Plan(
        "avoid",
        0.2,
        np.array([1.0, 0.0]),
        candidate_costs=np.array([0.7, 0.2, np.inf, 0.4]),
        chosen=1,
        extras={"shield": {"intervened": True}},
    )
    first = builder.build(0, 0.0, (0, 0, 0), 0.2, 0.0, observation, Decision(Command(0.2, 0.0), plan))
    assert (first.plan.chosen, first.plan.runner_up) == (1, 3)
    assert first.plan.runner_up_cost == pytest.approx(0.4)
    assert first.series["shield_interventions"] == 1
    calm = Plan("straight", 0.2, np.array([1.0, 0.0]))
    second = builder.build(1, 0.1, (0, 0, 0), 0.2, 0.0, observation, Decision(Command(0.2, 0.0), calm))
    assert second.series["shield_interventions"] == 1
    assert second.plan.runner_up is None


def test_cost_terms_are_published_when_the_planner_gives_them():
    """After the planner redesign, extras["cost_terms"] holds the per-term breakdown: the costs
    message carries it for the chosen and the runner-up candidate, beside their totals."""
    from viapath.observation import Observation, RobotState
    from viapath.path import DesignatedPath
    from viapath.viz.foxglove import costs_message

    builder = SceneBuilder(DesignatedPath([[0, 0], [5, 0]], half_width_m=1.0), 0.25)
    observation = Observation(0.0, RobotState(np.zeros(2), 0.0, 0.2), Obstacles.empty())
    terms = {
        "chosen": {"distance": 0.5, "time": 0.02, "speed": 0.0, "heading": 0.1},
        "runner_up": {"distance": 0.52, "time": 0.03, "speed": 0.008, "heading": np.inf},
    }
    plan = Plan(
        "avoid",
        0.2,
        np.array([1.0, 0.0]),
        candidate_costs=np.array([0.62, 0.9, 0.7]),
        chosen=0,
        extras={"cost_terms": terms},
    )
    message = costs_message(builder.build(0, 0.0, (0, 0, 0), 0.2, 0.0, observation, Decision(Command(0.2, 0.0), plan)))
    assert message["terms_available"] is True
    assert message["chosen"] == {"index": 0, "E": 0.62, "terms": terms["chosen"]}
    assert message["runner_up"]["index"] == 2 and message["runner_up"]["E"] == pytest.approx(0.7)
    assert message["runner_up"]["terms"]["heading"] is None  # not finite: JSON null
    assert message["margin"] == pytest.approx(0.08)
    import json

    json.dumps(message, allow_nan=False)  # valid JSON for Foxglove


def test_a_plan_that_stops_stands_for_the_whole_horizon():
    start = np.array([1.0, 2.0])
    plan = Plan("stop", 0.0, start, waypoints=np.array([start, start + [2.0, 0.0]]))
    line = plan_xyt(start, plan, horizon_s=7.0)
    np.testing.assert_allclose(line, [[1.0, 2.0, 0.0], [1.0, 2.0, 7.0]])


def test_lateral_deviation_of_one_point_is_the_paths():
    """The scene's scalar lateral deviation (one point per cycle) is DesignatedPath's, to rounding."""
    from viapath.path import DesignatedPath
    from viapath.viz.scene import lateral_deviation_m

    rng = np.random.default_rng(0)
    for _ in range(100):
        waypoints = np.cumsum(rng.normal(size=(rng.integers(2, 6), 2)) * 3, axis=0)
        path = DesignatedPath(waypoints, half_width_m=1.0)
        segments = list(
            zip(path.segment_starts.tolist(), path.segment_directions.tolist(), path.segment_lengths_m.tolist())
        )
        for point in rng.normal(size=(20, 2)) * 5:
            assert lateral_deviation_m(segments, *point.tolist()) == pytest.approx(
                float(path.lateral_deviation(point)), abs=1e-12
            )
