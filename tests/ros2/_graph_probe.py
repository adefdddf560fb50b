"""Record the ROS graph as the other processes of a test see it (for test_ros2_node_names).

``python _graph_probe.py OUT.json TIMEOUT_S NODE...``: waits until every NODE (a fully-qualified name)
is in the graph, or TIMEOUT_S, then 2 s more (for the endpoints of nodes just found), and writes
``nodes`` (one fully-qualified name per node in the graph, a name that two nodes hold listed twice; the
probe's own left out) and per node name its ``publishers``, ``subscribers`` and ``action_servers`` (names).
"""

from __future__ import annotations

import json
import sys
import time


def fully_qualified(name: str, namespace: str) -> str:
    return namespace.rstrip("/") + "/" + name


def main(out_path: str, timeout_s: float, wanted: list[str]) -> int:
    import rclpy
    from rclpy.action import get_action_server_names_and_types_by_node

    rclpy.init()
    node = rclpy.create_node("graph_probe")
    me = fully_qualified(node.get_name(), node.get_namespace())
    try:
        until = time.monotonic() + timeout_s
        while time.monotonic() < until:
            seen = {fully_qualified(n, ns) for n, ns in node.get_node_names_and_namespaces()}
            if set(wanted) <= seen:
                break
            rclpy.spin_once(node, timeout_sec=0.1)
        until = time.monotonic() + 2.0
        while time.monotonic() < until:
            rclpy.spin_once(node, timeout_sec=0.1)
        pairs = [(n, ns) for n, ns in node.get_node_names_and_namespaces() if fully_qualified(n, ns) != me]
        graph: dict = {"nodes": sorted(fully_qualified(n, ns) for n, ns in pairs), "by_node": {}}
        for n, ns in sorted(set(pairs)):
            graph["by_node"][fully_qualified(n, ns)] = {
                "publishers": sorted(t for t, _ in node.get_publisher_names_and_types_by_node(n, ns)),
                "subscribers": sorted(t for t, _ in node.get_subscriber_names_and_types_by_node(n, ns)),
                "action_servers": sorted(t for t, _ in get_action_server_names_and_types_by_node(node, n, ns)),
            }
        with open(out_path, "w") as out:
            json.dump(graph, out, indent=1)
    finally:
        node.destroy_node()
        rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], float(sys.argv[2]), sys.argv[3:]))
