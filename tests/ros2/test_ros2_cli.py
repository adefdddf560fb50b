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
        "choice": (["--ros-args", "-p", "planner.preferred_side:=up"], "parameter planner.preferred_side: expected one of left, right"),
        "file": (["--params-file", str(bad_file)], "parameter planner.horizn_s: unknown parameter"),
    }
    procs = Processes(tmp_path)
    try:
        started = {name: procs.start(name, viapath("ros2", "node", *args), domain_id()) for name, (args, _) in cases.items()}
        for name, proc in started.items():
            assert procs.wait(proc, 90) == 2, procs.output(proc)
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
