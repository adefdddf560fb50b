"""End to end over DDS: ``viapath ros2 sim`` and ``viapath ros2 node`` in separate processes.

The paper's three scenarios run through the node (scans, odometry, /clock and the designated path
in; cmd_vel out) and must show the paper's behaviours, and their metrics must agree with
``viapath run SCENARIO --perception laser`` (the same perception and planner in one process). The
pairs are started by the session launcher (``conftest.py``) at the same time as every other ROS 2
test's processes, each in its own ROS domain, in lock-step at up to 20x real time.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

from viapath.ros2 import rclpy_available

OK, WHY = rclpy_available()
pytestmark = pytest.mark.skipif(not OK, reason=WHY)

PAPER = ("paper-behind", "paper-front", "paper-side")


def read_trace(file) -> dict[str, np.ndarray]:
    with open(file) as handle:
        rows = list(csv.DictReader(handle))
    return {
        key: np.array([float(r[key]) if r[key] not in ("", None) else np.nan for r in rows])
        for key in rows[0]
        if key != "plan_status"
    }


@pytest.fixture(scope="module")
def paper_runs(ros2_launcher):
    return ros2_launcher.paper()[0]


@pytest.fixture(scope="module")
def in_process(ros2_launcher):
    return ros2_launcher.paper()[1]


@pytest.mark.parametrize("name", PAPER)
def test_reaches_the_goal_without_contact(paper_runs, name):
    metrics, trace, _ = paper_runs[name]
    assert metrics["reached_goal"] and not metrics["collision"]
    assert metrics["scenario"] == name and metrics["perception"] == "laser"
    gap = np.hypot(trace["x_m"] - trace["obstacle0_x_m"], trace["y_m"] - trace["obstacle0_y_m"]) - 0.5
    assert np.nanmin(gap) > 0.0
    assert np.hypot(trace["x_m"][-1] - 5.0, trace["y_m"][-1]) <= 0.1


def test_behind_speeds_up_on_the_path(paper_runs):
    _, trace, _ = paper_runs["paper-behind"]
    assert trace["speed_mps"].max() >= 0.29
    assert np.all(np.abs(trace["lateral_deviation_m"]) < 0.05)


def test_front_passes_on_the_left(paper_runs):
    _, trace, _ = paper_runs["paper-front"]
    alongside = np.abs(trace["obstacle0_x_m"] - trace["x_m"]) < 0.5
    assert alongside.any()
    assert np.all(trace["y_m"][alongside] > trace["obstacle0_y_m"][alongside])  # the person is on the robot's right
    assert trace["y_m"].max() > 0.2 and trace["y_m"].min() > -0.05
    assert np.all(np.abs(trace["y_m"]) < 1.0)  # inside the corridor


def test_side_slows_and_lets_the_person_pass(paper_runs):
    _, trace, _ = paper_runs["paper-side"]
    crossing = int(np.argmax(trace["obstacle0_y_m"] >= 0))
    assert crossing > 0
    assert trace["speed_mps"][:crossing].min() <= 0.11
    assert trace["speed_mps"][crossing:].max() >= 0.19
    assert trace["x_m"][crossing] < trace["obstacle0_x_m"][crossing]  # the person went first
    assert np.all(np.abs(trace["lateral_deviation_m"]) < 0.05)


@pytest.mark.parametrize("name", PAPER)
def test_metrics_agree_with_viapath_run(paper_runs, in_process, name):
    """Same keys as ``viapath run --json``; values as close as the transport allows.

    In lock-step (every command applied in its own step) only the float32 ranges of ``LaserScan``
    differ: measured, time to goal equal, clearance and path length equal to 1e-7 m. The margins
    below leave room for nothing else.
    """
    metrics, _, _ = paper_runs[name]
    reference = in_process[name]
    assert set(metrics) == set(reference)
    assert metrics["reached_goal"] == reference["reached_goal"]
    assert abs(metrics["time_to_goal_s"] - reference["time_to_goal_s"]) <= 0.3
    assert abs(metrics["min_clearance_m"] - reference["min_clearance_m"]) <= 0.02
    assert abs(metrics["path_length_m"] - reference["path_length_m"]) <= 0.05
    assert abs(metrics["max_lateral_deviation_m"] - reference["max_lateral_deviation_m"]) <= 0.02
    assert abs(metrics["max_speed_mps"] - reference["max_speed_mps"]) <= 0.02
    assert (
        metrics["shield"] == reference["shield"]
        and metrics["shield_interventions"] == reference["shield_interventions"]
    )
    assert abs(metrics["track_samples"] - reference["track_samples"]) <= 3
    assert abs(metrics["track_position_rmse_m"] - reference["track_position_rmse_m"]) <= 0.005
    for key in ("perception_time_p50_ms", "perception_time_p99_ms", "plan_time_p50_ms", "plan_time_p99_ms"):
        # measured on both sides (null only where a value does not exist); the node's are its own cycle's parts
        assert reference[key] is not None and metrics[key] is not None and 0.0 < metrics[key] < 1000.0, key


def test_every_command_was_finite_and_inside_the_limits(paper_runs, tmp_path_factory):
    for name in PAPER:
        _, trace, stderr = paper_runs[name]
        v, w = trace["cmd_speed_mps"][:-1], trace["cmd_turn_rate_radps"][:-1]
        assert np.all(np.isfinite(v)) and np.all(np.isfinite(w))
        assert np.all((v >= 0) & (v <= 0.6 + 1e-9)) and np.all(np.abs(w) <= 2.0 + 1e-9)
        # never asks for more speed than the robot gains in a cycle; braking harder is always allowed (a person
        # reported in the first cycle slows the robot from its starting speed at once)
        assert np.all(v - trace["speed_mps"][:-1] <= 0.08 + 1e-6)
        assert "0 without the node's command in time" in stderr, stderr


def test_the_table_in_the_docs_is_what_the_runs_print(paper_runs, in_process):
    """docs/results.md's ROS 2 table is generated (benchmarks/ros2_paper_table.py), never typed: the same runs give it."""
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    sys.path.insert(0, str(root / "benchmarks"))
    from ros2_paper_table import table

    text = table({name: paper_runs[name][0] for name in PAPER}, {name: in_process[name] for name in PAPER})
    assert text in (root / "docs" / "results.md").read_text(), (
        "regenerate it: python benchmarks/results_page.py --with ros2\n" + text
    )
