"""Every node a ``viapath ros2`` process creates has a name of its own, also when the node is renamed on the
command line as Nav2 starts its controller (``--ros-args -r __node:=controller_server``), and the user's
remappings and namespace still reach the topics and actions of every one of them. Real processes over DDS,
their own ROS domain, ended by pid; the graph is read by a third process (``_graph_probe.py``).

Two nodes in one domain: ``viapath ros2 nav2`` renamed ``controller_server`` in ``/robot1`` (map, command and
FollowPath action remapped) and ``viapath ros2 node`` renamed ``follower`` in ``/robot2`` (path and command
remapped)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from _ros2_procs import Processes, domain_id, viapath

NAV2 = "/robot1/controller_server"
FOLLOWER = "/robot2/follower"
EXPECTED = [NAV2, NAV2 + "_inputs", NAV2 + "_map", FOLLOWER, FOLLOWER + "_inputs"]


@pytest.fixture(scope="module")
def graph(tmp_path_factory):
    from viapath.ros2 import interfaces, rclpy_available

    ok, why = rclpy_available()
    if not ok:
        pytest.skip(why)
    interfaces.build()
    folder = tmp_path_factory.mktemp("node_names")
    procs = Processes(folder)
    domain = domain_id()
    out = folder / "graph.json"
    try:
        nav2 = procs.start(
            "nav2",
            viapath(
                "ros2",
                "nav2",
                "--ros-args",
                "-r",
                "__node:=controller_server",
                "-r",
                "__ns:=/robot1",
                "-r",
                "cmd_vel:=wheel_cmd",
                "-r",
                "map:=/shared_map",
                "-r",
                "follow_path:=follow_the_path",
                "-p",
                "autostart:=true",
                "-p",
                "map_topic:=map",
            ),
            domain,
        )
        follower = procs.start(
            "follower",
            viapath(
                "ros2",
                "node",
                "--ros-args",
                "--remap",
                "__node:=follower",
                "--remap",
                "__ns:=/robot2",
                "-r",
                "designated_path:=plan_in",
                "-r",
                "cmd_vel:=wheel_cmd",
                "-p",
                "autostart:=true",
            ),
            domain,
        )
        probe_script = str(Path(__file__).with_name("_graph_probe.py"))
        # up to 240 s for the nodes to appear: slow only on a loaded machine
        probe = procs.start("probe", [sys.executable, probe_script, str(out), "240", *EXPECTED], domain)
        code = procs.wait(probe, 300.0)
        assert code == 0, procs.output(probe)[1][-3000:]
        running = {name: proc.poll() is None for name, proc in (("nav2", nav2), ("follower", follower))}
        procs.stop(nav2)
        procs.stop(follower)
        yield json.loads(out.read_text()), running, procs.output(nav2)[1], procs.output(follower)[1]
    finally:
        procs.stop_all()


def _holders(graph, kind: str, name: str) -> list[str]:
    return sorted(node for node, ends in graph["by_node"].items() if name in ends[kind])


def test_no_two_nodes_share_a_fully_qualified_name(graph):
    found, running, _, _ = graph
    assert running == {"nav2": True, "follower": True}
    duplicates = sorted({n for n in found["nodes"] if found["nodes"].count(n) > 1})
    assert duplicates == [], found["nodes"]
    assert set(EXPECTED) <= set(found["nodes"]), found["nodes"]


def test_no_publisher_already_registered_warning(graph):
    _, _, nav2_err, follower_err = graph
    assert "already registered" not in nav2_err
    assert "already registered" not in follower_err
    assert "active: commanding" in nav2_err and "active: commanding" in follower_err  # the logs are these nodes'


def test_remapped_command_topics_are_published_by_the_renamed_nodes(graph):
    found, _, _, _ = graph
    assert _holders(found, "publishers", "/robot1/wheel_cmd") == [NAV2]
    assert _holders(found, "publishers", "/robot2/wheel_cmd") == [FOLLOWER]
    assert _holders(found, "publishers", "/robot1/cmd_vel") == _holders(found, "publishers", "/robot2/cmd_vel") == []


def test_the_follow_path_action_is_served_remapped_by_the_inputs_node(graph):
    found, _, _, _ = graph
    assert _holders(found, "action_servers", "/robot1/follow_the_path") == [NAV2 + "_inputs"]
    assert _holders(found, "action_servers", "/robot1/follow_path") == []


def test_the_map_is_taken_remapped_by_the_maps_node(graph):
    found, _, _, _ = graph
    assert _holders(found, "subscribers", "/shared_map") == [NAV2 + "_map"]
    assert _holders(found, "subscribers", "/robot1/map") == []


def test_the_path_is_taken_remapped_in_the_namespace_by_the_inputs_node(graph):
    found, _, _, _ = graph
    assert _holders(found, "subscribers", "/robot2/plan_in") == [FOLLOWER + "_inputs"]
    assert _holders(found, "subscribers", "/robot2/designated_path") == []
    assert _holders(found, "subscribers", "/robot2/scan_front") == [FOLLOWER]  # the control loop's, unchanged
