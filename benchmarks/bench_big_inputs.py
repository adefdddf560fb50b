"""The node's control loop against big inputs: gaps between ``cmd_vel`` messages while the robot drives and
a 100 000-pose FollowPath goal, a 10 000 x 10 000 map and a 30 000-pose zig-zag goal arrive.

Usage: python benchmarks/bench_big_inputs.py [--poses 100000] [--map-cells 10000] [--zigzag 30000]
                                            [--seconds 30] [--json]
       python benchmarks/bench_big_inputs.py --table RUN.json [RUN.json ...]

Needs the ``ros2`` extra. Starts ``viapath ros2 nav2`` (autostart, ``map_topic: map``) as a separate
process (its own ROS domain, DDS kept on this machine), and drives it from this process at the scan
rate in real time: odometry of an honest base that drives the received ``cmd_vel`` and two empty
URG-04LX scans every 0.1 s. A first goal (a straight path 100 m long, sent again until the node, once
active, accepts it) sets the robot going. The big
inputs are built by a second process (so that building them does not hold up the scans of this
one; the robot drives meanwhile); once they are built the measurement starts, and the sender sends
the 100 000-pose goal along the same line at 4 s, the free map at 9 s (``odom`` frame, 0.05 m
cells), the zig-zag goal (±0.1 m, 1 cm apart) at 14 s. cmd_vel arrival times are taken in
this process on one monotonic clock; the gaps are counted from 2 s (warm-up) to the end, and each is also
put to the input last sent before it ended (``driving`` before the first), which gives the longest gap per
input; the same for the gaps between the scans this process sent (the node cycles on them: a scan sent
late, on a busy machine, delays its command as much). The rate is the number of commands over the
measured time, with the fewest and most in any 1 s window of it, and who sent them (``cycle``,
``watchdog``: the planner status the node sends with each command). Both processes are ended by pid.

``--table`` prints the Markdown table of docs/explanation/robustness.md from the ``--json`` output of
runs saved to files, one row per run.
"""

from __future__ import annotations

import argparse
import array
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

SCAN_PERIOD_S = 0.1
WARMUP_S = 2.0
EVENTS_S = {"path": 4.0, "map": 9.0, "zigzag": 14.0}


def _wait_for(node, predicate, timeout_s: float) -> bool:
    import rclpy

    end = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > end:
            return False
        rclpy.spin_once(node, timeout_sec=0.05)
    return True


def _goal_client(node):
    from rclpy.action import ActionClient

    from viapath.ros2 import interfaces

    interfaces.load()
    from nav2_msgs.action import FollowPath

    client = ActionClient(node, FollowPath, "follow_path")
    if not client.wait_for_server(timeout_sec=120):
        raise RuntimeError("no follow_path action server")
    return client, FollowPath


def sender(poses: int, map_cells: int, zigzag: int) -> int:
    """The second process: builds the big inputs first, says "ready" on stdout, reads the start time
    (a time.time()) from stdin, then sends each input at its time after it."""
    import rclpy
    from nav_msgs.msg import OccupancyGrid
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    from viapath.ros2 import convert

    rclpy.init()
    node = rclpy.create_node("big_input_sender")
    client, FollowPath = _goal_client(node)
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    map_pub = node.create_publisher(OccupancyGrid, "map", latched)
    built = {}
    line = np.column_stack([np.linspace(0.0, 100.0, poses), np.zeros(poses)])
    goal = FollowPath.Goal()
    goal.path = convert.path_message(line, "odom", convert.time_msg(0.0))
    built["path"] = goal
    x = np.arange(zigzag) * 0.01
    goal = FollowPath.Goal()
    goal.path = convert.path_message(
        np.column_stack([x, np.where(np.arange(zigzag) % 2, 0.1, -0.1)]), "odom", convert.time_msg(0.0)
    )
    built["zigzag"] = goal
    grid = OccupancyGrid()
    grid.header.frame_id = "odom"
    grid.info.resolution = 0.05
    grid.info.width = grid.info.height = map_cells
    grid.info.origin.position.x = grid.info.origin.position.y = -0.5 * map_cells * 0.05
    grid.info.origin.orientation.w = 1.0
    grid.data = array.array("b", bytes(map_cells * map_cells))
    built["map"] = grid
    print("ready", flush=True)
    start_wall = float(sys.stdin.readline())
    for name in sorted(EVENTS_S, key=EVENTS_S.get):
        while time.time() < start_wall + EVENTS_S[name]:
            rclpy.spin_once(node, timeout_sec=0.02)
        if name == "map":
            map_pub.publish(built[name])
        else:
            client.send_goal_async(built[name])
        print(f"sent {name} at {time.time() - start_wall:.2f} s", file=sys.stderr, flush=True)
    end = time.monotonic() + 8.0
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    node.destroy_node()
    rclpy.shutdown()
    return 0


