"""Issue 12, findings 6 and 7, and the small ones: scenarios that cannot hang or mislead.

On main: dt_s 1e-6 (40 million steps) was accepted and ran silently for minutes; an obstacle that
started on the robot counted as an at-fault collision without a word; a corridor narrower than the
robot gave no warning; duplicate YAML keys were accepted; a missing replay file's message showed a
relative path; a refused bench left an empty folder behind; there was no --version and flags showed
``<bool>`` in the help."""

from __future__ import annotations

import re
import time

import pytest
from typer.testing import CliRunner

from viapath.scenarios import ScenarioError, load_scenario, scenario_from_dict
from viapath.sim.loop import run_episode


def _base(**changes) -> dict:
    data = {
        "name": "checks",
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.2, "radius": 0.25},
        "path": {"waypoints": [[0.0, 0.0], [3.0, 0.0]], "half_width": 1.0},
        "obstacles": [],
        "duration_s": 20.0,
    }
    data.update(changes)
    return data


def _app():
    from viapath.cli import app

    return app


def test_finding_6_too_many_steps_is_an_error_naming_dt(tmp_path):
    with pytest.raises(ScenarioError, match=r"dt_s: .*40,000,000 steps; at most 1,000,000"):
        scenario_from_dict(_base(dt_s=0.000001, duration_s=40.0))
    file = tmp_path / "tiny-dt.yaml"
    file.write_text(
        "name: t\nrobot: {start: [0, 0]}\npath: {waypoints: [[0, 0], [5, 0]], half_width: 1.0}\n"
        "duration_s: 40\ndt_s: 0.000001\n"
    )
    started = time.monotonic()
    result = CliRunner().invoke(_app(), ["run", str(file)])
    assert result.exit_code == 2 and "dt_s" in result.output
    assert time.monotonic() - started < 30


def test_finding_6_start_overlap_warns_and_is_not_at_fault():
    scenario = scenario_from_dict(_base(obstacles=[{"start": [0.3, 0.0], "velocity": [0.0, 0.0], "radius": 0.25}]))
    from viapath.sim.checks import scenario_warnings

    warnings = scenario_warnings(scenario)
    assert any("obstacle 0 starts overlapping the robot" in w for w in warnings), warnings
    metrics = run_episode(scenario, planner="follow").metrics
    assert metrics["collision"]  # there was contact
    assert metrics["overlapping_at_appearance"] == 1
    assert not metrics["at_fault_collision"]
    # A person met later, driving into them, still counts as at fault.
    later = scenario_from_dict(_base(obstacles=[{"start": [1.5, 0.0], "velocity": [-0.3, 0.0], "radius": 0.25}]))
    later_metrics = run_episode(later, planner="follow").metrics
    assert later_metrics["at_fault_collision"] and later_metrics["overlapping_at_appearance"] == 0


def test_finding_7_corridor_narrower_than_robot_warns(tmp_path):
    from viapath.sim.checks import scenario_warnings

    narrow = scenario_from_dict(_base(path={"waypoints": [[0.0, 0.0], [3.0, 0.0]], "half_width": 0.1}))
    assert any(
        w.startswith("path.half_width = 0.1 m is less than the robot radius 0.25 m") for w in scenario_warnings(narrow)
    )
    assert scenario_warnings(scenario_from_dict(_base())) == []
    file = tmp_path / "narrow.yaml"
    file.write_text(
        "name: n\nrobot: {start: [0, 0]}\npath: {waypoints: [[0, 0], [1, 0]], half_width: 0.1}\nduration_s: 10\n"
    )
    result = CliRunner().invoke(_app(), ["run", str(file), "--planner", "follow"])
    assert result.exit_code == 0 and "warning:" in result.output and "narrower than the robot" in result.output


def test_duplicate_yaml_key_names_both_lines(tmp_path):
    file = tmp_path / "dup.yaml"
    file.write_text(
        "name: a\nrobot: {start: [0, 0]}\npath:\n  waypoints: [[0, 0], [5, 0]]\n  half_width: 1.0\n  half_width: 0.5\n"
    )
    with pytest.raises(ScenarioError, match=r"dup\.yaml: line 6: duplicate key 'half_width' \(first given on line 5\)"):
        load_scenario(file)


def test_missing_replay_file_shows_resolved_path(tmp_path, monkeypatch):
    folder = tmp_path / "suite"
    folder.mkdir()
    (folder / "r.yaml").write_text(
        "name: r\nrobot: {start: [0, 0]}\npath: {waypoints: [[0, 0], [5, 0]], "
        "half_width: 1.0}\nobstacles:\n  - replay: {file: data/nothere.txt}\n"
    )
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(_app(), ["run", "suite/r.yaml"])
    assert result.exit_code == 2
    assert str((folder / "data" / "nothere.txt").resolve()) in result.output.replace("\n", "")


def test_refused_bench_leaves_no_folder(tmp_path):
    out = tmp_path / "results"
    result = CliRunner().invoke(_app(), ["bench", "paper", "--count", "1", "--planners", "nosuch", "--out", str(out)])
    assert result.exit_code == 2 and "unknown planner" in result.output
    assert not out.exists()


def test_version_and_plain_flags_in_help():
    from viapath.bench.identity import viapath_version

    result = CliRunner().invoke(_app(), ["--version"])
    assert result.exit_code == 0 and result.output.strip() == f"viapath {viapath_version()}"
    help_text = CliRunner().invoke(_app(), ["run", "--help"], env={"COLUMNS": "200"}).output
    json_line = next(line for line in help_text.splitlines() if "--json" in line)
    assert "<bool>" not in json_line and "bool" not in json_line.lower().replace("boolean", "")


def test_progress_bar_reads_elapsed_then_left(capsys):
    from viapath.bench.runner import _with_progress

    assert list(_with_progress(iter([{"a": 1}, {"a": 2}]), 2, True)) == [{"a": 1}, {"a": 2}]
    line = [x for x in capsys.readouterr().err.splitlines() if "episodes" in x][-1]
    assert re.search(r"elapsed \d+:\d\d:\d\d / \d+:\d\d:\d\d left", line), line


def test_animation_progress_callback_shows_frames():
    import io

    from rich.console import Console

    from viapath.cli.extras import animation_progress

    buffer = io.StringIO()
    update, close = animation_progress(Console(file=buffer, force_terminal=True, width=120))
    for frame in range(3):
        update(frame, 3)
    close()
    text = buffer.getvalue()
    assert "writing frames" in text and "3/3" in text
