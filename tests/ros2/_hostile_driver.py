"""Drive a running planner node with hostile input over DDS and record what it answers (for test_ros2_faults).

``python _hostile_driver.py OUT.json``: a node with one scanner ``laser`` on ``scan_front``
(``scan_geometry: from_message``, any frame) and ``use_sim_time`` must be running in the same ROS
domain. The driver is the robot: it publishes /clock, odometry (an honest base that drives the
received cmd_vel) and empty-world scans, one step every 0.1 s of simulated time, waiting for the
node's status of each step (lock-step). Phases:

1. the first scan has range_min 6 m > range_max 1 m (a layout no scanner has); then good scans;
2. the odometry's quaternion is (0, 0, 0, 0) for three steps;
3. no odometry for 20 steps (2 s), the scans going on;
4. an empty nav_msgs/Path;
5. a path again, then /clock and every input stop for 2 s of wall time.

OUT.json holds, per phase, the planner statuses and the commands received (with wall times).
"""

from __future__ import annotations

import json
import math
import sys
import time

import numpy as np

ODOMETRY_STALE_STEPS = 20  # steps of 0.1 s of simulated time without odometry


def main(out_path: str) -> int:
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry
    from nav_msgs.msg import Path as PathMsg
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import LaserScan

    from viapath.ros2 import convert

    rclpy.init()
    node = rclpy.create_node("hostile_driver")
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    clock_pub = node.create_publisher(Clock, "/clock", 10)
    odom_pub = node.create_publisher(Odometry, "odom", 10)
    scan_pub = node.create_publisher(
        LaserScan, "scan_front", QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    )
    path_pub = node.create_publisher(PathMsg, "designated_path", latched)
    got = {"statuses": [], "commands": []}
    node.create_subscription(
        Twist, "cmd_vel", lambda m: got["commands"].append((time.monotonic(), m.linear.x, m.angular.z)), 50
    )

    def on_status(msg):
        for s in msg.status:
            if s.name.endswith(": planner") or ": scanner " in s.name or s.name.endswith(": odometry"):
                values = {kv.key: kv.value for kv in s.values}
                values["_name"] = s.name.split(": ", 1)[1]
                values["_wall"] = time.monotonic()
                got["statuses"].append(values)

    node.create_subscription(DiagnosticArray, "viapath/status", on_status, 100)

    def spin(seconds: float, done=lambda: False, clock=None) -> None:
        """Spin for ``seconds`` or until ``done()``; with ``clock``, republish it every 50 ms (waiting, not stopped)."""
        end = beat = time.monotonic()
        end += seconds
        while time.monotonic() < end and not done():
            if clock is not None and time.monotonic() - beat >= 0.05:
                clock_pub.publish(clock)
                beat = time.monotonic()
            rclpy.spin_once(node, timeout_sec=0.01)

    started = time.monotonic()
    while node.count_subscribers("scan_front") == 0 or node.count_publishers("cmd_vel") == 0:
        if time.monotonic() - started > 120:
            print("error: no planner node", file=sys.stderr)
            return 3
        rclpy.spin_once(node, timeout_sec=0.05)
    spin(1.0)
    state = {"t": 1.0, "x": 0.0, "y": 0.0, "h": 0.0, "v": 0.0, "w": 0.0}
    beams, increment = 683, math.radians(0.352)
    angle_min = -0.5 * (beams - 1) * increment
    phases: dict[str, dict] = {}

    def path(points):
        path_pub.publish(
            convert.path_message(np.asarray(points, float).reshape(-1, 2), "odom", convert.time_msg(state["t"]))
        )

    def step(quaternion=None, range_min=0.02, range_max=5.6, odometry=True):
        """One simulated step: clock, odometry (unless not ``odometry``), scan; wait for the node's cycle; drive the
        last command."""
        stamp = convert.time_msg(state["t"])
        clock = Clock()
        clock.clock = stamp
        clock_pub.publish(clock)
        odom = convert.odometry("odom", "base_link", stamp, state["x"], state["y"], state["h"], state["v"], state["w"])
        if quaternion is not None:
            q = odom.pose.pose.orientation
            q.x, q.y, q.z, q.w = quaternion
        if odometry:
            odom_pub.publish(odom)
        scan_pub.publish(
            convert.laser_scan("right_laser", stamp, angle_min, increment, np.full(beams, np.inf), range_min, range_max)
        )
        key = f"{state['t']:.6f}"
        if range_min < range_max:
            spin(
                10.0,
                lambda: any(s.get("stamp_s") == key and s.get("source") == "cycle" for s in got["statuses"]),
                clock,
            )
        else:  # refused: no cycle comes; wait for the scanner's status to say so
            spin(5.0, lambda: any("layout" in s.get("refused", "") for s in got["statuses"]), clock)
        spin(0.02)
        v, w = got["commands"][-1][1:] if got["commands"] else (0.0, 0.0)
        state["v"], state["w"] = v, w
        state["x"] += v * 0.1 * math.cos(state["h"] + 0.05 * w)
        state["y"] += v * 0.1 * math.sin(state["h"] + 0.05 * w)
        state["h"] += w * 0.1
        state["t"] += 0.1

    def phase(name, run):
        first_status, first_command = len(got["statuses"]), len(got["commands"])
        run()
        phases[name] = {"statuses": got["statuses"][first_status:], "commands": got["commands"][first_command:]}

    path([[0.0, 0.0], [20.0, 0.0]])
    spin(0.5)
    phase("malformed_first_scan", lambda: step(range_min=6.0, range_max=1.0))
    phase("driving", lambda: [step() for _ in range(12)])
    phase("zero_quaternion", lambda: [step(quaternion=(0.0, 0.0, 0.0, 0.0)) for _ in range(3)])
    phase("after_quaternion", lambda: [step() for _ in range(12)])
    phase("odometry_stale", lambda: [step(odometry=False) for _ in range(ODOMETRY_STALE_STEPS)])

    def empty_path():
        path([])
        spin(0.3)
        for _ in range(8):
            step()

    phase("empty_path", empty_path)

    def clock_stops():
        path([[state["x"], 0.0], [20.0, 0.0]])
        spin(0.3)
        for _ in range(12):
            step()
        phases["before_stop"] = {"wall": time.monotonic(), "speed": state["v"]}
        spin(2.0)  # nothing published: no clock, no scans, no odometry

    phase("clock_stops", clock_stops)
    phases["clock_stops"]["stopped_at_wall"] = phases.pop("before_stop")
    with open(out_path, "w") as handle:
        json.dump(phases, handle)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1]))
