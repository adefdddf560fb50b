"""Drive a running ``viapath ros2 nav2`` node (autostart, ``map_topic: map``) with hostile maps, transforms
and goals over DDS, in real time, and record what it answers (for test_ros2_nav2_inputs).

``python _nav2_input_driver.py OUT.json``. The driver is the robot: odometry of an honest base that
drives the received cmd_vel and two empty scans every 0.1 s. Phases:

1. a good map with a wall across the way 1.2 m ahead and a goal through it: the robot stops short;
2. maps with a NaN origin, a 1e300 origin and an empty frame_id, all free: each refused, the wall kept;
3. /tf_static with the front scanner 1e6 m out, /tf with the quaternion (0, 0, 1, 1);
4. a goal whose three poses all lie at the robot;
5. goals that are empty, have a NaN among 3 poses, or one among 20 000 poses;
6. a free map (the wall gone) and a 30 000-pose zig-zag goal along the way;
7. a goal that is canceled while it runs;
8. a goal running when the node is shut down (lifecycle ``shutdown``).

Before them, the DDS participants that subscribe to the map, a scan and odometry.

OUT.json holds per phase the robot's largest x, the goal results (status, error code) and the commands, and
the node's ``way`` status on /diagnostics (level, message) with the driver's time of each change.
"""

from __future__ import annotations

import array
import json
import math
import sys
import time

import numpy as np


