"""viapath selected by name in navground's own experiment YAML (behavior: {type: Viapath}), judged by
navground's own collision records; distances checked independently on the recorded poses."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("navground", reason="navground is not installed (extra 'navground': pip install -e '.[navground]')")

from navground import core, sim

import viapath.integrations.navground as viapath_navground
from viapath.options import OptionError

ROOT = Path(__file__).resolve().parents[2]
CROSSING = ROOT / "examples" / "navground" / "crossing.yaml"


def _run(experiment: dict | str):
    text = experiment if isinstance(experiment, str) else yaml.safe_dump(experiment, sort_keys=False)
    loaded = sim.load_experiment(text)
    loaded.run()
    return loaded.runs[0]


def _min_gaps(run, radii) -> np.ndarray:
    """Per other agent: the smallest gap between its disc and the robot's over the recorded poses."""
    poses = np.asarray(run.poses)
    return np.array(
        [(np.hypot(*(poses[:, 0, :2] - poses[:, j, :2]).T) - radii[0] - radii[j]).min() for j in range(1, len(radii))]
    )


def _arrival_step(run, goal, tolerance=0.1) -> int | None:
    distance = np.hypot(*(np.asarray(run.poses)[:, 0, :2] - np.asarray(goal)).T)
    reached = np.flatnonzero(distance <= tolerance + 1e-6)
    return int(reached[0]) if len(reached) else None


def test_the_crossing_experiment_reaches_the_goal_without_a_collision():
    run = _run(CROSSING.read_text())
    assert len(run.collisions) == 0  # navground's own collision record
    assert _arrival_step(run, [9.0, 0.0]) is not None
    assert (_min_gaps(run, [0.25, 0.25, 0.25]) > 0.05).all()
    box_gap = np.hypot(*(np.asarray(run.poses)[:, 0, :2] - [5.0, 0.1]).T).min() - 0.55
    assert box_gap > 0.02
    assert np.abs(np.asarray(run.poses)[:, 0, 1]).max() <= 1.0  # inside the corridor


def test_the_crossing_experiment_is_a_real_test_a_robot_going_straight_collides():
    experiment = yaml.safe_load(CROSSING.read_text())
    experiment["scenario"]["groups"][0]["behavior"] = {"type": "Dummy", "optimal_speed": 0.3}
    assert len(_run(experiment).collisions) > 0


def test_the_entry_point_makes_viapath_selectable_in_navgrounds_own_loader(tmp_path):
    """pyproject's navground_behaviors entry point, as installed metadata: navground's load_plugins() (what
    navground_py run calls) imports it, and the experiment runs with no import of viapath by the user."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    entry = project["entry-points"]["navground_behaviors"]
    assert entry == {"viapath": "viapath.integrations.navground"}
    info = tmp_path / "viapath_entry_points_under_test-0.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: viapath-entry-points-under-test\nVersion: 0.0\n")
    (info / "entry_points.txt").write_text(
        "[navground_behaviors]\n" + "".join(f"{k} = {v}\n" for k, v in entry.items())
    )
    script = (
        "import json, sys\n"
        "from navground import sim\n"
        "assert 'viapath.integrations.navground' not in sys.modules\n"
        "sim.load_plugins()\n"
        f"exp = sim.load_experiment(open({str(CROSSING)!r}).read())\n"
        "exp.run(); run = exp.runs[0]\n"
        "print(json.dumps({'type': run.world.agents[0].behavior.type, 'collisions': len(run.collisions),"
        " 'x': float(run.poses[-1, 0, 0])}))\n"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT / "src")])}
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["type"] == "Viapath" and result["collisions"] == 0 and result["x"] > 8.8


def _head_on(behavior: dict) -> dict:
    """viapath's paper-front scenario as a navground experiment: a person comes head-on at 0.3 m/s."""
    return {
        "steps": 350,
        "time_step": 0.1,
        "runs": 1,
        "record_pose": True,
        "record_collisions": True,
        "scenario": {
            "groups": [
                {
                    "number": 1,
                    "type": "robot",
                    "radius": 0.25,
                    "control_period": 0.1,
                    "kinematics": {"type": "2WDiff", "wheel_axis": 0.4, "max_speed": 0.6},
                    "behavior": {"type": "Viapath", "optimal_speed": 0.2, **behavior},
                    "state_estimation": {"type": "Bounded", "range": 5.0},
                    "task": {"type": "Waypoints", "waypoints": [[5.0, 0.0]], "tolerance": 0.1},
                    "position": [0.0, 0.0],
                    "orientation": 0.0,
                },
                {
                    "number": 1,
                    "type": "human",
                    "radius": 0.25,
                    "kinematics": {"type": "Omni", "max_speed": 0.3},
                    "behavior": {"type": "Dummy", "optimal_speed": 0.3},
                    "task": {"type": "Waypoints", "waypoints": [[-3.0, 0.0]], "tolerance": 0.1},
                    "position": [2.0, 0.0],
                    "orientation": 3.1416,
                },
            ]
        },
    }


