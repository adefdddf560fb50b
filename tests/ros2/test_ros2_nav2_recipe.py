"""docs/nav2.md's "Try it without a robot", end to end: its three commands as written (``viapath ros2
nav2 --use-sim-time``, ``viapath ros2 sim paper-front …``, ``viapath ros2 follow paper-front …``), real
processes over DDS in a ROS domain of their own, ended by pid. The goal must succeed when the robot
reaches the end of the path, while the simulator still runs; ``follow`` prints the result and exits 0.
"""

from __future__ import annotations

import re
import shlex
import time
from pathlib import Path

import pytest
from _ros2_procs import Processes, domain_id, viapath

from viapath.ros2 import rclpy_available

OK, WHY = rclpy_available()
pytestmark = pytest.mark.skipif(not OK, reason=WHY)

NAV2_MD = Path(__file__).resolve().parents[2] / "docs" / "nav2.md"


def recipe() -> list[list[str]]:
    """The commands of the page's block that runs ``viapath ros2 follow``."""
    for block in re.findall(r"```bash\n(.*?)```", NAV2_MD.read_text(), flags=re.S):
        if "viapath ros2 follow" in block:
            lines = [line.split("#")[0].strip() for line in block.splitlines()]
            return [shlex.split(line) for line in lines if line]
    raise AssertionError(f"{NAV2_MD}: no bash block with 'viapath ros2 follow'")


def test_the_recipe_commands_are_the_controller_the_simulator_and_the_client():
    commands = recipe()
    assert [c[:3] for c in commands] == [
        ["viapath", "ros2", "nav2"],
        ["viapath", "ros2", "sim"],
        ["viapath", "ros2", "follow"],
    ]


def test_the_nav2_recipe_ends_with_success_before_the_simulator_stops(tmp_path):
    from viapath.ros2 import interfaces

    interfaces.build()  # cached after the first build on this machine
    node_cmd, sim_cmd, follow_cmd = recipe()
    procs, domain = Processes(tmp_path), domain_id()
    try:
        node = procs.start("recipe_node", viapath(*node_cmd[1:]), domain)
        sim = procs.start("recipe_sim", viapath(*sim_cmd[1:]), domain)
        follow = procs.start("recipe_follow", viapath(*follow_cmd[1:]), domain)
        ended: dict[str, float] = {}
        deadline = time.monotonic() + 300
        while len(ended) < 2 and time.monotonic() < deadline:
            for name, proc in (("sim", sim), ("follow", follow)):
                if name not in ended and proc.poll() is not None:
                    ended[name] = time.monotonic()
            time.sleep(0.05)
        follow_out, follow_err = procs.output(follow)
        sim_out, sim_err = procs.output(sim)
        running = sorted({"sim", "follow"} - set(ended))
        assert not running, f"still running after 300 s: {running}\n{follow_err[-2000:]}"
        assert follow.returncode == 0, f"follow exited {follow.returncode}\n{follow_out}\n{follow_err[-3000:]}"
        assert sim.returncode == 0, sim_err[-3000:]
        assert node.poll() is None, "the controller stays up until stopped"
    finally:
        procs.stop_all()
    # without --log the JSON records go to stdout and the result line to stderr
    (result,) = [line for line in follow_err.splitlines() if line.startswith("follow_path:")]
    assert result.startswith("follow_path: SUCCEEDED"), result
    metrics = dict(line.split(": ", 1) for line in sim_out.splitlines() if ": " in line)
    assert metrics["reached_goal"] == "True" and metrics["collision"] == "False", sim_out
    # the result came at the goal, before the simulator stopped
    assert ended["follow"] < ended["sim"]
    t = float(re.search(r"at t = ([\d.]+) s", result).group(1))
    assert abs(t - float(metrics["time_to_goal_s"])) <= 1.0, (result, metrics["time_to_goal_s"])
