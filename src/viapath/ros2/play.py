"""``viapath ros2 play BAG``: publish a recording's laser scans with their timing, so the node runs on real data.

Source: :mod:`viapath.io.rosbag` (``rosbags`` reads ROS 1 / ROS 2 bags and MCAP without ROS); the
leg_tracker recordings in ``../shared/data`` (a standing scanner, people walking by).

What we chose:
* Time: ``/clock`` starts at the first scan's header stamp and follows the stamps, R times faster
  than the recording with ``--rate R``; every scan keeps its own header stamp, so the node (with
  ``use_sim_time``) tracks on the recorded timing. Stamps that jump back are published as recorded
  (the node handles them).
* The sensor stands still in these recordings: with ``--odom`` (default) a standing robot's odometry
  at the origin is published with each scan, so the node has a pose (frame ``odom``).
* Scans are published as recorded (clockwise ones too; invalid readings unchanged), with the
  sensor-data QoS but reliable, so a local subscriber misses none.
* ``--lockstep`` waits after each scan (up to ``max_wait_s``) for the node's cycle on it (its
  DiagnosticArray), then goes on with the recording's timing: on a slow machine the node then
  still sees every scan. ``--status-log`` writes the node's planner statuses (JSON lines).
* No node cycle on the published scans (the node refused them: wrong topic, frame or layout; or no
  node reported) is a failure: exit code 4 and a message with what the node said about each
  scanner (with ``--lockstep`` after five scans).
"""

from __future__ import annotations

import contextlib
import sys
import time


def run_play(
    bag,
    topic,
    out_topic: str,
    frame_id,
    rate: float,
    odom: bool,
    wait_s: float,
    ros_args=None,
    lockstep: bool = False,
    max_wait_s: float = 10.0,
    status_file=None,
    status_topic: str = "viapath/status",
) -> int:
    import json

    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from nav_msgs.msg import Odometry
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import LaserScan

    from viapath.io.rosbag import read_laser_scans
    from viapath.ros2 import convert
    from viapath.ros2.process import finish_ros_process, start_ros_process

    messages = list(read_laser_scans(bag, topic))
    if not messages:
        raise ValueError(f"{bag}: the topic holds no scans")
    node, stop, previous = start_ros_process("viapath_play", ros_args)
    try:
        qos = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
        scan_pub = node.create_publisher(LaserScan, out_topic, qos)
        clock_pub = node.create_publisher(Clock, "/clock", 10)
        odom_pub = node.create_publisher(Odometry, "odom", 10) if odom else None
        statuses: list[dict] = []
        cycles: set[float] = set()
        scanner_problems: dict[str, str] = {}  # what the node says about each scanner (refused scans)

        def on_status(msg):
            for st in msg.status:
                if ": scanner " in st.name:
                    values = {kv.key: kv.value for kv in st.values}
                    if values.get("refused", "none") != "none":
                        scanner_problems[st.name.split(": scanner ", 1)[1]] = (
                            f"topic {values.get('topic', '?')}: refused {values['refused']} ({values.get('last_problem', '')})"
                        )
                if st.name.endswith(": planner"):
                    values = {kv.key: kv.value for kv in st.values}
                    statuses.append(values)
                    if values.get("source") == "cycle":
                        with contextlib.suppress(ValueError):
                            cycles.add(round(float(values.get("stamp_s", "nan")), 6))

        node.create_subscription(DiagnosticArray, status_topic, on_status, 100)
        started = time.monotonic()
        while (
            node.count_subscribers(out_topic) == 0 or (lockstep and node.count_publishers(status_topic) == 0)
        ) and not stop["flag"]:
            if time.monotonic() - started > wait_s:
                print(f"error: nobody subscribed to {out_topic} within {wait_s:g} s", file=sys.stderr)
                return 3
            rclpy.spin_once(node, timeout_sec=0.05)
        end = time.monotonic() + 1.0
        while time.monotonic() < end:  # let both sides finish matching
            rclpy.spin_once(node, timeout_sec=0.05)
        first = messages[0].stamp_s
        wall0 = time.monotonic()
        clock = Clock()
        sent = 0
        for m in messages:
            if stop["flag"]:
                break
            due = wall0 + max(m.stamp_s - first, 0.0) / rate
            while time.monotonic() < due and not stop["flag"]:
                rclpy.spin_once(node, timeout_sec=min(0.01, max(due - time.monotonic(), 0.0)))
            stamp = convert.time_msg(m.stamp_s)
            clock.clock = stamp
            clock_pub.publish(clock)
            if odom_pub is not None:
                odom_pub.publish(convert.odometry("odom", "base_link", stamp, 0.0, 0.0, 0.0, 0.0, 0.0))
            scan_pub.publish(
                convert.laser_scan(
                    frame_id if frame_id is not None else m.frame_id,
                    stamp,
                    m.angle_min_rad,
                    m.angle_increment_rad,
                    m.ranges_m,
                    m.range_min_m,
                    m.range_max_m,
                    m.scan_time_s or 0.1,
                )
            )
            sent += 1
            if lockstep:  # wait for the node's cycle on this scan (a slow machine then changes nothing)
                key = round(m.stamp_s, 6)
                end = time.monotonic() + max_wait_s
                beat = time.monotonic()
                while key not in cycles and time.monotonic() < end and not stop["flag"]:
                    if time.monotonic() - beat >= 0.05:  # waiting, not stopped: keep /clock alive
                        clock_pub.publish(clock)
                        beat = time.monotonic()
                    rclpy.spin_once(node, timeout_sec=0.01)
                wall0 += max(time.monotonic() - due, 0.0)  # the recording's timing resumes from here
                if sent >= 5 and not cycles:
                    break  # the node takes none of them: say so now, not after max_wait_s per scan
        end = time.monotonic() + 1.0
        while time.monotonic() < end:  # let the last messages go out
            rclpy.spin_once(node, timeout_sec=0.05)
        if status_file:
            with open(status_file, "w") as handle:
                for values in statuses:
                    handle.write(json.dumps(values) + "\n")
        print(
            f"viapath ros2 play: {sent} scans from {bag} on {out_topic}, {len(cycles)} node cycles seen",
            file=sys.stderr,
        )
        if sent and not cycles:
            why = "; ".join(f"scanner {name}: {problem}" for name, problem in sorted(scanner_problems.items()))
            print(
                f"error: the node ran no cycle on the {sent} scans published on {out_topic}: "
                + (
                    f"it refused them ({why})"
                    if why
                    else f"no status on {status_topic} (is a viapath node listening on {out_topic}, with use_sim_time?)"
                ),
                file=sys.stderr,
            )
            return 4
        return 0
    finally:
        finish_ros_process(node, previous)
