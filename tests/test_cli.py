"""The ``viapath`` command line (docs/design.md §4): run, --json, --seed, --plot, --trace, scenarios, bad options."""

from __future__ import annotations

import csv
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from viapath.cli import app

SRC = Path(__file__).resolve().parents[1] / "src"
BUILTIN_DIR = SRC / "viapath" / "scenarios" / "builtin"

# The design's metric list is its specification: read from where the design writes it (a bullet "* **Metrics**" in
# docs/design.md), not from the code's own list, so that a metric the code drops is caught.
DESIGN = SRC.parent / "docs" / "design.md"


def _design_metrics() -> list[str]:
    bullet = re.search(r"^\* \*\*Metrics\*\*.*?(?=^\S|^\* |\Z)", DESIGN.read_text(encoding="utf-8"), re.M | re.S)
    assert bullet is not None, f"no '* **Metrics**' bullet in {DESIGN}"
    names = re.findall(r"`([a-z][a-z0-9_]*)`", bullet.group(0))
    assert {"reached_goal", "collision", "plan_time_p99_ms"} <= set(names), names  # the bullet was read
    return names


def _invoke(*args: str):
    result = CliRunner().invoke(app, list(args))
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result


def _run_json(*args: str) -> dict:
    result = _invoke("run", *args, "--json")
    assert result.exit_code == 0, result.output
    lines = [line for line in result.stdout.splitlines() if line.strip()]
    assert len(lines) == 1, f"--json must print exactly one line, got: {result.stdout!r}"
    data = json.loads(lines[0])
    assert isinstance(data, dict)
    return data


@pytest.fixture(scope="module")
def front_metrics() -> dict:
    return _run_json("paper-front")


def test_run_json_has_every_metric_of_the_design(front_metrics):
    for name in _design_metrics():
        assert name in front_metrics, name


def test_run_paper_front_json(front_metrics):
    m = front_metrics
    assert m["reached_goal"] is True
    assert m["collision"] is False
    assert m["min_clearance_m"] > 0  # consistent with "no collision" (surface-to-surface)
    # Physical bounds from the scenario (start (0,0), goal (5,0) within 0.1 m, corridor ±1 m, speeds <= 0.5).
    assert m["path_length_m"] >= 5.0 - 0.1
    assert 0 < m["time_to_goal_s"] <= 60.0
    assert m["time_to_goal_s"] >= (5.0 - 0.1) / 0.5
    assert m["path_length_m"] <= m["max_speed_mps"] * m["time_to_goal_s"] + 1e-9
    assert 0 <= m["mean_lateral_deviation_m"] <= m["max_lateral_deviation_m"] <= 1.0
    assert m["time_outside_corridor_s"] == 0.0
    assert 0 <= m["min_speed_mps"] <= m["max_speed_mps"] <= 0.5 + 1e-9
    assert 0 < m["plan_time_p50_ms"] <= m["plan_time_p99_ms"]
    # Head-on obstacle: the robot must leave the centre line to pass it.
    assert m["max_lateral_deviation_m"] > 0.25


def test_run_json_via_process_prints_one_object():
    """The real entry point, with nothing but the JSON object on stdout."""
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    script = Path(sys.executable).parent / "viapath"
    command = [str(script)] if script.exists() else [sys.executable, "-m", "viapath.cli"]
    done = subprocess.run(
        [*command, "run", "paper-front", "--json"], capture_output=True, text=True, env=env, timeout=120
    )
    assert done.returncode == 0, done.stderr
    data = json.loads(done.stdout)  # the whole of stdout is one JSON document
    assert data["reached_goal"] is True and data["collision"] is False
    assert "Traceback" not in done.stderr


def _without_timings(metrics: dict) -> dict:
    return {k: v for k, v in metrics.items() if not k.startswith("plan_time_")}


def test_seed_determinism_with_noise():
    noise = ("--position-noise", "0.03", "--velocity-noise", "0.05")
    first = _run_json("paper-side", "--seed", "7", *noise)
    second = _run_json("paper-side", "--seed", "7", *noise)
    assert _without_timings(first) == _without_timings(second)
    # The seed is really used: another seed gives a different noisy episode.
    other = _run_json("paper-side", "--seed", "8", *noise)
    assert _without_timings(other) != _without_timings(first)