def _viapath_own_side(preferred_side: str) -> float:
    from viapath.scenarios import load_scenario
    from viapath.sim.loop import run_episode

    episode = run_episode(load_scenario("paper-front"), planner_overrides={"preferred_side": preferred_side})
    y = episode.trace.robot_poses[:, 1]
    return float(y[np.argmax(np.abs(y))])


@pytest.mark.parametrize("side", ["left", "right"])
def test_preferred_side_in_the_experiment_passes_on_that_side_as_in_viapaths_own_scenario(side):
    run = _run(_head_on({"preferred_side": side}))
    assert len(run.collisions) == 0 and _arrival_step(run, [5.0, 0.0]) is not None
    y = np.asarray(run.poses)[:, 0, 1]
    widest = float(y[np.argmax(np.abs(y))])
    own = _viapath_own_side(side)
    assert np.sign(widest) == np.sign(own) == (1 if side == "left" else -1)
    assert abs(widest) > 0.3 and abs(own) > 0.3


def test_the_path_property_is_the_designated_path():
    """An L-shaped path to the target [4, 3]: the robot goes by the corner [4, 0] (corridor 0.3 m), where
    the straight line to the target would cut across."""
    experiment = _head_on({"path": [[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]], "half_width_m": 0.3})
    experiment["scenario"]["groups"][0]["task"]["waypoints"] = [[4.0, 3.0]]
    experiment["scenario"]["groups"].pop()  # nobody else
    experiment["steps"] = 450
    run = _run(experiment)
    poses = np.asarray(run.poses)[:, 0, :2]
    assert _arrival_step(run, [4.0, 3.0]) is not None
    assert np.hypot(*(poses - [4.0, 0.0]).T).min() < 0.3
    assert (poses[:, 1] <= 0.3 + 1e-6)[poses[:, 0] < 3.7].all()  # no cutting across before the corner


def test_every_option_is_a_property_with_the_schemas_default_and_description():
    behavior = core.Behavior.make_type("Viapath")
    properties = behavior.properties
    for option in viapath_navground.SCHEMA:
        prop = properties[option.name]
        assert prop.description == option.describe()
        default = prop.default_value
        if option.kind is tuple:
            assert np.allclose(default, option.default, rtol=1e-6)
        elif option.kind is float:
            assert default == pytest.approx(option.default, rel=1e-6)
        else:
            assert default == option.default
        value = behavior.get(option.name)  # through navground's property (single precision)
        if option.kind in (tuple, float):
            assert np.allclose(value, option.default, rtol=1e-6)
        else:
            assert value == option.default
    assert "path" in properties


@pytest.mark.parametrize(
    ("behavior", "field"),
    [
        ({"k1": -1.0}, "behavior Viapath.k1"),
        ({"half_width_m": 0.0}, "behavior Viapath.half_width_m"),
        ({"preferred_side": "up"}, "behavior Viapath.preferred_side"),
        ({"speeds": [0.1, -0.2]}, "behavior Viapath.speeds"),
    ],
)
def test_an_out_of_range_option_is_refused_naming_the_field(behavior, field):
    with pytest.raises(OptionError, match=field.replace(".", r"\.")):
        _run(_head_on(behavior))


def test_an_unknown_option_is_named_by_the_check_navground_itself_skips_it():
    text = yaml.safe_dump(_head_on({"speedz": [0.1], "k2": -3.0}), sort_keys=False)
    errors = viapath_navground.check_experiment(text, "exp.yaml")
    assert any(e.startswith("exp.yaml: scenario.groups.0.behavior.speedz: unknown option 'speedz'") for e in errors)
    assert any("scenario.groups.0.behavior.k2" in e and "greater than or equal to 0" in e for e in errors)
    assert viapath_navground.check_experiment(CROSSING.read_text(), "crossing.yaml") == []
    assert viapath_navground.main([str(CROSSING)]) == 0
    assert viapath_navground.main([str(CROSSING.with_name("missing.yaml"))]) == 2
