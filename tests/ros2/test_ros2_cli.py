"""``viapath ros2 node`` refuses a bad parameter at start, naming it, and never commands (exit 2).

Each process runs in a ROS domain of its own with DDS kept on this machine, and is ended by pid
by the test (also on failure).
"""

from __future__ import annotations

import pytest

from viapath.ros2 import rclpy_available

OK, WHY = rclpy_available()
pytestmark = pytest.mark.skipif(not OK, reason=WHY)

from _ros2_procs import Processes, domain_id, viapath  # noqa: E402


def test_bad_parameters_are_refused_by_name(tmp_path):
    bad_file = tmp_path / "bad.yaml"
    bad_file.write_text("viapath:\n  ros__parameters:\n    planner:\n      horizn_s: 3.0\n")
    cases = {
        "negative": (["--ros-args", "-p", "nominal_speed_mps:=-1.0"], "parameter nominal_speed_mps: expected >= 0.01"),
        "choice": (
            ["--ros-args", "-p", "planner.preferred_side:=up"],
            "parameter planner.preferred_side: expected one of left, right",
        ),
        "file": (["--params-file", str(bad_file)], "parameter planner.horizn_s: unknown parameter"),
    }
    procs = Processes(tmp_path)
    try:
        started = {
            name: procs.start(name, viapath("ros2", "node", *args), domain_id()) for name, (args, _) in cases.items()
        }
        for name, proc in started.items():
            assert procs.wait(proc, 240) == 2, procs.output(proc)  # slow only on a loaded machine
            _, err = procs.output(proc)
            assert cases[name][1] in err
            assert "active: commanding" not in err
    finally:
        procs.stop_all()


def test_sim_refuses_a_bad_fault_and_rate(tmp_path):
    procs = Processes(tmp_path)
    try:
        a = procs.start("fault", viapath("ros2", "sim", "paper-side", "--fault", "silence@2"), domain_id())
        b = procs.start("rate", viapath("ros2", "sim", "paper-side", "--rate", "0"), domain_id())
        assert procs.wait(a, 60) == 2 and "name the scanner" in procs.output(a)[1]
        assert procs.wait(b, 60) == 2 and "--rate: expected a number > 0" in procs.output(b)[1]
    finally:
        procs.stop_all()


def test_every_mistake_is_named_and_values_that_exhaust_memory_are_refused(tmp_path):
    two = tmp_path / "two.yaml"
    two.write_text("viapath:\n  ros__parameters:\n    nominal_speed_mps: -1.0\n    planner:\n      horizn_s: 3.0\n")
    cases = {
        "two": (
            ["--params-file", str(two)],
            ["parameter nominal_speed_mps: expected >= 0.01", "parameter planner.horizn_s: unknown parameter"],
        ),
        "memory": (
            [
                "--ros-args",
                "-p",
                "planner.rollout_s:=1e9",
                "-p",
                "planner.rollout_dt_s:=1e-9",
                "-p",
                "planner.escape_s:=1e9",
                "-p",
                "planner.escape_dt_s:=1e-9",
            ],
            [
                "parameter planner.rollout_s:",
                "parameter planner.rollout_dt_s:",
                "parameter planner.escape_s:",
                "parameter planner.escape_dt_s:",
            ],
        ),
    }
    procs = Processes(tmp_path)
    try:
        started = {
            name: procs.start(name, viapath("ros2", "node", *args), domain_id()) for name, (args, _) in cases.items()
        }
        for name, proc in started.items():
            assert procs.wait(proc, 240) == 2, procs.output(proc)  # slow only on a loaded machine
            _, err = procs.output(proc)
            assert all(words in err for words in cases[name][1]), err
            assert "error: None" not in err and "active: commanding" not in err
    finally:
        procs.stop_all()


def test_a_failure_while_configuring_is_reported_with_its_text(monkeypatch):
    """Whatever goes wrong while the node builds its planner, it says what (not "error: None")."""
    import os

    import rclpy
    from _ros2_procs import ros_env

    from viapath.ros2.core import PlannerCore
    from viapath.ros2.node import make_node_class

    for key, value in ros_env(domain_id()).items():
        if key.startswith("ROS_"):
            monkeypatch.setenv(key, value)
    monkeypatch.delenv("ROS_STATIC_PEERS", raising=False)
    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"

    def no_memory(self):
        raise MemoryError()

    monkeypatch.setattr(PlannerCore, "warm_up", no_memory)
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = make_node_class()(context=context)
        try:
            node.trigger_configure()
            assert node.error and "MemoryError" in node.error, node.error
        finally:
            node.destroy_node()
    finally:
        rclpy.shutdown(context=context)