def main(out_path: str) -> int:
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import TransformStamped, Twist
    from lifecycle_msgs.msg import Transition
    from lifecycle_msgs.srv import ChangeState
    from nav_msgs.msg import OccupancyGrid, Odometry
    from rclpy.action import ActionClient
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
    from sensor_msgs.msg import LaserScan

    from viapath.perception.scanner import paper_scanners
    from viapath.ros2 import convert, interfaces

    interfaces.load()
    from nav2_msgs.action import FollowPath
    from tf2_msgs.msg import TFMessage

    rclpy.init()
    node = rclpy.create_node("nav2_input_driver")
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    static_qos = QoSProfile(
        depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
    )
    odom_pub = node.create_publisher(Odometry, "odom", 10)
    scan_pubs = [node.create_publisher(LaserScan, f"scan_{n}", qos_profile_sensor_data) for n in ("front", "rear")]
    map_pub = node.create_publisher(OccupancyGrid, "map", latched)
    tf_pub = node.create_publisher(TFMessage, "/tf", 100)
    tf_static_pub = node.create_publisher(TFMessage, "/tf_static", static_qos)
    commands: list[tuple[float, float, float]] = []
    node.create_subscription(
        Twist, "cmd_vel", lambda m: commands.append((time.monotonic(), m.linear.x, m.angular.z)), 50
    )
    ways: list[tuple[float, int, str]] = []  # (driver time, level, message) of the way status as it changes

    def on_diagnostics(msg) -> None:
        for status in msg.status:
            if status.name.endswith(": way"):
                level = int.from_bytes(status.level, "little") if isinstance(status.level, bytes) else int(status.level)
                if not ways or ways[-1][1:] != (level, status.message):
                    ways.append((time.monotonic() - started, level, status.message))

    node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 50)
    client = ActionClient(node, FollowPath, "follow_path")
    change = node.create_client(ChangeState, "controller_server/change_state")
    started = time.monotonic()
    while not client.wait_for_server(timeout_sec=0.1):
        if time.monotonic() - started > 120:
            print("error: no follow_path server", file=sys.stderr)
            return 3
    scanners = paper_scanners()
    empty = [np.full(s.beam_count, np.inf) for s in scanners]
    state = {"x": 0.0, "y": 0.0, "h": 0.0, "v": 0.0, "w": 0.0, "next": time.monotonic()}
    phases: dict[str, dict] = {}

    def tick() -> None:
        """One scan period of the robot: drive the last command, publish odometry and scans."""
        if commands:
            state["v"], state["w"] = commands[-1][1], commands[-1][2]
        state["x"] += state["v"] * 0.1 * math.cos(state["h"])
        state["y"] += state["v"] * 0.1 * math.sin(state["h"])
        state["h"] += state["w"] * 0.1
        stamp = convert.time_msg(node.get_clock().now().nanoseconds * 1e-9)
        odom_pub.publish(
            convert.odometry("odom", "base_link", stamp, state["x"], state["y"], state["h"], state["v"], state["w"])
        )
        for pub, s, ranges in zip(scan_pubs, scanners, empty):
            pub.publish(
                convert.laser_scan(
                    f"laser_{s.name}",
                    stamp,
                    s.angle_min_rad,
                    s.angle_increment_rad,
                    ranges,
                    s.range_min_m,
                    s.range_max_m,
                )
            )

    def run(seconds: float, done=lambda: False) -> float:
        """Spin and tick for ``seconds`` (or until ``done()``); the robot's largest x meanwhile."""
        end = time.monotonic() + seconds
        largest = state["x"]
        while time.monotonic() < end and not done():
            if time.monotonic() >= state["next"]:
                tick()
                state["next"] += 0.1
                largest = max(largest, state["x"])
            rclpy.spin_once(node, timeout_sec=0.005)
        return largest

    def grid(origin_x: float, origin_y: float, frame: str = "odom", wall: bool = True) -> OccupancyGrid:
        msg = OccupancyGrid()
        msg.header.frame_id = frame
        msg.info.resolution = 0.05
        msg.info.width = msg.info.height = 80
        msg.info.origin.position.x, msg.info.origin.position.y = origin_x, origin_y
        msg.info.origin.orientation.w = 1.0
        cells = np.zeros((80, 80), dtype=np.int8)
        if wall:
            cells[:, 64] = 100  # x = -2 + 64.5 * 0.05 = 1.225 m
        msg.data = array.array("b", cells.tobytes())
        return msg

    handles: dict[int, object] = {}  # the goal handles, by id of their record

    def goal(points) -> dict:
        request = FollowPath.Goal()
        request.path = convert.path_message(np.asarray(points, float).reshape(-1, 2), "odom", convert.time_msg(0.0))
        record: dict = {"sent_s": time.monotonic() - started}
        sent = client.send_goal_async(request)

        def accepted(future):
            handle = future.result()
            handles[id(record)] = handle
            record["accepted"] = bool(handle.accepted)
            if handle.accepted:
                handle.get_result_async().add_done_callback(
                    lambda f: record.update(
                        status=int(f.result().status),
                        code=int(f.result().result.error_code),
                        message=str(f.result().result.error_msg),
                    )
                )

        sent.add_done_callback(accepted)
        return record

    run(2.0)  # the node configures its scanners

    def participants(topic: str) -> list[str]:
        """The DDS participants (the first 12 bytes of the endpoint's id) subscribing to ``topic``."""
        return sorted({bytes(info.endpoint_gid[:12]).hex() for info in node.get_subscriptions_info_by_topic(topic)})

    topics = ("/map", "/scan_front", "/odom")
    run(30.0, lambda: all(node.count_subscribers(topic) > 0 for topic in topics))  # discovered
    phases["participants"] = {topic: participants(topic) for topic in topics}
    map_pub.publish(grid(-2.0, -2.0))
    run(1.0)
    first = goal([[0.0, 0.0], [3.0, 0.0]])
    phases["good_map"] = {"largest_x": run(4.5)}
    for name, msg in (
        ("nan_origin", grid(float("nan"), -2.0, wall=False)),
        ("huge_origin", grid(1e300, -2.0, wall=False)),
        ("empty_frame", grid(-2.0, -2.0, frame="", wall=False)),
    ):
        map_pub.publish(msg)
        phases[name] = {"largest_x": run(1.5)}
    phases["good_map"]["goal"] = dict(first)

    def transform(parent, child, x, q=(0.0, 0.0, 0.0, 1.0)) -> TransformStamped:
        t = TransformStamped()
        t.header.frame_id, t.child_frame_id = parent, child
        t.header.stamp = convert.time_msg(node.get_clock().now().nanoseconds * 1e-9)
        t.transform.translation.x = x
        t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z, t.transform.rotation.w = q
        return t

    tf_static_pub.publish(TFMessage(transforms=[transform("base_link", "laser_front", 1e6)]))
    tf_pub.publish(TFMessage(transforms=[transform("map", "odom", 0.0, (0.0, 0.0, 1.0, 1.0))]))
    phases["bad_tf"] = {"largest_x": run(1.5)}
    here = goal([[state["x"], state["y"]]] * 3)
    run(5.0, lambda: "status" in here)
    phases["goal_at_robot"] = dict(here)
    spoiled = np.c_[np.arange(20_000) * 0.001 + state["x"], np.zeros(20_000)]
    spoiled[15_000, 1] = float("nan")
    bad = {
        "empty": goal(np.zeros((0, 2))),
        "nan_short": goal([[state["x"], 0.0], [state["x"] + 0.2, float("nan")], [state["x"] + 0.4, 0.0]]),
        "nan_long": goal(spoiled),
    }
    run(8.0, lambda: all("status" in record for record in bad.values()))
    phases["bad_goals"] = {name: dict(record) for name, record in bad.items()}
    map_pub.publish(grid(-2.0, -2.0, wall=False))  # the wall gone: the way opens
    run(1.0)
    start_x = state["x"]
    n = 30_000
    zigzag = np.c_[start_x + np.arange(n) * 0.01, np.where(np.arange(n) % 2, 0.05, -0.05)]
    big = goal(zigzag)
    phases["open_way"] = {"start_x": start_x, "largest_x": run(6.0), "goal": big}
    canceled = goal([[state["x"], 0.0], [state["x"] + 3.0, 0.0]])
    run(3.0, lambda: canceled.get("accepted") is not None)
    if id(canceled) in handles:
        handles[id(canceled)].cancel_goal_async()  # type: ignore[attr-defined]  # a ClientGoalHandle
    run(5.0, lambda: "status" in canceled)
    phases["cancel"] = dict(canceled)
    last = goal([[state["x"], 0.0], [state["x"] + 0.5, 0.0]])
    run(2.0, lambda: last.get("accepted") is not None)
    request = ChangeState.Request()
    request.transition.id = Transition.TRANSITION_ACTIVE_SHUTDOWN
    change.wait_for_service(timeout_sec=10.0)
    change.call_async(request)
    run(6.0, lambda: "status" in last)
    phases["shutdown_during_goal"] = dict(last)
    phases["ways"] = ways
    with open(out_path, "w") as handle:
        json.dump(phases, handle)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1]))