def _stop(proc) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=10)


def run(poses: int, map_cells: int, zigzag: int, seconds: float, node_log: str | None = None) -> dict:
    domain = 150 + os.getpid() % 50
    os.environ.update(ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_DOMAIN_ID=str(domain))
    import tempfile

    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import LaserScan

    from viapath.perception.scanner import paper_scanners
    from viapath.ros2 import convert

    # the node's log to a file: a pipe nobody reads until the end would block the node once full
    log = open(node_log, "w+b") if node_log else tempfile.TemporaryFile()  # noqa: SIM115  # closed in finally
    node_proc = subprocess.Popen(
        [sys.executable, "-m", "viapath.cli", "ros2", "nav2", "--ros-args", "-p", "autostart:=true"]
        + ["-p", "map_topic:=map", "-p", "scan_timeout_s:=5.0", "-p", "odom_timeout_s:=5.0"],
        env=dict(os.environ),
        stdout=subprocess.DEVNULL,
        stderr=log,
    )
    sender_proc = None
    rclpy.init()
    node = rclpy.create_node("big_input_driver")
    try:
        odom_pub = node.create_publisher(Odometry, "odom", 10)
        scan_pubs = [node.create_publisher(LaserScan, f"scan_{n}", qos_profile_sensor_data) for n in ("front", "rear")]
        commands: list[tuple[float, float, float]] = []
        node.create_subscription(
            Twist, "cmd_vel", lambda m: commands.append((time.monotonic(), m.linear.x, m.angular.z)), 50
        )
        sources: list[tuple[float, str]] = []  # who sent each command: the planner status beside it

        def on_status(msg) -> None:
            for status in msg.status:
                if status.name.endswith(": planner"):
                    values = {kv.key: kv.value for kv in status.values}
                    sources.append((time.monotonic(), values.get("source", "")))

        node.create_subscription(DiagnosticArray, "viapath/status", on_status, 50)
        if not _wait_for(
            node, lambda: node.count_publishers("cmd_vel") > 0 and node.count_subscribers("scan_rear") > 0, 120
        ):
            log.seek(0)
            raise RuntimeError("the node did not come up: " + log.read().decode()[-2000:])
        client, FollowPath = _goal_client(node)
        goal = FollowPath.Goal()
        goal.path = convert.path_message([[-1.0, 0.0], [100.0, 0.0]], "odom", convert.time_msg(0.0))
        accepted_by, first_goal_sends = time.monotonic() + 30.0, 0
        while True:  # the action server is there once configured; goals are refused until the node is active
            first_goal_sends += 1
            future = client.send_goal_async(goal)
            if _wait_for(node, future.done, 30) and future.result().accepted:
                break
            if time.monotonic() > accepted_by:
                raise RuntimeError("the node did not accept the first goal")
            _wait_for(node, lambda: False, 0.2)
        scanners = paper_scanners()
        empty = [np.full(s.beam_count, np.inf) for s in scanners]
        sender_proc = subprocess.Popen(
            [
                sys.executable,
                __file__,
                "--sender",
                "--poses",
                str(poses),
                "--map-cells",
                str(map_cells),
                "--zigzag",
                str(zigzag),
            ],
            env=dict(os.environ),
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        scans_sent: list[float] = []  # when this process published each cycle's scans (monotonic)
        state = {"x": 0.0, "y": 0.0, "h": 0.0, "k": 0, "t0": time.monotonic()}

        def drive_until(end_s: float) -> None:
            """The robot at 10 Hz (odometry of the commands received, empty scans) until ``end_s`` (monotonic)."""
            while time.monotonic() < end_s:
                due = state["t0"] + state["k"] * SCAN_PERIOD_S
                while time.monotonic() < due:
                    rclpy.spin_once(node, timeout_sec=max(0.0, min(0.005, due - time.monotonic())))
                v, w = (commands[-1][1], commands[-1][2]) if commands else (0.0, 0.0)
                state["x"] += v * SCAN_PERIOD_S * np.cos(state["h"])
                state["y"] += v * SCAN_PERIOD_S * np.sin(state["h"])
                state["h"] += w * SCAN_PERIOD_S
                stamp = convert.time_msg(node.get_clock().now().nanoseconds * 1e-9)
                odom_pub.publish(convert.odometry("odom", "base_link", stamp, state["x"], state["y"], state["h"], v, w))
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
                state["k"] += 1
                scans_sent.append(time.monotonic())

        import selectors

        ready = selectors.DefaultSelector()
        ready.register(sender_proc.stdout, selectors.EVENT_READ)
        while not ready.select(timeout=0):  # the sender builds its messages: the robot drives meanwhile
            drive_until(time.monotonic() + 0.5)
            if sender_proc.poll() is not None:
                raise RuntimeError("the sender ended: " + sender_proc.stderr.read()[-2000:])
        sender_proc.stdout.readline()
        start_wall = time.time() + 0.5
        sender_proc.stdin.write(f"{start_wall}\n")
        sender_proc.stdin.flush()
        started = time.monotonic() + 0.5
        commands.clear()
        scans_sent.clear()
        sources.clear()
        drive_until(started + seconds)
        x = state["x"]
        _, sender_err = sender_proc.communicate(timeout=60)
        times = np.array([t - started for t, _, _ in commands if t - started >= WARMUP_S])
        speeds = np.array([s for t, s, _ in commands if t - started >= WARMUP_S])
        gaps = np.diff(times)
        worst = int(np.argmax(gaps)) if len(gaps) else 0
        sent_at = {
            line.split()[1]: float(line.split()[3]) for line in sender_err.splitlines() if line.startswith("sent")
        }

        def longest_by_input(moments) -> dict[str, float]:
            by_input: dict[str, float] = {"driving": 0.0, **dict.fromkeys(EVENTS_S, 0.0)}
            for end, gap in zip(moments[1:], np.diff(moments), strict=True):
                earlier = [name for name, at in sent_at.items() if at <= end]
                name = max(earlier, key=lambda n: sent_at[n]) if earlier else "driving"
                by_input[name] = round(max(by_input[name], float(gap)), 3)
            return by_input

        scan_times = np.array([t - started for t in scans_sent if t - started >= WARMUP_S])
        # commands in each 1 s window (one starting at each command) that ends by the end of the measurement
        ends = np.searchsorted(times, times + 1.0 - 1e-9)
        per_second = (ends - np.arange(len(times)))[times + 1.0 <= seconds]
        by_source: dict[str, int] = {}
        for t, source in sources:
            if t - started >= WARMUP_S:
                by_source[source] = by_source.get(source, 0) + 1
        return {
            "benchmark": "big_inputs",
            "poses": poses,
            "map_cells": f"{map_cells} x {map_cells}",
            "zigzag_poses": zigzag,
            "seconds_measured": seconds - WARMUP_S,
            "cmd_vel_messages": int(len(times)),
            "rate_hz": float(len(times) / (seconds - WARMUP_S)),
            "cmd_vel_in_1_s": [int(per_second.min()), int(per_second.max())] if len(per_second) else None,
            "cmd_vel_by_source": by_source,  # from the planner status sent with each command
            "longest_gap_s": float(gaps.max()) if len(gaps) else None,
            "longest_gap_at_s": float(times[worst]) if len(gaps) else None,
            "longest_gap_by_input_s": longest_by_input(times),
            # the robot's side: a late scan (this process or the machine busy) delays the node's cycle as much
            "longest_scan_gap_by_input_s": longest_by_input(scan_times),
            "gaps_over_0_2_s": int((gaps > 0.2).sum()),
            "gaps_over_0_2_s_at": [
                [round(float(times[i]), 2), round(float(gaps[i]), 3)] for i in np.flatnonzero(gaps > 0.2)
            ],
            "mean_speed_mps": float(speeds.mean()) if len(speeds) else None,
            "first_goal_sends": first_goal_sends,
            "distance_driven_m": float(x),
            "sent": [line for line in sender_err.splitlines() if line.startswith("sent")],
            "load_avg_1min": os.getloadavg()[0],
        }
    finally:
        node.destroy_node()
        rclpy.shutdown()
        for proc in (sender_proc, node_proc):
            if proc is not None:
                _stop(proc)
        log.close()


def table(results: list[dict]) -> str:
    """The Markdown table of the robustness page, one row per run's ``--json`` result."""
    lines = [
        "| run | load average | longest `cmd_vel` gap: driving | after the 100 000-pose goal | after the map "
        "| after the zig-zag goal | rate | commands in any 1 s | from scan cycles | longest gap between scans sent |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for k, r in enumerate(results, 1):
        gaps = r["longest_gap_by_input_s"]
        fewest, most = r["cmd_vel_in_1_s"]
        cycles = r["cmd_vel_by_source"].get("cycle", 0)
        lines.append(
            f"| {k} | {r['load_avg_1min']:.1f} | "
            + " | ".join(f"{gaps[name]:.3f} s" for name in ("driving", "path", "map", "zigzag"))
            + f" | {r['rate_hz']:.2f} Hz | {fewest}–{most} | {cycles} of {sum(r['cmd_vel_by_source'].values())} | "
            + f"{max(r['longest_scan_gap_by_input_s'].values()):.3f} s |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=100_000)
    parser.add_argument("--map-cells", type=int, default=10_000)
    parser.add_argument("--zigzag", type=int, default=30_000)
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--node-log", help="write the node's log (stderr) to this file")
    parser.add_argument("--table", nargs="+", metavar="RUN.json", help="print the docs' table of saved --json runs")
    parser.add_argument("--sender", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.table:
        print(table([json.loads(Path(path).read_text()) for path in args.table]))
        return
    if args.sender:
        raise SystemExit(sender(args.poses, args.map_cells, args.zigzag))
    result = run(args.poses, args.map_cells, args.zigzag, args.seconds, args.node_log)
    if args.json:
        print(json.dumps(result))
        return
    print(
        f"viapath ros2 nav2 driving, with a {result['poses']}-pose goal, a {result['map_cells']} map and a "
        f"{result['zigzag_poses']}-pose zig-zag goal sent (load avg {result['load_avg_1min']:.1f})"
    )
    print(
        f"cmd_vel: {result['cmd_vel_messages']} messages in {result['seconds_measured']:.0f} s = {result['rate_hz']:.2f} Hz; "
        f"longest gap {result['longest_gap_s']:.3f} s (at {result['longest_gap_at_s']:.1f} s); "
        f"{result['gaps_over_0_2_s']} gaps over 0.2 s; mean speed {result['mean_speed_mps']:.2f} m/s"
    )
    print(
        "  commands in any 1 s: {}-{}; sent by: {}".format(
            *(result["cmd_vel_in_1_s"] or ("-", "-")),
            ", ".join(f"{name} {n}" for name, n in sorted(result["cmd_vel_by_source"].items())),
        )
    )
    print(
        "  longest gap between the scans sent: "
        + ", ".join(f"{name} {gap:.3f} s" for name, gap in result["longest_scan_gap_by_input_s"].items())
    )
    print(
        "  longest gap after each input: "
        + ", ".join(f"{name} {gap:.3f} s" for name, gap in result["longest_gap_by_input_s"].items())
    )
    for line in result["sent"]:
        print("  " + line)
    for at, gap in result["gaps_over_0_2_s_at"]:
        print(f"  gap {gap:.3f} s from {at:.2f} s")


if __name__ == "__main__":
    main()