def test_plot_writes_png(tmp_path):
    target = tmp_path / "episode.png"
    result = _invoke("run", "paper-front", "--plot", str(target))
    assert result.exit_code == 0, result.output
    data = target.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(data) > 1000


def test_trace_rows_match_steps(tmp_path, front_metrics):
    target = tmp_path / "trace.csv"
    result = _invoke("run", "paper-front", "--trace", str(target))
    assert result.exit_code == 0, result.output
    with target.open() as handle:
        rows = list(csv.DictReader(handle))
    times = np.array([float(r["time_s"]) for r in rows])
    dt = 0.1  # paper-front uses the default control period
    # One row per control step: from 0 to the arrival time, every dt.
    assert times[0] == 0.0
    np.testing.assert_allclose(np.diff(times), dt, atol=1.5e-3)
    assert times[-1] == pytest.approx(front_metrics["time_to_goal_s"], abs=1e-3)
    assert len(rows) == round(front_metrics["time_to_goal_s"] / dt) + 1
    # The trace agrees with the metrics (CSV keeps 4 decimals).
    xy = np.array([[float(r["x_m"]), float(r["y_m"])] for r in rows])
    length = float(np.sum(np.hypot(*np.diff(xy, axis=0).T)))
    assert length == pytest.approx(front_metrics["path_length_m"], abs=len(rows) * 2 * math.sqrt(2) * 5e-5)
    lateral = np.abs([float(r["lateral_deviation_m"]) for r in rows])
    assert lateral.max() == pytest.approx(front_metrics["max_lateral_deviation_m"], abs=1e-4)
    np.testing.assert_allclose(lateral, np.abs(xy[:, 1]), atol=1e-4)  # straight path along the x axis


def test_scenarios_lists_builtins():
    result = _invoke("scenarios")
    assert result.exit_code == 0, result.output
    names = sorted(p.stem for p in BUILTIN_DIR.glob("*.yaml"))
    assert {"paper-behind", "paper-front", "paper-side"} <= set(names)
    listed = {line.split("│")[1].strip() for line in result.stdout.splitlines() if line.count("│") >= 3}
    assert set(names) <= listed, (names, listed)


@pytest.mark.parametrize("name", ["paper-behind", "paper-side"])
def test_other_paper_scenarios_reach_the_goal(name):
    m = _run_json(name)
    assert m["reached_goal"] is True and m["collision"] is False
    assert m["time_outside_corridor_s"] == 0.0


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--plot", "x.txt"], "--plot"),
        (["--plot", "no/such/folder/x.png"], "does not exist"),
        (["--trace", "x.json"], "--trace"),
        (["--animate", "x.avi"], "--animate"),
        (["--animate", "x.gif", "--frame-stride", "0"], "--frame-stride"),
        (["--planner", "nosuch"], "--planner"),
        (["--perception", "radar"], "--perception"),
        (["--position-noise", "nan"], "--position-noise"),
        (["--velocity-noise", "-1"], "--velocity-noise"),
        (["--velocity-noise", "inf"], "--velocity-noise"),
        (["--seed", "-1"], "--seed"),
    ],
)
def test_bad_options_fail_cleanly(tmp_path, args, needle):
    args = [str(tmp_path / a) if a.startswith(("x.", "no/")) else a for a in args]
    result = _invoke("run", "paper-front", *args, "--json")
    assert result.exit_code != 0
    assert "Traceback" not in result.output
    assert needle in result.output, result.output
    assert result.stdout == ""


def test_an_interrupt_wrapped_by_numba_is_recognised_as_one():
    """numba turns a Ctrl-C that lands in its call back into Python into chained SystemErrors; `viapath run`
    must still end with 'interrupted' (130), and only then."""
    from viapath.cli.common import caused_by_interrupt as _caused_by_interrupt

    def wrapped(inner):
        try:
            try:
                raise inner
            except BaseException as cause:
                raise SystemError("returned a result with an exception set") from cause
        except SystemError as outer:
            try:
                raise SystemError("again") from outer
            except SystemError as error:
                return error

    assert _caused_by_interrupt(wrapped(KeyboardInterrupt()))
    assert not _caused_by_interrupt(wrapped(ValueError("not an interrupt")))
    assert not _caused_by_interrupt(SystemError("alone"))
