"""Hostile input, second round: YAML and files that would take unbounded time or memory are refused
quickly, everywhere viapath reads them (scenario files, presets, bench suites, the ROS 2 node's
path_file and parameters file, ``--option`` values), with a short message naming the file and,
where there is one, the field; replay files are bounded too.

On main a dozen-line alias bomb hung ``viapath run`` for minutes past 2 GB, integer literals of
thousands of digits and waypoints at ±1e308 ended in tracebacks, and a replay file /dev/zero grew
without bound."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from tests.robustness._hostile import SCENARIO_HEAD, far_coordinates, hostile_yaml, long_integers
from viapath.io.safe_read import MAX_YAML_BYTES, InputError, load_yaml, read_text_file
from viapath.presets import PresetError, load_preset, parse_preset
from viapath.scenarios import ScenarioError, load_scenario
from viapath.scenarios.loader import _parse

VIAPATH = str(Path(sys.executable).parent / "viapath")
MAX_MESSAGE_CHARS = 600
_FAST = settings(max_examples=25, deadline=None, database=None, suppress_health_check=list(HealthCheck))


def _short_refusal(error: BaseException, origin: str) -> str:
    message = str(error)
    assert message.startswith(origin), message[:300]
    assert len(message) < MAX_MESSAGE_CHARS, message[:300]
    return message


@_FAST
@given(hostile_yaml())
def test_oversized_yaml_is_refused_by_every_reader(text):
    with pytest.raises(ScenarioError) as error:
        _parse(text, "s.yaml", base_dir=None)
    _short_refusal(error.value, "s.yaml")
    with pytest.raises(PresetError) as error:
        parse_preset(text, "p.yaml")
    _short_refusal(error.value, "p.yaml")
    with pytest.raises(InputError):
        load_yaml(text, "any")


@_FAST
@given(long_integers())
def test_integer_literals_of_thousands_of_digits_name_the_field(case):
    text, field = case
    with pytest.raises(ScenarioError) as error:
        _parse(text, "s.yaml", base_dir=None)
    message = _short_refusal(error.value, "s.yaml")
    assert f": {field}: " in message and "digits" in message, message


@_FAST
@given(far_coordinates())
def test_coordinates_near_the_float_limit_name_the_field(case):
    text, field = case
    with pytest.raises(ScenarioError) as error:
        _parse(text, "s.yaml", base_dir=None)
    message = _short_refusal(error.value, "s.yaml")
    assert f": {field}: " in message and "1000000" in message, message


def test_a_legitimate_file_with_aliases_still_loads(tmp_path):
    text = SCENARIO_HEAD + "w: &w {velocity: [0, 0], radius: 0.3}\n"
    data = load_yaml(text + "x: [*w, *w]\n")
    assert data["x"] == [{"velocity": [0, 0], "radius": 0.3}] * 2


def test_error_messages_quote_a_huge_value_shortly():
    big = "[" + ", ".join(["[1, 2, 3]"] * 5000) + "]"
    with pytest.raises(ScenarioError) as error:
        _parse(SCENARIO_HEAD.replace("name: hostile", f"name: {big}"), "s.yaml", base_dir=None)
    assert "name" in str(error.value) and len(str(error.value)) < MAX_MESSAGE_CHARS


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom"])
def test_devices_and_folders_are_not_read(tmp_path, device):
    with pytest.raises(ScenarioError, match="not a regular file"):
        load_scenario(device)
    with pytest.raises(PresetError, match="nor a preset file"):
        load_preset(device)
    with pytest.raises(InputError, match="not a regular file"):
        read_text_file(device)


def test_files_above_the_cap_are_refused_before_reading(tmp_path):
    big = tmp_path / "big.yaml"
    with open(big, "wb") as handle:
        handle.truncate(MAX_YAML_BYTES + 1)  # sparse: no disk used
    with pytest.raises(ScenarioError, match=r"big.yaml: .*bytes; .* at most"):
        load_scenario(big)


def test_replay_files_are_bounded(tmp_path):
    from viapath.io.eth_ucy import load_tracks

    for source in ("/dev/zero", "/dev/urandom"):
        with pytest.raises(ValueError, match="not a regular file"):
            load_tracks(source, 0.4)
    huge = tmp_path / "huge.txt"
    with open(huge, "wb") as handle:
        handle.truncate(200 * 1024 * 1024)
    with pytest.raises(ValueError, match=r"bytes; .* at most"):
        load_tracks(huge, 0.4)


def test_ros_path_file_and_parameters_file_use_the_safe_reader(tmp_path):
    from viapath.ros2.convert import PathFileError, load_path_file
    from viapath.ros2.settings import ParameterError, read_params_file

    bomb = tmp_path / "bomb.yaml"
    bomb.write_text(
        "a: &a [x, x, x, x, x, x, x, x, x, x]\n"
        + "".join(f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join([f'*{chr(97 + i)}'] * 10)}]\n" for i in range(8))
    )
    with pytest.raises(PathFileError, match="aliases"):
        load_path_file(str(bomb))
    with pytest.raises(ParameterError, match="aliases"):
        read_params_file(bomb)
    with pytest.raises(ParameterError, match="not a regular file"):
        read_params_file("/dev/zero")


def test_option_values_from_the_command_line_are_bounded():
    from viapath.cli.run import parse_assignment
    from viapath.options import OptionError

    value = "9" * 5000
    with pytest.raises(OptionError, match="digits"):
        parse_assignment(f"max_depth={value}")


def _limited():
    """In the child: at most 1.5 GB of heap and 20 s of CPU (a bomb on main passed 2 GB in seconds)."""
    resource.setrlimit(resource.RLIMIT_DATA, (1536 * 1024 * 1024, 1536 * 1024 * 1024))
    resource.setrlimit(resource.RLIMIT_CPU, (20, 20))


@pytest.mark.parametrize("command", ["run", "bench", "weights"])
def test_cli_refuses_a_bomb_with_exit_2_and_bounded_memory(tmp_path, command):
    bomb = tmp_path / "suite" / "bomb.yaml"
    bomb.parent.mkdir()
    bomb.write_text(
        SCENARIO_HEAD
        + "a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n"
        + "".join(f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join([f'*{chr(97 + i)}'] * 9)}]\n" for i in range(8))
        + "obstacles: *i\n"
    )
    args = {
        "run": ["run", str(bomb)],
        "bench": [
            "bench",
            str(bomb.parent),
            "--planners",
            "follow",
            "--out",
            str(tmp_path / "out"),
            "--workers",
            "1",
            "--no-plots",
        ],
        "weights": ["run", "hallway", "--weights", str(bomb)],
    }[command]
    result = subprocess.run(
        [VIAPATH, *args],
        capture_output=True,
        text=True,
        timeout=60,
        preexec_fn=_limited,
        env={**os.environ, "COLUMNS": "200"},
    )
    assert result.returncode == 2, result.stderr[-2000:]
    assert "Traceback" not in result.stderr and "aliases" in result.stderr, result.stderr[-2000:]
    assert len(result.stderr) < 2000
