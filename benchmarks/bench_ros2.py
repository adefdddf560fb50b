"""ROS 2 node latency: scan in -> cmd_vel out over DDS, with 10 and 50 simulated people; CPU per cycle.

Usage: python benchmarks/bench_ros2.py [--people 10 50] [--cycles 150] [--executor events|single-threaded]
                                      [--profile node.prof] [--nav2] [--json]

``--nav2`` starts ``viapath ros2 nav2`` (autostart) instead and gives it the path as a FollowPath goal
(odom frame, 100 m long) from this process, so its action server, feedback and TF subscriptions run
in every cycle.

Needs the ``ros2`` extra. Starts ``viapath ros2 node`` as a separate process (its own ROS domain,
DDS kept on this machine) and drives it from this process at the scan rate (10 Hz, real time):
each cycle publishes odometry and the two URG-04LX scans of a robot driving at 0.2 m/s through N
people walking in random directions within 4 m (ray-cast here, before the clock starts). Latency is
measured in this process, on one monotonic clock: from just before the second scan is published
(the one that completes the node's cycle) to the arrival of its ``cmd_vel``. The node's CPU per cycle
is its process CPU time (user + system, ``/proc``) over the measured cycles divided by their number;
``cycle_p50/p99`` is the node's own timing of perception + planning (DiagnosticArray). The first
20 cycles are warm-up and not counted. The node is ended by pid at the end.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

SCAN_PERIOD_S = 0.1
WARMUP_CYCLES = 20


def _cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def run(
    people_counts,
    cycles: int,
    seed: int = 0,
    profile: str | None = None,
    node_args: tuple[str, ...] = (),
    nav2: bool = False,
) -> list[dict]:
    domain = 150 + os.getpid() % 50
    os.environ.update(ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_DOMAIN_ID=str(domain))
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import LaserScan

    from viapath.perception.raycast import simulate_scan
    from viapath.perception.scanner import paper_scanners
    from viapath.ros2 import convert

    command = (
        ["ros2", "nav2", "--ros-args", "-p", "autostart:=true"]
        if nav2
        else ["ros2", "node", "--ros-args", "-p", "path_file:=paper-front"]
    )
    node_proc = subprocess.Popen(
        [
            sys.executable,
            *(["-m", "cProfile", "-o", profile] if profile else []),
            "-m",
            "viapath.cli",
            *command,
            "-p",
            "scan_timeout_s:=5.0",
            "-p",
            "odom_timeout_s:=5.0",
            *node_args,
        ],
        env=dict(os.environ),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    rclpy.init()
    node = rclpy.create_node("viapath_bench")
    results = []
    try:
        odom_pub = node.create_publisher(Odometry, "odom", 10)
        scan_pubs = [node.create_publisher(LaserScan, f"scan_{n}", qos_profile_sensor_data) for n in ("front", "rear")]
        got = {"cmd_t": None, "status": []}
        node.create_subscription(Twist, "cmd_vel", lambda m: got.__setitem__("cmd_t", time.monotonic()), 10)

        def on_status(msg):
            for s in msg.status:
                if s.name.endswith(": planner"):
                    values = {kv.key: kv.value for kv in s.values}
                    if values.get("source") == "cycle":
                        got["status"].append(values)

        node.create_subscription(DiagnosticArray, "viapath/status", on_status, 50)
        deadline = time.monotonic() + 120
        while node.count_publishers("cmd_vel") == 0 or node.count_subscribers("scan_rear") == 0:
            if time.monotonic() > deadline or node_proc.poll() is not None:
                raise RuntimeError(
                    "the node did not come up: "
                    + (node_proc.stderr.read().decode()[-2000:] if node_proc.poll() is not None else "timeout")
                )
            rclpy.spin_once(node, timeout_sec=0.05)
        if nav2:
            _send_goal(node, [[-1.0, 0.0], [100.0, 0.0]])
        end = time.monotonic() + 1.0
        while time.monotonic() < end:
            rclpy.spin_once(node, timeout_sec=0.05)

        scanners = paper_scanners()
        rng = np.random.default_rng(seed)
        for count in people_counts:
            start = rng.uniform(-4.0, 4.0, (count, 2))
            heading = rng.uniform(-np.pi, np.pi, count)
            velocity = 0.5 * np.stack([np.cos(heading), np.sin(heading)], axis=1)
            latencies, cycle_ms, missed = [], [], 0
            cpu0 = wall0 = None
            got["status"].clear()
            for k in range(WARMUP_CYCLES + cycles):
                t = k * SCAN_PERIOD_S
                x = 0.2 * t % 5.0  # the robot drives along the path (wraps: the scene stays busy)
                people = start + velocity * t
                people = np.where(np.abs(people) > 5.0, -np.sign(people) * 4.0, people)  # walk back in at the far side
                pose = np.array([x, 0.0, 0.0])
                scans = [simulate_scan(s, pose, people, np.full(count, 0.25), None, rng) for s in scanners]
                stamp = convert.time_msg(node.get_clock().now().nanoseconds * 1e-9)
                msgs = [
                    convert.laser_scan(
                        f"laser_{s.name}",
                        stamp,
                        s.angle_min_rad,
                        s.angle_increment_rad,
                        r,
                        s.range_min_m,
                        s.range_max_m,
                    )
                    for s, r in zip(scanners, scans)
                ]
                odom = convert.odometry("odom", "base_link", stamp, x, 0.0, 0.0, 0.2, 0.0)
                if k == WARMUP_CYCLES:
                    cpu0, wall0 = _cpu_seconds(node_proc.pid), time.monotonic()
                got["cmd_t"] = None
                odom_pub.publish(odom)
                scan_pubs[0].publish(msgs[0])
                sent = time.monotonic()
                scan_pubs[1].publish(msgs[1])
                period_end = sent + SCAN_PERIOD_S
                while got["cmd_t"] is None and time.monotonic() < period_end:
                    rclpy.spin_once(node, timeout_sec=0.001)
                if k >= WARMUP_CYCLES:
                    if got["cmd_t"] is None:
                        missed += 1
                    else:
                        latencies.append((got["cmd_t"] - sent) * 1e3)
                while time.monotonic() < period_end:
                    rclpy.spin_once(node, timeout_sec=max(period_end - time.monotonic(), 0.0))
            cpu = _cpu_seconds(node_proc.pid) - cpu0
            wall = time.monotonic() - wall0
            cycle_ms = [float(s["cycle_time_ms"]) for s in got["status"][-cycles:] if s.get("cycle_time_ms")]
            lat = np.array(latencies)
            results.append(
                {
                    "people": count,
                    "cycles": cycles,
                    "missed_cycles": missed,
                    "latency_p50_ms": float(np.percentile(lat, 50)) if len(lat) else None,
                    "latency_p99_ms": float(np.percentile(lat, 99)) if len(lat) else None,
                    "latency_max_ms": float(lat.max()) if len(lat) else None,
                    "node_cpu_per_cycle_ms": 1e3 * cpu / cycles,
                    "node_cpu_share": cpu / wall,
                    "cycle_p50_ms": float(np.percentile(cycle_ms, 50)) if cycle_ms else None,
                    "cycle_p99_ms": float(np.percentile(cycle_ms, 99)) if cycle_ms else None,
                    "tracks_p50": float(np.median([int(s.get("tracks", 0)) for s in got["status"][-cycles:]]))
                    if got["status"]
                    else None,
                }
            )
    finally:
        node.destroy_node()
        rclpy.shutdown()
        if node_proc.poll() is None:
            node_proc.send_signal(signal.SIGTERM)
            try:
                node_proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                node_proc.kill()
                node_proc.wait(timeout=10)
    return results


def _send_goal(node, waypoints) -> None:
    """A FollowPath goal in the odometry frame (no TF needed), accepted before the cycles start."""
    import rclpy
    from rclpy.action import ActionClient

    from viapath.ros2 import convert, interfaces

    interfaces.load()
    from nav2_msgs.action import FollowPath

    client = ActionClient(node, FollowPath, "follow_path")
    if not client.wait_for_server(timeout_sec=60):
        raise RuntimeError("no follow_path action server")
    goal = FollowPath.Goal()
    goal.path = convert.path_message(waypoints, "odom", convert.time_msg(0.0))
    future = client.send_goal_async(goal)
    end = time.monotonic() + 30
    while not future.done() and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    if not (future.done() and future.result().accepted):
        raise RuntimeError("the FollowPath goal was not accepted")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--people", type=int, nargs="+", default=[10, 50])
    parser.add_argument("--cycles", type=int, default=150)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--executor",
        choices=("events", "single-threaded"),
        default=None,
        help="the node's executor parameter (default: the node's default)",
    )
    parser.add_argument("--profile", metavar="FILE", help="run the node under cProfile, stats written to FILE")
    parser.add_argument(
        "--nav2", action="store_true", help="viapath ros2 nav2 with a FollowPath goal instead of viapath ros2 node"
    )
    args = parser.parse_args()
    started = time.time()
    node_args = ("-p", f"executor:={args.executor}") if args.executor else ()
    results = run(args.people, args.cycles, args.seed, args.profile, node_args, nav2=args.nav2)
    load = os.getloadavg()[0]
    if args.json:
        print(
            json.dumps(
                {
                    "benchmark": "ros2",
                    "node": "nav2" if args.nav2 else "node",
                    "load_avg_1min": load,
                    "wall_s": time.time() - started,
                    "results": results,
                }
            )
        )
        return
    print(
        f"viapath ros2 {'nav2 (FollowPath goal)' if args.nav2 else 'node'}, scan in -> cmd_vel out over DDS ({args.cycles} cycles at 10 Hz; load avg {load:.1f})"
    )
    print(
        f"{'people':>6} {'lat p50':>8} {'lat p99':>8} {'lat max':>8} {'cpu/cycle':>10} {'cycle p50':>10} {'cycle p99':>10} {'tracks':>6} {'missed':>6}"
    )
    for r in results:
        print(
            f"{r['people']:>6} {r['latency_p50_ms']:>7.2f}ms {r['latency_p99_ms']:>7.2f}ms {r['latency_max_ms']:>7.2f}ms "
            f"{r['node_cpu_per_cycle_ms']:>8.2f}ms {r['cycle_p50_ms']:>8.2f}ms {r['cycle_p99_ms']:>8.2f}ms "
            f"{r['tracks_p50']:>6.0f} {r['missed_cycles']:>6}"
        )


if __name__ == "__main__":
    main()
