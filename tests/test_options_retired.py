"""Names that are no longer options (:class:`viapath.options.Retired`): one mechanism for the planner's, the
shield's and the laser chain's options. Each retired name, given in a scenario file, on the command line or as a
ROS 2 parameter, is read with exactly one FutureWarning naming it and changes nothing (the same metrics, the same
settings, the same laser chain); a name that never was an option is still refused, naming the field (through the
CLI: exit 2, no traceback)."""

from __future__ import annotations

import json
import warnings

import pytest
import yaml
from typer.testing import CliRunner

from viapath.cli import app
from viapath.options import Option, OptionSet, Retired, RetiredNames
from viapath.perception.detection import RETIRED_LASER_OPTIONS
from viapath.planning import planner_class
from viapath.safety import SHIELD_OPTIONS

PLANNER_NAMES = ("compute", "backend")
SHIELD_NAMES = ("compute", "backend")
RAY_NAMES = ("ray_compute", "ray_backend")  # the laser perception's own
FIT_NAMES = ("fit_compute", "fit_backend")  # the detector's, and the ROS 2 node's


def _recorded(call):
    """``call()``'s result and the text of every FutureWarning it raised (each one, not once per place)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = call()
    return result, [str(w.message) for w in caught if issubclass(w.category, FutureWarning)]


def _about(messages: list[str], name: str) -> list[str]:
    return [message for message in messages if f"option {name!r} no longer does anything" in message]


def _scenario(tmp_path, planner: dict, perception: dict | None = None, duration_s: float = 30.0):
    """The paper's front case (a person head-on: the planner chooses a pass), with ``planner`` as its block."""
    data = {
        "name": "retired-names",
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.2, "radius": 0.25},
        "path": {"waypoints": [[0.0, 0.0], [5.0, 0.0]], "half_width": 1.0},
        "obstacles": [{"start": [2.0, 0.0], "velocity": [-0.3, 0.0], "radius": 0.25}],
        "planner": {"name": "viapath", **planner},
        "duration_s": duration_s,
    }
    if perception is not None:
        data["perception"] = perception
    file = tmp_path / f"s{len(list(tmp_path.iterdir()))}.yaml"
    file.write_text(yaml.safe_dump(data))
    return str(file)


def _metrics(*arguments: str):
    result, messages = _recorded(lambda: CliRunner().invoke(app, ["run", *arguments, "--json"]))
    assert result.exit_code == 0, result.output
    metrics = json.loads(result.stdout.strip().splitlines()[-1])
    return {key: value for key, value in metrics.items() if "_time_p" not in key}, messages  # timings aside


def test_the_three_option_sets_keep_their_retired_names_in_one_kind_of_registry():
    planner = planner_class("viapath").options
    for retired, names, options in (
        (planner.retired, PLANNER_NAMES, planner),
        (SHIELD_OPTIONS.retired, SHIELD_NAMES, SHIELD_OPTIONS),
        (RETIRED_LASER_OPTIONS, RAY_NAMES + FIT_NAMES, None),
    ):
        assert isinstance(retired, RetiredNames)
        assert sorted(retired) == sorted(names)
        assert all(retired[name].name == name and retired[name].reason for name in names)
        if options is not None:
            assert not set(names) & set(options.names)  # no longer options: nothing declares or lists them
    with pytest.raises(ValueError, match="retired name 'x' is given twice"):
        RetiredNames([Retired("x", "a"), Retired("x", "b")])
    with pytest.raises(ValueError, match="retired name 'k1' is an option's name"):
        OptionSet([Option("k1", 1.0, "a")], retired=[Retired("k1", "why")])


def test_retired_names_survive_joining_option_sets():
    joined = OptionSet([Option("a", 1.0, "a")], retired=[Retired("old_a", "gone")]) + OptionSet(
        [Option("b", 1.0, "b")], retired=[Retired("old_b", "gone too")]
    )
    settings, messages = _recorded(lambda: joined.validate({"old_a": 1, "old_b": "x", "b": 2.0}, where="here"))
    assert dict(settings) == {"a": 1.0, "b": 2.0}
    assert messages == [
        "here.old_a: option 'old_a' no longer does anything (gone); it is ignored",
        "here.old_b: option 'old_b' no longer does anything (gone too); it is ignored",
    ]


@pytest.mark.parametrize("name", PLANNER_NAMES)
def test_a_retired_planner_name_in_a_scenario_file_or_on_the_command_line_warns_once_and_changes_nothing(
    tmp_path, name
):
    plain, messages = _metrics(_scenario(tmp_path, {"speeds": [0.1, 0.2, 0.3, 0.4, 0.5]}))
    assert not messages
    assert plain["reached_goal"] and plain["max_speed_mps"] > 0.2  # a pass, sped up: the planner decided things
    from_file, messages = _metrics(_scenario(tmp_path, {"speeds": [0.1, 0.2, 0.3, 0.4, 0.5], name: "numpy"}))
    assert from_file == plain
    assert len(_about(messages, name)) == 1 and len(messages) == 1, messages
    assert _about(messages, name)[0].startswith(f"planner.{name}: ")
    from_option, messages = _metrics(
        _scenario(tmp_path, {"speeds": [0.1, 0.2, 0.3, 0.4, 0.5]}), "--option", f"{name}=numba"
    )
    assert from_option == plain
    assert len(messages) == 1 and messages[0].startswith(f"--option {name}: option {name!r} no longer"), messages


