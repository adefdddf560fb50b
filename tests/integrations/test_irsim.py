"""viapath selected by name in IR-SIM's own world files (behavior: {name: viapath}), judged by IR-SIM's
own arrival and collision flags; clearances measured independently on IR-SIM's geometry (shapely)."""

from __future__ import annotations

import copy
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("irsim", reason="IR-SIM is not installed (extra 'irsim': pip install -e '.[irsim]')")

from tests.integrations._irsim_helpers import EXAMPLES, run_world, write_world
from viapath.options import OptionError

CROSSING = EXAMPLES / "crossing.yaml"


def _world(file=CROSSING) -> dict:
    return yaml.safe_load(file.read_text())


def test_the_crossing_world_reaches_the_goal_without_a_collision():
    run = run_world(CROSSING)
    assert run.arrived and not run.collided
    assert run.min_clearance_m > 0.02
    assert np.abs(run.positions[:, 1]).max() <= 1.0  # inside the corridor (half-width 1 m) all along


def test_the_crossing_world_is_a_real_test_dash_collides(tmp_path):
    """IR-SIM's own dash behaviour, on the same world, runs into the box or a person."""
    world = _world()
    world["robot"][0]["behavior"] = {"name": "dash"}
    assert run_world(write_world(tmp_path, world), max_steps=400).collided


def _head_on_world(behavior: dict) -> dict:
    """viapath's paper-front scenario as an IR-SIM world: a person comes head-on at 0.3 m/s."""
    return {
        "world": {"height": 6, "width": 10, "step_time": 0.1, "sample_time": 0.1, "offset": [-2, -3]},
        "robot": [
            {
                "kinematics": {"name": "diff"},
                "shape": {"name": "circle", "radius": 0.25},
                "state": [0, 0, 0],
                "goal": [5, 0, 0],
                "vel_max": [0.6, 2.0],
                "acce": [0.8, 6.0],
                "behavior": {"name": "viapath", "nominal_speed_mps": 0.2, **behavior},
            }
        ],
        "obstacle": [
            {
                "kinematics": {"name": "omni"},
                "shape": {"name": "circle", "radius": 0.25},
                "state": [2, 0, 0],
                "goal": [-3, 0, 0],
                "vel_max": [0.3, 0.3],
                "behavior": {"name": "dash"},
            }
        ],
    }


def _viapath_own_side(preferred_side: str) -> float:
    from viapath.scenarios import load_scenario
    from viapath.sim.loop import run_episode

    episode = run_episode(load_scenario("paper-front"), planner_overrides={"preferred_side": preferred_side})
    y = episode.trace.robot_poses[:, 1]
    return float(y[np.argmax(np.abs(y))])


@pytest.mark.parametrize("side", ["left", "right"])
def test_preferred_side_in_the_world_file_passes_on_that_side_as_in_viapaths_own_scenario(tmp_path, side):
    run = run_world(write_world(tmp_path, _head_on_world({"preferred_side": side})))
    assert run.arrived and not run.collided
    y = run.positions[:, 1]
    widest = float(y[np.argmax(np.abs(y))])
    own = _viapath_own_side(side)
    assert np.sign(widest) == np.sign(own) == (1 if side == "left" else -1)
    assert abs(widest) > 0.3 and abs(own) > 0.3


@pytest.mark.parametrize(
    ("behavior", "field"),
    [
        ({"speedz": [0.1]}, "behavior.speedz"),
        ({"weights": {"k1": -1.0}}, "behavior.weights.k1"),
        ({"half_width_m": 0.0}, "behavior.half_width_m"),
        ({"preferred_side": "up"}, "behavior.preferred_side"),
        ({"preset": "fastest"}, "behavior.preset"),
        ({"path": [[0, 0]]}, "behavior.path"),
    ],
)
def test_a_bad_option_in_the_world_file_is_refused_naming_the_field(tmp_path, behavior, field):
    import irsim

    env = irsim.make(str(write_world(tmp_path, _head_on_world(behavior))), display=False, disable_all_plot=True)
    env.load_behavior("viapath.integrations.irsim")
    with pytest.raises(OptionError, match=field.replace(".", r"\.")):
        env.step()
    env.end(0)


def test_a_preset_applies_first_and_options_beside_it_win():
    from viapath.integrations.irsim import read_behavior
    from viapath.presets import preset_values

    paper = preset_values("paper")
    settings, path = read_behavior({"name": "viapath", "preset": "paper", "weights": {"k3": 0.5}})
    assert path is None
    assert settings["k2"] == paper["k2"] != read_behavior({})[0]["k2"]
    assert settings["k3"] == 0.5


