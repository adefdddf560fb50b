"""One definition of each option: the schema validates YAML, the CLI and keyword arguments alike, and
every bad value is refused with the field, what was expected and what was found (through the CLI:
exit 2, no traceback)."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from viapath.cli import app
from viapath.options import Option, OptionError, OptionSet
from viapath.path import DesignatedPath
from viapath.planning import available_planners, make_planner, planner_options

SCENARIO = """\
name: options-test
robot: {start: [0.0, 0.0], speed: 0.2}
path: {waypoints: [[0.0, 0.0], [3.0, 0.0]], half_width: 1.0}
planner: PLANNER
duration_s: 20
"""


def _run(tmp_path, planner_block: str, *extra: str):
    file = tmp_path / "s.yaml"
    file.write_text(SCENARIO.replace("PLANNER", planner_block))
    return file, CliRunner().invoke(app, ["run", str(file), "--json", *extra])


def _clean_failure(result, *needles):
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
    for needle in needles:
        assert needle in result.output, (needle, result.output)


def test_a_set_refuses_two_options_of_one_name():
    with pytest.raises(ValueError, match="'x' is defined twice"):
        OptionSet([Option("x", 1.0, "a"), Option("x", 2.0, "b")])


def test_defaults_types_and_bounds_come_from_the_definition():
    schema = OptionSet(
        [
            Option("gap_m", 0.5, "a gap", "m", minimum=0.0, exclusive_minimum=True),
            Option("count", 3, "how many", minimum=1, maximum=5),
            Option("side", "left", "a side", choices=("left", "right")),
            Option("k1", 0.1, "a weight", group="weights"),
        ],
        owner="demo",
    )
    assert dict(schema.validate({})) == {"gap_m": 0.5, "count": 3, "side": "left", "k1": 0.1}
    assert schema.validate({"weights": {"k1": 0.3}}).k1 == 0.3
    assert schema.validate({"weights.k1": 0.4}).k1 == 0.4  # dotted, as ROS parameters name it
    for bad, field in (
        ({"gap_m": 0.0}, "gap_m"),
        ({"count": 6}, "count"),
        ({"side": "up"}, "side"),
        ({"count": "many"}, "count"),
        ({"gap_m": float("nan")}, "gap_m"),
        ({"gapm": 1}, "gapm"),
    ):
        with pytest.raises(OptionError) as info:
            schema.validate(bad, where="planner")
        assert info.value.errors[0][0] == f"planner.{field}", info.value.errors


def test_every_registered_planner_builds_from_its_defaults_and_refuses_a_foreign_option():
    path = DesignatedPath([[0.0, 0.0], [3.0, 0.0]], half_width_m=1.0)
    for name in available_planners():
        schema = planner_options(name)
        assert {"safety_margin_m", "uncertainty_sigmas", "max_inflation_m"} <= set(schema.names)
        planner = make_planner(name, path)
        assert dict(planner.settings) == dict(schema.validate({}))
        with pytest.raises(OptionError, match="unknown option 'no_such_option'"):
            make_planner(name, path, no_such_option=1)


def test_the_planner_block_sets_the_planner_it_names(tmp_path):
    _, result = _run(tmp_path, "{name: viapath, speeds: [0.1, 0.3], weights: {k2: 0.01}}")
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["max_speed_mps"] <= 0.3 + 1e-9


@pytest.mark.parametrize(
    "block, needles",
    [
        # An option the named planner does not have: the file, the field, and the options it has.
        (
            "{name: dwa, speeds: [0.1, 0.2]}",
            ["s.yaml: planner.speeds: unknown option 'speeds'", "planner 'dwa' has options:", "n_speeds"],
        ),
        # The older spelling (params) is checked the same way.
        ("{name: vo, params: {keep_previous_way: false}}", ["planner.keep_previous_way: unknown option"]),
        ("{max_depth: deep}", ["planner.max_depth: Input should be a valid integer", "found 'deep'"]),
        ("{max_depth: 9}", ["planner.max_depth: Input should be less than or equal to 6", "found 9"]),
        ("{weights: {k4: -0.3}}", ["planner.weights.k4: Input should be greater than or equal to 0"]),
        ("{preferred_side: up}", ["planner.preferred_side: Input should be 'left' or 'right'"]),
        ("{name: nobody}", ["planner.name: unknown planner 'nobody'; available:"]),
    ],
)
def test_bad_planner_blocks_name_file_field_and_expectation(tmp_path, block, needles):
    file, result = _run(tmp_path, block)
    _clean_failure(result, *needles)
    assert str(file) in result.output


def test_a_block_for_viapath_run_with_another_planner_runs_it_with_its_defaults(tmp_path):
    # Before the redesign: a raw TypeError traceback and exit code 1.
    _, result = _run(tmp_path, "{params: {keep_previous_way: false}}", "--planner", "dwa")
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["planner"] == "dwa"
    assert "runs with its own defaults" in result.stderr


@pytest.mark.parametrize(
    "assignment, needles",
    [
        ("k9=1", ["--option k9: unknown option 'k9'", "planner 'viapath' has options:", "weights.k1"]),
        ("k1=-1", ["--option weights.k1: Input should be greater than or equal to 0", "found -1"]),
        ("speeds=[]", ["--option speeds:", "expected at least 1 value", "found []"]),
        ("max_depth", ["expected NAME=VALUE"]),
    ],
)
def test_bad_command_line_options_are_refused(tmp_path, assignment, needles):
    _, result = _run(tmp_path, "{name: viapath}", "--option", assignment)
    _clean_failure(result, *needles)


def test_a_bad_element_of_a_list_option_is_one_line(tmp_path):
    """The element's own error only: not also pydantic's "too short" for the list it was dropped from."""
    _, result = _run(tmp_path, "{name: viapath}", "-o", "speeds=[-0.1]")
    _clean_failure(result, "--option speeds.0: Input should be greater than or equal to 0.01", "found -0.1")
    assert [line for line in result.stderr.splitlines() if line.strip()] == [
        "error: --option speeds.0: Input should be greater than or equal to 0.01; found -0.1"
    ]


def test_a_command_line_option_reaches_the_planner(tmp_path):
    _, slow = _run(tmp_path, "{name: viapath}", "--option", "speeds=[0.1]", "-o", "weights.k3=0")
    assert slow.exit_code == 0, slow.output
    # The nominal speed stays in the set, so the robot still drives 0.2 m/s, never faster.
    assert json.loads(slow.stdout)["max_speed_mps"] <= 0.2 + 1e-9


def test_planners_lists_a_planners_options_with_defaults_and_units():
    result = CliRunner().invoke(app, ["planners", "viapath", "--json"])
    assert result.exit_code == 0, result.output
    listed = {item["name"]: item for item in json.loads(result.stdout)}
    assert listed["weights.k2"]["default"] == 0.01 and listed["horizon_s"]["unit"] == "s"
    assert listed["speeds"]["default"] == [0.1, 0.2, 0.3, 0.4, 0.5]
    text = CliRunner().invoke(app, ["planners", "dwa"]).output
    assert "horizon_s = 3.0 s" in text and ">= 0.25;" in text and "<= 10)" in text
    _clean_failure(CliRunner().invoke(app, ["planners", "nobody"]), "unknown planner 'nobody'")


def test_a_renamed_option_reads_its_former_name_with_a_warning():
    schema = OptionSet(
        [Option("new", 1.0, "a", former_names=("old",)), Option("k", 0.0, "b", group="g", former_names=("j",))]
    )
    with pytest.warns(FutureWarning, match="'old' is now called 'new'"):
        assert schema.validate({"old": 2.0})["new"] == 2.0
    with pytest.warns(FutureWarning, match="g.j: option 'j' is now called 'k'"):
        assert schema.validate({"g": {"j": 3.0}})["k"] == 3.0
    with pytest.warns(FutureWarning):
        assert schema.validate({"g.j": 4.0})["k"] == 4.0
    with pytest.raises(OptionError, match="give only 'new'"):
        schema.validate({"old": 2.0, "new": 3.0})
    with pytest.raises(OptionError, match="unknown option 'older'"):
        schema.validate({"older": 2.0})
    with pytest.raises(ValueError, match="former name 'new' of option 'other' is taken"):
        OptionSet([Option("new", 1.0, "a"), Option("other", 1.0, "b", former_names=("new",))])


def test_an_old_preset_file_with_backend_leaves_it_out(tmp_path):
    from viapath.presets import load_preset

    file = tmp_path / "old.yaml"
    file.write_text("name: old\ndescription: numpy arithmetic\noptions:\n  backend: numpy\n  weights: {k1: 0.2}\n")
    with pytest.warns(FutureWarning, match="options.backend: option 'backend' no longer does anything"):
        preset = load_preset(str(file))
    assert preset.options == {"k1": 0.2}


def test_the_options_hash_leaves_out_options_that_decide_nothing():
    """The retired names ``compute`` and ``backend`` do not change a run's identity; an option that decides does."""
    from viapath.bench.identity import options_hash
    from viapath.bench.suites import generate_suite

    scenario = generate_suite("paper", 1, seed=0)[0]
    plain = options_hash(scenario, "viapath")
    assert options_hash(scenario, "viapath", {"compute": "numpy"}) == plain
    assert options_hash(scenario, "viapath", {"backend": "numba"}) == plain
    assert options_hash(scenario, "viapath", {"k1": 0.3}) != plain


def test_settings_survive_copy_and_pickle():
    # copy and pickle build the instance before __init__ runs: an attribute lookup then must not recurse.
    import copy
    import pickle

    settings = planner_options("viapath").validate({"k2": 0.02})
    for clone in (copy.deepcopy(settings), copy.copy(settings), pickle.loads(pickle.dumps(settings))):
        assert dict(clone) == dict(settings) and clone.k2 == 0.02 and clone["k2"] == 0.02
    planner = make_planner("viapath", DesignatedPath([[0.0, 0.0], [4.0, 0.0]], half_width_m=1.0))
    assert copy.deepcopy(planner).config.k2 == planner.config.k2