@pytest.mark.parametrize(
    ("prefix", "name"),
    [*(("planner.", n) for n in PLANNER_NAMES), *(("shield.", n) for n in SHIELD_NAMES), *(("", n) for n in FIT_NAMES)],
)
def test_a_retired_ros_parameter_warns_once_and_changes_nothing(prefix, name):
    from viapath.ros2.settings import validate

    given = {"shield.margin_m": 0.1, "planner.weights.k2": 0.02, "detector": "legs"}
    plain, messages = _recorded(lambda: validate(given))
    assert not messages
    settings, messages = _recorded(lambda: validate({**given, prefix + name: "numpy"}))
    assert (settings.values, settings.planner_values, settings.shield_values) == (
        plain.values,
        plain.planner_values,
        plain.shield_values,
    )
    assert len(messages) == 1 and messages[0].startswith(f"ROS 2 parameter {prefix}{name}: option {name!r} no longer")


@pytest.mark.parametrize("name", SHIELD_NAMES)
def test_a_retired_shield_name_warns_once_and_makes_the_same_shield(name):
    from viapath.safety.shield import ShieldConfig

    config, messages = _recorded(lambda: ShieldConfig.from_options({name: "numba", "margin_m": 0.1}))
    assert config == ShieldConfig(margin_m=0.1) != ShieldConfig()
    assert len(messages) == 1 and messages[0].startswith(f"shield.{name}: option {name!r} no longer"), messages


@pytest.mark.parametrize(
    "options",
    [
        {"ray_compute": "numba"},
        {"ray_backend": "numpy"},
        {"detector": {"fit_compute": "numpy", "iterations": 3}},
        {"detector": {"fit_backend": "auto"}},
    ],
)
def test_a_retired_laser_name_in_a_scenario_file_warns_once_and_builds_the_same_chain(tmp_path, options):
    from viapath.scenarios import load_scenario
    from viapath.scenarios.build import build

    def chain(given):
        def load_and_build():
            return build(load_scenario(_scenario(tmp_path, {}, {"mode": "laser", "options": given}))).perception

        return _recorded(load_and_build)

    kept = {key: value for key, value in options.get("detector", {}).items() if key == "iterations"}
    plain, messages = chain({"detector": kept} if "detector" in options else {})
    assert not messages
    built, messages = chain(options)
    name = next(
        key for part in (options, options.get("detector", {})) for key in part if key not in ("detector", "iterations")
    )
    assert len(messages) == 1 and len(_about(messages, name)) == 1, messages
    assert messages[0].startswith("perception.options." + ("detector." if "detector" in options else "") + name)
    assert (built.scanners, built.detector_params, built.tracker_params) == (
        plain.scanners,
        plain.detector_params,
        plain.tracker_params,
    )
    assert built.detector_params.iterations == (3 if kept else 4)


def test_the_retired_laser_names_leave_a_laser_run_as_it_was(tmp_path):
    perception = {"mode": "laser", "options": {"ray_compute": "numba", "detector": {"fit_backend": "numpy"}}}
    plain, messages = _metrics(_scenario(tmp_path, {}, {"mode": "laser"}, duration_s=8.0))
    assert not messages and plain["perception"] == "laser"
    with_retired, messages = _metrics(_scenario(tmp_path, {}, perception, duration_s=8.0))
    assert with_retired == plain
    assert [len(_about(messages, name)) for name in ("ray_compute", "fit_backend")] == [1, 1] and len(messages) == 2


def test_a_retired_keyword_of_the_laser_perception_warns_once():
    from viapath.perception.laser import LaserPerception

    chain, messages = _recorded(lambda: LaserPerception(ray_backend="numpy"))
    assert chain.detector_params == LaserPerception().detector_params
    assert len(messages) == 1 and messages[0].startswith("LaserPerception.ray_backend: option 'ray_backend'"), messages
    with pytest.raises(TypeError, match=r"unexpected keyword argument.*ray_computer"):
        LaserPerception(ray_computer="numpy")


def _refused(result, *needles):
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
    for needle in needles:
        assert needle in result.output, (needle, result.output)


def test_an_unknown_name_is_still_refused_naming_the_field(tmp_path):
    runner = CliRunner()
    _refused(
        runner.invoke(app, ["run", _scenario(tmp_path, {"computer": "numpy"}), "--json"]),
        "planner.computer",
        "unknown option 'computer'",
    )
    _refused(
        runner.invoke(app, ["run", _scenario(tmp_path, {}), "--option", "computer=numpy"]),
        "--option computer",
        "unknown option 'computer'",
    )
    laser = {"mode": "laser", "options": {"detector": {"fit_computer": "numpy"}}}
    _refused(runner.invoke(app, ["run", _scenario(tmp_path, {}, laser)]), "perception.options.detector.fit_computer")
    params = tmp_path / "params.yaml"
    params.write_text("viapath:\n  ros__parameters:\n    shield:\n      computer: numpy\n")
    _refused(
        runner.invoke(app, ["ros2", "node", "--params-file", str(params)]),
        "parameter shield.computer: unknown parameter",
    )
    from viapath.safety.shield import ShieldConfig

    with pytest.raises(ValueError, match=r"shield\.computer: unknown option 'computer'"):
        ShieldConfig.from_options({"computer": "numpy"})
