"""Weight presets (issue 15): the shipped registry, preset files, and every place a preset is accepted
(``viapath run --weights``, ``viapath bench --weights``, a scenario's ``planner: {weights: NAME}``, the
ROS 2 parameter ``weights_preset``)."""

from __future__ import annotations

import json

import pytest
import yaml
from typer.testing import CliRunner

from tests.tune._tiny import TINY, tiny_scenario
from viapath.cli import app
from viapath.planning.viapath.options import VIAPATH_OPTIONS
from viapath.presets import PresetError, load_preset, parse_preset, preset_names


def _invoke(*args):
    result = CliRunner().invoke(app, [str(a) for a in args])
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result


@pytest.mark.parametrize("name", preset_names())
def test_every_shipped_preset_is_valid_and_justified(name):
    preset = load_preset(name)
    assert preset.name == name
    assert preset.options, "a preset sets at least one option"
    VIAPATH_OPTIONS.validate(preset.nested())  # the planner's own schema accepts it
    assert preset.evidence, "each preset says what justifies it"
    again = parse_preset(preset.to_yaml())  # written out and read back: the same values
    assert again.options == preset.options


def test_paper_preset_holds_the_papers_weights():
    assert load_preset("paper").options == {
        "k1": 0.1,
        "k2": 0.001,
        "k3": 0.08,
        "k4": 0.3,
        "return_lookahead_m": 0.0,
        "outrun_hold_s": 0.0,
    }


def test_a_bad_preset_names_the_field(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\noptions: {weights: {k5: 1.0}}\n")
    with pytest.raises(PresetError, match=r"bad.yaml: options.weights.k5: unknown option"):
        load_preset(bad)
    bad.write_text("name: bad\noptions: {weights: {k1: -1.0}}\n")
    with pytest.raises(PresetError, match=r"options.weights.k1"):
        load_preset(bad)
    with pytest.raises(PresetError, match="not a preset name"):
        load_preset(tmp_path / "missing.yaml")


def test_presets_command_lists_values_and_evidence():
    result = _invoke("presets", "--json")
    assert result.exit_code == 0, result.output
    listed = {p["name"]: p for p in json.loads(result.stdout)}
    assert set(listed) == set(preset_names())
    assert listed["paper"]["options"]["weights.k2"] == 0.001


def test_run_weights_file_equals_the_same_options(tmp_path):
    scenario = tmp_path / "s.yaml"
    scenario.write_text(yaml.safe_dump(tiny_scenario("s", TINY["tiny-head-on-1"])))
    preset = tmp_path / "fast.yaml"
    preset.write_text("name: fast\noptions: {weights: {k2: 0.05}}\n")
    runs = {}
    for label, args in (
        ("preset", ["--weights", preset]),
        ("option", ["-o", "weights.k2=0.05"]),
        ("paper", ["--weights", "paper"]),
    ):
        result = _invoke("run", scenario, *args, "--json")
        assert result.exit_code == 0, result.output
        runs[label] = json.loads(result.stdout)
    assert runs["preset"]["time_to_goal_s"] == runs["option"]["time_to_goal_s"]
    assert runs["preset"]["mean_lateral_deviation_m"] == runs["option"]["mean_lateral_deviation_m"]
    # ... and the weight did something here: a larger k2 hurries past the oncoming person.
    assert runs["preset"]["time_to_goal_s"] != runs["paper"]["time_to_goal_s"]
    bad = _invoke("run", scenario, "--weights", "no-such-preset", "--json")
    assert bad.exit_code == 2 and "--weights" in bad.output and "Traceback" not in bad.output


def test_scenario_block_may_name_a_preset(tmp_path):
    from viapath.scenarios import ScenarioError, load_scenario
    from viapath.scenarios.loader import planner_settings

    data = tiny_scenario("s", TINY["tiny-crossing-0"])
    file = tmp_path / "s.yaml"
    file.write_text(yaml.safe_dump({**data, "planner": {"name": "viapath", "weights": "paper", "horizon_s": 7.0}}))
    settings = planner_settings(load_scenario(file))
    assert settings["k2"] == 0.001 and settings["horizon_s"] == 7.0
    file.write_text(yaml.safe_dump({**data, "planner": {"weights": "nope"}}))
    with pytest.raises(ScenarioError, match=r"s.yaml: planner.weights: nope: not a preset name"):
        load_scenario(file)


def test_bench_weights_enter_the_row_identity():
    from viapath.bench.runner import make_tasks

    scenario = tiny_scenario("s", TINY["tiny-crossing-0"])
    plain = make_tasks([scenario], ["viapath", "follow"])
    same = make_tasks(
        [scenario], ["viapath", "follow"], planner_options={"viapath": load_preset("close-to-path").options}
    )
    paper = make_tasks([scenario], ["viapath", "follow"], planner_options={"viapath": load_preset("paper").options})
    other = make_tasks([scenario], ["viapath", "follow"], planner_options={"viapath": {"k2": 0.05}})
    by = lambda tasks: {t.planner: t for t in tasks}
    # close-to-path's values are the defaults: the same options, the same row; the paper's are another row.
    assert by(plain)["viapath"].key == by(same)["viapath"].key
    assert by(paper)["viapath"].key != by(plain)["viapath"].key
    assert by(other)["viapath"].key != by(plain)["viapath"].key
    assert dict(by(other)["viapath"].options) == {"k2": 0.05}
    assert by(other)["follow"].key == by(plain)["follow"].key  # applied to the viapath planner only


def test_bench_weights_bad_input_writes_nothing(tmp_path):
    out = tmp_path / "results"
    result = _invoke("bench", "paper", "--planners", "viapath", "--weights", "nope", "--out", out)
    assert result.exit_code == 2 and not out.exists()
    result = _invoke("bench", "paper", "--planners", "follow", "--weights", "paper", "--out", out)
    assert result.exit_code == 2 and not out.exists()


def test_ros2_parameter_selects_a_preset(tmp_path):
    from viapath.ros2.settings import ParameterError, validate

    preset = tmp_path / "p.yaml"
    preset.write_text("name: p\noptions: {weights: {k1: 0.5, k2: 0.02}}\n")
    settings = validate({"weights_preset": str(preset), "planner.weights.k2": 0.03})
    assert settings.planner_values["weights.k1"] == 0.5  # from the preset
    assert settings.planner_values["weights.k2"] == 0.03  # a parameter set away from its default wins
    assert settings.planner_values["weights.k4"] == 0.3  # not in the preset: the default
    with pytest.raises(ParameterError, match="weights_preset"):
        validate({"weights_preset": "nope"})
