"""Bad scenario files give one clear error: the file, the field path, what was expected, what was found.

Checked both through the loader (``ScenarioError``) and through the command line (exit code != 0,
message on stderr, no traceback).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from viapath.cli import app
from viapath.scenarios import ScenarioError, load_scenario
from viapath.scenarios.loader import builtin_names, scenario_from_dict

SRC = Path(__file__).resolve().parents[2] / "src"

GOOD = """\
name: yaml-test
robot: {start: [0.0, 0.0], heading: 0.0, speed: 0.2, radius: 0.25}
path: {waypoints: [[0.0, 0.0], [5.0, 0.0]], half_width: 1.0}
obstacles:
  - {start: [2.0, 0.0], velocity: [-0.3, 0.0], radius: 0.25}
planner: {name: viapath, speeds: [0.1, 0.2, 0.3, 0.4, 0.5], weights: {k1: 0.1, k2: 0.001, k3: 0.08, k4: 0.3}}
duration_s: 60
"""

# id: (old text, new text, field path, expected-part, found-part or None, number of error lines)
BAD = {
    "nan_radius": (
        "speed: 0.2, radius: 0.25",
        "speed: 0.2, radius: .nan",
        "robot.radius",
        "finite number",
        "found nan",
        1,
    ),
    "negative_radius": (
        "speed: 0.2, radius: 0.25",
        "speed: 0.2, radius: -0.25",
        "robot.radius",
        "greater than 0",
        "found -0.25",
        1,
    ),
    "empty_speed_set": (
        "speeds: [0.1, 0.2, 0.3, 0.4, 0.5]",
        "speeds: []",
        "planner.speeds",
        "expected at least 1 value",
        "found []",
        1,
    ),
    "zero_speed_in_set": (
        "speeds: [0.1, 0.2, 0.3, 0.4, 0.5]",
        "speeds: [0.0, 0.2]",
        "planner.speeds.0",
        "greater than or equal to 0.01",
        "found 0.0",
        1,
    ),
    "unknown_field": ("heading: 0.0", "headng: 0.0", "robot.headng", "unknown field", "found 0.0", 1),
    "unknown_top_level_field": (
        "duration_s: 60",
        "duration_s: 60\nduraton: 30",
        "duraton",
        "unknown field",
        "found 30",
        1,
    ),
    "wrong_type": ("speed: 0.2,", "speed: fast,", "robot.speed", "valid number", "found 'fast'", 1),
    "missing_required": (
        "path: {waypoints: [[0.0, 0.0], [5.0, 0.0]], half_width: 1.0}\n",
        "",
        "path",
        "required field is missing",
        None,
        1,
    ),
    "nan_waypoint": ("[5.0, 0.0]]", "[5.0, .nan]]", "path.waypoints.1.1", "finite number", "found nan", 1),
    "infinite_obstacle_velocity": (
        "velocity: [-0.3, 0.0]",
        "velocity: [-.inf, 0.0]",
        "obstacles.0.velocity.0",
        "finite number",
        "found -inf",
        1,
    ),
    "negative_obstacle_radius": (
        "velocity: [-0.3, 0.0], radius: 0.25",
        "velocity: [-0.3, 0.0], radius: -1",
        "obstacles.0.radius",
        "greater than 0",
        "found -1",
        1,
    ),
    "replay_typo": (
        "radius: 0.25}\nplanner",
        "radius: 0.25}\n  - {replay: {file: eth.txt, dt_z: 0.4}}\nplanner",
        "obstacles.1.replay.dt_z",
        "unknown field",
        "found 0.4",
        1,
    ),
    "unknown_perception_mode": (
        "duration_s: 60",
        "perception: {mode: lidar}\nduration_s: 60",
        "perception.mode",
        "'oracle' or 'tracked' or 'laser'",
        "found 'lidar'",
        1,
    ),
    "negative_seed": (
        "duration_s: 60",
        "duration_s: 60\nseed: -3",
        "seed",
        "greater than or equal to 0",
        "found -3",
        1,
    ),
    "step_longer_than_episode": (
        "duration_s: 60",
        "duration_s: 5\ndt_s: 10",
        "dt_s",
        "must not exceed duration_s",
        "found 10",
        1,
    ),
    "one_number_velocity": (
        "velocity: [-0.3, 0.0]",
        "velocity: [-0.3]",
        "obstacles.0.velocity",
        "too few items",
        "found [-0.3]",
        1,
    ),
    "empty_velocity": ("velocity: [-0.3, 0.0]", "velocity: []", "obstacles.0.velocity", "too few items", "found []", 1),
    "three_number_start": (
        "start: [2.0, 0.0]",
        "start: [2.0, 0.0, 1.0]",
        "obstacles.0.start",
        "list of 2 items",
        "found [2.0, 0.0, 1.0]",
        1,
    ),
    "negative_weight": ("k1: 0.1", "k1: -0.1", "planner.weights.k1", "greater than or equal to 0", "found -0.1", 1),
    "laser_min_points": (
        "duration_s: 60",
        "duration_s: 60\nperception: {mode: laser, options: {detector: {segmentation: {min_points: -1}}}}",
        "perception.options.detector.segmentation.min_points",
        "greater than or equal to 2",
        "found -1",
        1,
    ),
    "laser_unknown_option": (
        "duration_s: 60",
        "duration_s: 60\nperception: {mode: laser, options: {bogus: 1}}",
        "perception.options.bogus",
        "unknown field",
        "found 1",
        1,
    ),
    "laser_unknown_tracker_option": (
        "duration_s: 60",
        "duration_s: 60\nperception: {mode: laser, options: {tracker: {gate: 3}}}",
        "perception.options.tracker.gate",
        "unknown field",
        "found 3",
        1,
    ),
    "laser_scanner_ranges_crossed": (
        "duration_s: 60",
        "duration_s: 60\nperception: {mode: laser, options: {scanners: [{range_min_m: 5.0, range_max_m: 4.0}]}}",
        "perception.options.scanners.0",
        "range_min_m < range_max_m",
        None,
        1,
    ),
    "laser_tracker_window_too_short": (
        "duration_s: 60",
        "duration_s: 60\nperception: {mode: laser, options: {tracker: {confirm_hits: 5, confirm_window: 3}}}",
        "perception.options.tracker",
        "confirm_hits <= confirm_window",
        None,
        1,
    ),
    "laser_oracle_noise": (
        "duration_s: 60",
        "duration_s: 60\nperception: {mode: laser, options: {position_noise_m: 0.1}}",
        "perception.options.position_noise_m",
        "oracle option",
        "found 0.1",
        1,
    ),
    "oracle_with_laser_options": (
        "duration_s: 60",
        "duration_s: 60\nperception: {mode: oracle, options: {tracker: {max_unseen_s: 2.0}}}",
        "perception",
        "options (tracker) configure the laser chain; mode 'oracle' takes none",
        None,
        1,
    ),
}


def _write_bad(tmp_path: Path, case: str) -> tuple[Path, tuple]:
    old, new, *expect = BAD[case]
    assert old in GOOD, "test set-up: the text to replace must be in the good file"
    file = tmp_path / f"{case}.yaml"
    file.write_text(GOOD.replace(old, new, 1))
    return file, tuple(expect)


def test_good_file_loads(tmp_path):
    file = tmp_path / "good.yaml"
    file.write_text(GOOD)
    scenario = load_scenario(file)
    assert scenario.name == "yaml-test"
    assert scenario.robot.radius == 0.25
    assert scenario.path.widths() == [1.0]
    assert scenario.planner.speeds == [0.1, 0.2, 0.3, 0.4, 0.5]
    assert tuple(scenario.obstacles[0].velocity) == (-0.3, 0.0)


@pytest.mark.parametrize("case", list(BAD))
def test_bad_field_names_file_field_expected_and_found(tmp_path, case):
    file, (field, expected, found, n_lines) = _write_bad(tmp_path, case)
    with pytest.raises(ScenarioError) as info:
        load_scenario(file)
    message = str(info.value)
    lines = message.splitlines()
    assert len(lines) == n_lines, message
    line = next((text for text in lines if f": {field}: " in text), None)
    assert line is not None, f"field path {field!r} not named in: {message}"
    assert line.startswith(f"{file}: "), message
    assert expected in line, message
    if found is not None:
        assert found in line, message


def test_missing_half_width_is_named_at_path(tmp_path):
    file = tmp_path / "nowidth.yaml"
    file.write_text(GOOD.replace(", half_width: 1.0", ""))
    with pytest.raises(ScenarioError, match=r"nowidth\.yaml: path: .*half_width"):
        load_scenario(file)


def test_every_error_is_reported_each_on_its_own_line(tmp_path):
    file = tmp_path / "two.yaml"
    file.write_text(GOOD.replace("radius: 0.25}", "radius: -0.25}").replace("headin", "headdin"))
    with pytest.raises(ScenarioError) as info:
        load_scenario(file)
    message = str(info.value)
    lines = message.splitlines()
    fields = sorted(line.split(": ")[1] for line in lines)
    assert fields == ["obstacles.0.radius", "robot.headding", "robot.radius"]
    assert all(line.startswith(f"{file}: ") for line in lines)


def test_unreadable_yaml_syntax_names_line_and_column(tmp_path):
    file = tmp_path / "syntax.yaml"
    file.write_text(GOOD.replace("speeds: [0.1, 0.2, 0.3, 0.4, 0.5]", "speeds: [0.1, 0.2"))
    with pytest.raises(ScenarioError) as info:
        load_scenario(file)
    message = str(info.value)
    assert message.startswith(f"{file}: line 6, column ")
    assert "not valid YAML" in message


def test_tab_indentation_is_a_yaml_error(tmp_path):
    file = tmp_path / "tab.yaml"
    file.write_text("name: t\n\trobot: {}\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(file)
    message = str(info.value)
    assert message.startswith(f"{file}: line 2, column 1: not valid YAML")


def test_empty_file_says_so(tmp_path):
    file = tmp_path / "empty.yaml"
    file.write_text("# only a comment\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(file)
    message = str(info.value)
    assert message.startswith(f"{file}: the file is empty")


@pytest.mark.parametrize("text, found", [("- a\n- b\n", "list"), ("just words", "str"), ("null\n", "null")])
def test_not_a_mapping(tmp_path, text, found):
    file = tmp_path / "notmap.yaml"
    file.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(file)
    message = str(info.value)
    assert message.startswith(f"{file}: expected a mapping")
    assert message.endswith(f"found {found}")


def test_nonexistent_file_and_folder_and_binary(tmp_path):
    missing = tmp_path / "nope.yaml"
    with pytest.raises(ScenarioError) as info:
        load_scenario(missing)
    message = str(info.value)
    assert message.startswith(f"{missing}: no such file")
    assert "paper-front" in message  # lists the built-ins as the alternative
    with pytest.raises(ScenarioError) as info:
        load_scenario(tmp_path)
    message = str(info.value)
    assert message.startswith(f"{tmp_path}: is a folder")
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"name: \xff\xfe\x00\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(binary)
    message = str(info.value)
    assert message.startswith(f"{binary}: cannot read")


def test_scenario_from_dict_names_origin():
    with pytest.raises(ScenarioError, match=r"^<mine>: robot: required field is missing"):
        scenario_from_dict({"name": "x", "path": {"waypoints": [[0, 0], [1, 0]], "half_width": 1.0}}, "<mine>")


def test_all_builtins_load():
    names = builtin_names()
    assert {"paper-behind", "paper-front", "paper-side"} <= set(names)
    for name in names:
        scenario = load_scenario(name)
        assert scenario.name == name  # the file's name field matches the name it is listed under


# --------------------------------------------------------------------------- through the CLI

CLI_CASES = [
    "nan_radius",
    "negative_radius",
    "empty_speed_set",
    "unknown_field",
    "wrong_type",
    "missing_required",
    "replay_typo",
    "laser_min_points",
    "oracle_with_laser_options",
]


def _assert_clean_failure(exit_code: int, output: str, *needles: str) -> None:
    assert exit_code not in (0, None), output
    assert "Traceback" not in output, output
    for needle in needles:
        assert needle in output, f"{needle!r} not in {output!r}"


@pytest.mark.parametrize("case", CLI_CASES)
def test_cli_bad_field(tmp_path, case):
    file, (field, expected, _found, _) = _write_bad(tmp_path, case)
    result = CliRunner().invoke(app, ["run", str(file), "--json"])
    assert not isinstance(result.exception, Exception) or isinstance(result.exception, SystemExit)
    _assert_clean_failure(result.exit_code, result.output, str(file), f": {field}: ", expected)
    assert result.stdout == ""  # nothing on stdout: a --json consumer sees no half object


def test_cli_yaml_syntax_missing_file_and_folder(tmp_path):
    bad = tmp_path / "syntax.yaml"
    bad.write_text("name: [unclosed\n")
    result = CliRunner().invoke(app, ["run", str(bad)])
    _assert_clean_failure(result.exit_code, result.output, str(bad), "not valid YAML", "line ")
    missing = tmp_path / "nope.yaml"
    result = CliRunner().invoke(app, ["run", str(missing)])
    _assert_clean_failure(result.exit_code, result.output, str(missing), "no such file")
    result = CliRunner().invoke(app, ["run", str(tmp_path)])
    _assert_clean_failure(result.exit_code, result.output, str(tmp_path), "is a folder")


def test_cli_error_keeps_brackets_in_file_name(tmp_path):
    """Square brackets in a path are not console markup: the message must name the real file."""
    folder = tmp_path / "run[v2]"
    folder.mkdir()
    file, (field, expected, _, _) = _write_bad(folder, "negative_radius")
    file = file.rename(folder / "neg[draft].yaml")
    result = CliRunner().invoke(app, ["run", str(file)])
    _assert_clean_failure(result.exit_code, result.output, str(file), field, expected)


def test_cli_bad_input_via_subprocess(tmp_path):
    """The real process: exit code, stderr message, no traceback."""
    file, (field, expected, found, _) = _write_bad(tmp_path, "nan_radius")
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    done = subprocess.run(
        [sys.executable, "-m", "viapath.cli", "run", str(file), "--json"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    _assert_clean_failure(done.returncode, done.stdout + done.stderr, str(file), f": {field}: ", expected, found)
    assert done.stdout == ""


@pytest.mark.parametrize(
    "old, new, needle",
    [
        ("name: viapath,", "name: viapth,", ": planner.name: unknown planner 'viapth'"),
        (
            "duration_s: 60",
            "duration_s: 60\nperception: {mode: laser, options: {bogus: 1}}",
            ": perception.options.bogus: unknown field",
        ),
        (
            "duration_s: 60",
            "duration_s: 60\nperception: {mode: laser, options: {tracker: {gate: 3}}}",
            ": perception.options.tracker.gate: unknown field",
        ),
    ],
)
def test_cli_names_the_field_of_errors_found_after_loading(tmp_path, old, new, needle):
    file = tmp_path / "late.yaml"
    file.write_text(GOOD.replace(old, new, 1))
    result = CliRunner().invoke(app, ["run", str(file), "--json"])
    _assert_clean_failure(result.exit_code, result.output, f"{file}{needle}")
    assert result.stdout == ""


def test_laser_options_are_passed_through_including_the_mode():
    from viapath.perception.laser import LaserPerception
    from viapath.perception.modes import laser_perception

    perception = laser_perception({"mode": "laser", "range_noise": False})
    assert isinstance(perception, LaserPerception)
    assert perception.range_noise is False
    with pytest.raises(ValueError, match=r"^perception.options.bogus: "):
        laser_perception({"bogus": 1})
    with pytest.raises(ValueError, match=r"^perception.options.detector.iterations: .*greater than or equal to 1"):
        laser_perception({"detector": {"iterations": 0}})


LASER_OPTION_SETS = [
    {},
    {"detector": {"fixed_radius_m": 0.25, "segmentation": {"min_points": 4}}},
    {"fixed_radius_m": 0.3, "range_noise": False},
    {"tracker": {"max_unseen_s": 1.5, "static_after_s": float("inf")}, "static_layer": {"enabled": False}},
    {"scanners": [{"name": "only", "beam_count": 361, "angle_increment_rad": 0.0087}], "detector": None},
]


@pytest.mark.parametrize("options", LASER_OPTION_SETS)
def test_a_scenario_builds_the_laser_chain_the_mapping_builds(options):
    """The typed options hand LaserPerception the mapping it was given: the same scanners, detector, tracker and
    static layer as ``LaserPerception(**options)``."""
    from viapath.perception.laser import LaserPerception
    from viapath.scenarios.build import build

    data = yaml.safe_load(GOOD)
    data["perception"] = {"mode": "laser", "options": options}
    built = build(scenario_from_dict(data)).perception
    direct = LaserPerception(**options)
    assert built.scanners == direct.scanners
    assert built.detector_params == direct.detector_params
    assert built.tracker_params == direct.tracker_params
    assert built._static.params == direct._static.params
    assert (built.range_noise, built.robot_radius_m) == (direct.range_noise, direct.robot_radius_m)


@pytest.mark.parametrize(
    "options",
    [
        {"ray_compute": "numba"},
        {"ray_backend": "numpy"},
        {"detector": {"fit_compute": "numpy", "iterations": 3}},
        {"detector": {"fit_backend": "auto"}, "ray_compute": "cuda"},
    ],
)
def test_the_retired_laser_options_are_read_with_a_warning_and_do_nothing(options):
    """The options that chose between the laser chain's numpy and compiled code (and their earlier names) are
    read, whatever their value, with a FutureWarning naming each, and build the chain built without them."""
    from viapath.perception.laser import LaserPerception
    from viapath.scenarios.build import build

    data = yaml.safe_load(GOOD)
    data["perception"] = {"mode": "laser", "options": options}
    given = [name for part in (options, options.get("detector", {})) for name in part if name != "detector"]
    with pytest.warns(FutureWarning) as caught:
        built = build(scenario_from_dict(data)).perception
    retired = [name for name in given if name != "iterations"]
    for name in retired:
        assert any(f"option {name!r} no longer does anything" in str(w.message) for w in caught), name
    detector = options.get("detector")
    plain = LaserPerception(detector=None if detector is None else {"iterations": 3} if "iterations" in given else {})
    assert built.detector_params == plain.detector_params and built.scanners == plain.scanners


def test_the_laser_option_models_default_to_the_dataclasses():
    from viapath.perception.detection import DetectorParams
    from viapath.perception.laser_options import (
        DetectorOptions,
        ScannerOptions,
        StaticLayerOptions,
        TrackerOptions,
    )
    from viapath.perception.scanner import ScannerModel
    from viapath.perception.static_layer import StaticLayerParams
    from viapath.perception.tracking import TrackerParams

    for model, cls in (
        (ScannerOptions, ScannerModel),
        (DetectorOptions, DetectorParams),
        (TrackerOptions, TrackerParams),
        (StaticLayerOptions, StaticLayerParams),
    ):
        assert model().build() == cls()
        defaults = {name: field.get_default(call_default_factory=True) for name, field in model.model_fields.items()}
        built = {name: getattr(cls(), name) for name in defaults}
        assert {name: value for name, value in defaults.items() if name != "segmentation"} == {
            name: value for name, value in built.items() if name != "segmentation"
        }
    assert DetectorOptions().segmentation.build() == DetectorParams().segmentation