def test_every_static_shape_reaches_the_static_layer_at_its_true_distance(tmp_path):
    """Polygons, rectangles, lines, static circles and a grid map: the distance from the robot to viapath's
    static layer (segments, padded) equals shapely's distance to IR-SIM's own geometry."""
    import irsim

    from viapath.integrations.irsim import people_of, static_of
    from viapath.static import point_segment_distances

    world = _head_on_world({})
    world["world"]["obstacle_map"] = "cave.png"
    world["world"].update({"height": 50, "width": 50, "offset": [0, 0]})
    world["robot"][0]["state"] = [20, 20, 0]
    world["robot"][0]["goal"] = [25, 20, 0]
    world["obstacle"] = [
        {"shape": {"name": "rectangle", "length": 0.6, "width": 0.4}, "state": [22, 20.2, 0.3]},
        {"shape": {"name": "polygon", "vertices": [[0, 0], [1, 0], [0.5, 0.8]]}, "state": [18, 21, 0]},
        {"shape": {"name": "linestring", "vertices": [[17, 18], [23, 18.5]]}, "state": [0, 0, 0]},
        {"shape": {"name": "circle", "radius": 0.4}, "state": [19, 19, 0]},
    ]
    import irsim.world.map as maps

    shutil.copy(Path(maps.__path__[0]) / "cave.png", tmp_path / "cave.png")  # the grid map IR-SIM ships
    env = irsim.make(str(write_world(tmp_path, world)), display=False, disable_all_plot=True)
    robot = env.robot
    people, layer = people_of(list(env.obstacle_list)), static_of(list(env.obstacle_list))
    assert len(people) == 0
    shapes = {obj.shape for obj in env.obstacle_list}
    assert {"rectangle", "polygon", "linestring", "circle", "map"} <= shapes
    assert len(np.unique(layer.shape_ids)) >= 5
    centre = np.asarray(robot.state[:2, 0], dtype=float)
    ours = float((point_segment_distances(centre[None], layer.segments)[0] - layer.padding_m).min())
    theirs = min(float(robot.geometry.centroid.distance(obj.geometry)) for obj in env.obstacle_list)
    assert ours == pytest.approx(theirs, abs=0.02)
    # Each shape on its own, at its own distance (none dropped, none merged into another).
    for k, obj in enumerate(env.obstacle_list):
        one = static_of([obj])
        assert len(one) > 0, obj.shape
        d = float((point_segment_distances(centre[None], one.segments)[0] - one.padding_m).min())
        assert d == pytest.approx(float(robot.geometry.centroid.distance(obj.geometry)), abs=0.02), (k, obj.shape)
    env.end(0)


def test_with_lidar_sensing_the_crossing_world_reaches_the_goal_without_a_collision(tmp_path, monkeypatch):
    """The robot's own IR-SIM lidar through viapath's laser chain: the people are tracked as people (moving
    rows with their velocity), and the robot reaches the goal without a collision."""
    from viapath.integrations.irsim import ViapathBehavior

    seen_moving = []
    observe = ViapathBehavior.observation

    def recording(self, ego, external_objects, time_s):
        observation = observe(self, ego, external_objects, time_s)
        people = observation.obstacles.people()
        seen_moving.append(int((np.hypot(*people.velocities.T) > 0.2).sum()) if len(people) else 0)
        return observation

    monkeypatch.setattr(ViapathBehavior, "observation", recording)
    world = copy.deepcopy(_world())
    robot = world["robot"][0]
    robot["behavior"]["sensing"] = "lidar"
    robot["sensors"] = [{"name": "lidar2d", "range_min": 0.05, "range_max": 6.0, "angle_range": 6.2832, "number": 360}]
    run = run_world(write_world(tmp_path, world))
    assert run.arrived and not run.collided
    assert run.min_clearance_m > 0.02
    assert max(seen_moving) >= 1 and sum(seen_moving) > 20  # people tracked over many cycles


def _empty_world(robot: dict) -> dict:
    world = _head_on_world({})
    world["obstacle"] = []
    world["robot"][0].update(robot)
    return world


def test_the_path_option_and_a_goal_list_are_the_designated_path(tmp_path):
    """An L-shaped path, given as the path option or as IR-SIM's goal list: the robot goes by the corner
    [3, 0] inside a 0.3 m corridor, where the straight line to [3, 3] would cut across, and IR-SIM, which
    takes the goals one by one, raises its arrive flag at the last."""
    given = {"behavior": {"name": "viapath", "path": [[0, 0], [3, 0], [3, 3]], "half_width_m": 0.3}, "goal": [3, 3, 0]}
    goals = {"behavior": {"name": "viapath", "half_width_m": 0.3}, "goal": [[[3, 0, 0], [3, 3, 0]]]}  # one robot's
    for k, robot in enumerate((given, goals)):
        run = run_world(write_world(tmp_path, _empty_world(robot), f"world{k}.yaml"), max_steps=500)
        assert run.arrived and np.allclose(run.positions[-1], [3, 3], atol=0.1), k
        assert np.hypot(*(run.positions - [3, 0]).T).min() < 0.3, k
        assert (run.positions[:, 1] <= 0.3 + 1e-6)[run.positions[:, 0] < 2.7].all(), k


def test_a_reset_world_starts_the_behaviour_anew(tmp_path):
    import irsim

    world = _empty_world({"goal": [2, 0, 0]})
    env = irsim.make(str(write_world(tmp_path, world)), display=False, disable_all_plot=True)
    env.load_behavior("viapath.integrations.irsim")
    for _ in range(2):
        for _ in range(200):
            env.step()
            if env.robot.arrive:
                break
        assert env.robot.arrive and np.hypot(*(env.robot.state[:2, 0] - [2, 0])) < 0.1
        env.reset()
        assert np.hypot(*env.robot.state[:2, 0]) < 1e-9  # back at the start, to go again
    env.end(0)
