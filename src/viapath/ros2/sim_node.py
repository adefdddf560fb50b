"""``viapath ros2 sim SCENARIO``: the simulator as a ROS 2 node, so the planner node can be tried without a robot.

Source: docs/design.md §8 (topics) and the simulator of :mod:`viapath.sim` (kinematics, obstacle motion,
metrics), with the two URG-04LX scans of :mod:`viapath.perception` (ray casting, range noise,
invalid readings as +inf). The episode's metrics are :func:`viapath.sim.metrics.compute_metrics` of
the same :class:`~viapath.sim.loop.Trace` that ``viapath run`` builds, so ``--json`` prints the same
object as ``viapath run SCENARIO --perception laser --json``.

What we chose:
* Time is the simulator's: step k is at ``k · dt_s`` and published on ``/clock`` (the node runs with
  ``use_sim_time``). Each step publishes the clock, then odometry (true pose and motion), then both
  scans, all stamped with the step's time; it then waits until ``dt_s / rate`` of wall time has passed
  and drives the robot one step with the latest ``cmd_vel`` through the same drive limits as
  ``viapath run``.
* ``--lockstep`` also waits (up to ``--max-wait-s`` of wall time) for the node's status of this step
  before driving, so a slow machine changes the timing of nothing: the command of step k is applied
  in step k, as in ``viapath run``. Without it a late command is applied a step later, as on a robot.
* The planner's side of the trace (plan speed, status, side, via points, cycle time, tracks) comes
  from the node's DiagnosticArray (its planner status carries them as key/values); ``plan_time_*``
  are the node's planner call and ``perception_time_*`` its detection and tracking, as ``viapath run``
  times them (null only when the node reported no such cycle), and the tracking errors compare the
  node's reported tracks with the true people at the same stamps.
* Fault injection for tests (``--fault KIND@T[-END]``, from T to END s or for good): ``silence:NAME``
  (scanner NAME publishes nothing), ``nan:NAME`` (all-NaN ranges), ``short:NAME`` (scans 10 beams
  short), ``odom`` (no odometry), ``clock-back:D`` (at T the clock and all stamps jump back by D
  seconds, then go on).
"""

from __future__ import annotations

import json
import math
import sys
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class Fault:
    kind: str  # silence | nan | short | odom | clock-back
    at_s: float
    scanner: str = ""
    amount_s: float = 0.0
    until_s: float = math.inf

    def active(self, t: float) -> bool:
        return self.at_s <= t < self.until_s

    @classmethod
    def parse(cls, text: str) -> Fault:
        """``silence:front@2``, ``nan:rear@1.5-3``, ``short:front@2``, ``odom@3-4``, ``clock-back:2@3``."""
        try:
            what, at = text.rsplit("@", 1)
            start, _, end = at.partition("-")
            at_s = float(start)
            until_s = float(end) if end else math.inf
            kind, _, arg = what.partition(":")
        except ValueError:
            raise ValueError(f"--fault {text!r}: expected KIND[:ARG]@TIME[-END], e.g. silence:front@2-4") from None
        if not math.isfinite(at_s) or at_s < 0 or not until_s > at_s:
            raise ValueError(f"--fault {text!r}: times must be finite, >= 0, and END after TIME")
        if kind in ("silence", "nan", "short"):
            if not arg:
                raise ValueError(f"--fault {text!r}: name the scanner, e.g. {kind}:front@{at}")
            return cls(kind, at_s, scanner=arg, until_s=until_s)
        if kind == "odom":
            return cls(kind, at_s, until_s=until_s)
        if kind == "clock-back":
            try:
                amount = float(arg)
            except ValueError:
                raise ValueError(f"--fault {text!r}: expected clock-back:SECONDS@TIME") from None
            if not (math.isfinite(amount) and amount > 0):
                raise ValueError(f"--fault {text!r}: the jump must be > 0 s")
            return cls(kind, at_s, amount_s=amount)
        raise ValueError(f"--fault {text!r}: unknown kind {kind!r}; one of silence, nan, short, odom, clock-back")


def _resolved(node, topic: str) -> str:
    """The topic name after remapping (``count_publishers`` does not remap)."""
    try:
        return node.resolve_topic_name(topic)
    except Exception:
        return topic


def _tf_publishers(node, scanners, map_offset):
    """Publish TF as a robot driver (and a localisation) would: ``/tf_static`` map -> odom (the
    offset) and base_link -> each scanner, once; returns a function publishing odom -> base_link."""
    try:
        from viapath.ros2 import interfaces

        interfaces.load()
        from geometry_msgs.msg import TransformStamped
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from tf2_msgs.msg import TFMessage
    except Exception as error:  # no compiler here: simulate without TF (the node falls back to its parameters)
        print(f"warning: no TF published ({error})", file=sys.stderr)
        return None
    from viapath.ros2 import convert

    def transform(parent, child, stamp, x, y, yaw):
        t = TransformStamped()
        t.header.frame_id, t.header.stamp, t.child_frame_id = parent, stamp, child
        t.transform.translation.x, t.transform.translation.y = float(x), float(y)
        q = convert.quaternion_from_yaw(yaw)
        t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z, t.transform.rotation.w = q
        return t

    static = node.create_publisher(
        TFMessage,
        "/tf_static",
        QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL),
    )
    dynamic = node.create_publisher(TFMessage, "/tf", 100)
    zero = convert.time_msg(0.0)
    message = TFMessage()
    message.transforms = [transform("map", "odom", zero, *map_offset)] + [
        transform("base_link", f"laser_{s.name}", zero, s.mount_x_m, s.mount_y_m, s.mount_yaw_rad) for s in scanners
    ]
    static.publish(message)

    def publish(stamp, x, y, yaw):
        out = TFMessage()
        out.transforms = [transform("odom", "base_link", stamp, x, y, yaw)]
        dynamic.publish(out)

    return publish


@dataclass
class StepRecord:
    command: tuple[float, float] = (0.0, 0.0)
    plan_speed: float = 0.0
    status: str = "none"
    side: int = 0
    via: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    cycle_ms: float = float("nan")
    perception_ms: float = float("nan")
    late: bool = False


@dataclass
class _World:
    """The scenario as the simulator node plays it: times, people, static shapes, path, limits, scanners."""

    spec: Any
    dt: float
    n_steps: int
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    radii: np.ndarray
    static_world: Any
    path: Any
    limits: Any
    goal_tolerance: float
    laser: Any

    @classmethod
    def of(cls, scenario_source: str, seed: int | None, duration_s: float | None, faults: list[Fault]) -> _World:
        from viapath.perception.laser import LaserPerception
        from viapath.scenarios import load_scenario
        from viapath.scenarios.build import scenario_limits, scenario_path, scenario_subgoal_policy
        from viapath.sim.obstacles import scenario_obstacle_states
        from viapath.sim.static_world import StaticWorld

        spec = load_scenario(scenario_source)
        dt = spec.dt_s
        n_steps = int(round((spec.duration_s if duration_s is None else min(duration_s, spec.duration_s)) / dt))
        times = np.arange(n_steps + 1) * dt
        positions, velocities, radii = scenario_obstacle_states(spec, times)
        static_world = StaticWorld.of_scenario(spec)
        path = scenario_path(spec)
        limits = scenario_limits(spec)
        goal_tolerance = scenario_subgoal_policy(spec).goal_tolerance_m
        laser = LaserPerception(robot_radius_m=spec.robot.radius)
        rng = np.random.default_rng(spec.seed if seed is None else seed)
        laser.reset(rng)
        names = [s.name for s in laser.scanners]
        for f in faults:
            if f.scanner and f.scanner not in names:
                raise ValueError(f"--fault: unknown scanner {f.scanner!r}; scanners: {', '.join(names)}")
        world = (spec, dt, n_steps, times, positions, velocities, radii, static_world, path, limits)
        return cls(*world, goal_tolerance, laser)

    @property
    def names(self) -> list[str]:
        return [s.name for s in self.laser.scanners]


@dataclass
class _Episode:
    """What the episode recorded: poses, the commands received, the node's reports matched by stamp."""

    rows: dict[str, list] = field(default_factory=lambda: {k: [] for k in ("pose", "speed", "turn")})
    records: list[StepRecord] = field(default_factory=list)
    reached: bool = False
    offset_s: float = 0.0  # the clock's jumps back so far
    late_steps: list[int] = field(default_factory=list)
    received: list[tuple[float, float, float, float]] = field(default_factory=list)  # sim time, v, w, speed
    worlds: list = field(default_factory=list)  # (stamp key, true world) per step
    last_state: Any = None


class _SimNode:
    """The simulator's side of the ROS graph: /clock, odometry, scans, TF and the designated path out;
    cmd_vel and the planner's status in."""

    def __init__(self, node, stop, world: _World, tf: bool, map_offset):
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from nav_msgs.msg import Path as PathMsg
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import LaserScan

        from viapath.ros2 import convert

        self.node, self.stop, self.world = node, stop, world
        latched = QoSProfile(
            depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
        )
        self.clock_pub = node.create_publisher(Clock, "/clock", 10)
        self.odom_pub = node.create_publisher(Odometry, "odom", 10)
        self.path_pub = node.create_publisher(PathMsg, "designated_path", latched)
        self.scan_pubs = {
            n: node.create_publisher(LaserScan, f"scan_{n}", qos_profile_sensor_data) for n in world.names
        }
        self.got: dict[str, Any] = {"cmd": None, "cmd_count": 0, "status": [], "by_stamp": {}, "watchdog": []}
        node.create_subscription(Twist, "cmd_vel", self._on_twist, 10)
        self.tf_pub = _tf_publishers(node, world.laser.scanners, map_offset) if tf else None
        node.create_subscription(DiagnosticArray, "viapath/status", self._on_status, 50)
        self.clock = Clock()
        self.clock.clock = convert.time_msg(0.0)

    def _on_twist(self, msg) -> None:
        self.got["cmd"] = (msg.linear.x, msg.angular.z)
        self.got["cmd_count"] += 1

    def _on_status(self, msg) -> None:
        for s in msg.status:
            if s.name.endswith(": planner"):
                values = {kv.key: kv.value for kv in s.values}
                self.got["status"].append(values)
                try:
                    stamp = round(float(values.get("stamp_s", "nan")), 6)
                except ValueError:
                    continue
                if values.get("source") == "cycle":
                    self.got["by_stamp"][stamp] = values
                else:
                    self.got["watchdog"].append(stamp)

    def spin_until(self, deadline: float, done=lambda: False, heartbeat: bool = False) -> None:
        """Spin until ``deadline`` or ``done()``; with ``heartbeat``, publish the (unchanged) clock every
        50 ms meanwhile: the simulation waits, it has not stopped (the node's wall-clock watchdog
        takes a silent /clock for a dead simulator)."""
        import rclpy

        beat = time.monotonic()
        while not self.stop["flag"]:
            now = time.monotonic()
            remaining = deadline - now
            if remaining <= 0 or done():
                return
            if heartbeat and now - beat >= 0.05:
                self.clock_pub.publish(self.clock)
                beat = now
            rclpy.spin_once(self.node, timeout_sec=min(remaining, 0.01))

    def wait_for_node(self, wait_for_node_s: float) -> bool:
        """Publish the clock and the path, wait for a planner node, warm it up; False when none came."""
        import rclpy

        from viapath.ros2 import convert

        self.clock_pub.publish(self.clock)
        waypoints = self.world.spec.path.waypoints
        self.path_pub.publish(convert.path_message(waypoints, "odom", convert.time_msg(0.0)))
        # Wait for a planner node: someone listening to the scans and publishing commands.
        started, first = time.monotonic(), self.world.names[0]
        while not self.stop["flag"] and (
            self.node.count_subscribers(f"scan_{first}") == 0
            or self.node.count_publishers(_resolved(self.node, "cmd_vel")) == 0
        ):
            if time.monotonic() - started > wait_for_node_s:
                print(
                    f"error: no planner node (subscriber of scan_{first}, publisher of cmd_vel) within "
                    f"{wait_for_node_s:g} s",
                    file=sys.stderr,
                )
                return False
            rclpy.spin_once(self.node, timeout_sec=0.05)
        self._warm_up(started, wait_for_node_s)
        return True

    def _warm_up(self, started: float, wait_for_node_s: float) -> None:
        """Tick the clock below the episode's start (1 s) until the node's watchdog reports ("no scan
        yet"): then clock, status and commands are matched both ways."""
        from viapath.ros2 import convert

        def node_ready():
            last = self.got["status"][-1] if self.got["status"] else {}
            return (
                bool(last) and "no designated path" not in last.get("reasons", "") and last.get("inputs_matched") == "1"
            )

        tick = 0.0
        while not self.stop["flag"] and not node_ready() and time.monotonic() - started < wait_for_node_s:
            tick = min(tick + 0.01, 0.99)
            self.clock.clock = convert.time_msg(tick)
            self.clock_pub.publish(self.clock)
            self.spin_until(time.monotonic() + 0.02)
        if not node_ready():
            print("warning: the planner node did not report a designated path during warm-up", file=sys.stderr)
        self.spin_until(time.monotonic() + 0.2)

    def publish_state(self, t: float, offset_s: float, state, odometry: bool = True):
        """/clock, TF and (unless ``odometry`` is off) odometry of step time ``t``; the stamp and its seconds."""
        from viapath.ros2 import convert

        stamp_s = max(t + offset_s, 0.0) + 1.0  # +1 s: /clock never shows 0 (rclpy's "time not set")
        stamp = convert.time_msg(stamp_s)
        self.clock.clock = stamp
        self.clock_pub.publish(self.clock)
        if self.tf_pub is not None:
            self.tf_pub(stamp, state.x, state.y, state.heading_rad)
        if odometry:
            self.odom_pub.publish(
                convert.odometry(
                    "odom",
                    "base_link",
                    stamp,
                    state.x,
                    state.y,
                    state.heading_rad,
                    state.speed_mps,
                    state.turn_rate_radps,
                )
            )
        return stamp, stamp_s

    def publish_scan(self, scanner, stamp, ranges) -> None:
        from viapath.ros2 import convert

        self.scan_pubs[scanner.name].publish(
            convert.laser_scan(
                f"laser_{scanner.name}",
                stamp,
                scanner.angle_min_rad,
                scanner.angle_increment_rad,
                ranges,
                scanner.range_min_m,
                scanner.range_max_m,
                scanner.scan_period_s,
            )
        )

    def command(self) -> tuple[float, float]:
        """The latest cmd_vel (a stop before the first)."""
        return self.got["cmd"] if self.got["cmd"] is not None else (0.0, 0.0)

    def play(self, rate: float, lockstep: bool, max_wait_s: float, faults: list[Fault]) -> _Episode:
        """Every step: publish, wait for the node (with ``lockstep``) and hold the rate, drive."""
        from viapath.observation import Command
        from viapath.sim import robot as kinematics

        world, episode, period = self.world, _Episode(), self.world.dt / rate
        spec = world.spec
        state = kinematics.UnicycleState(
            spec.robot.start[0], spec.robot.start[1], spec.robot.heading, spec.robot.speed, 0.0
        )
        jumped: set[int] = set()
        self.wall_start = time.monotonic()
        for k in range(world.n_steps + 1):
            episode.rows["pose"].append((state.x, state.y, state.heading_rad))
            episode.rows["speed"].append(state.speed_mps)
            episode.rows["turn"].append(state.turn_rate_radps)
            if np.hypot(*(world.path.goal - state.position)) <= world.goal_tolerance:
                episode.reached = True
            if episode.reached or k == world.n_steps or self.stop["flag"]:
                episode.records.append(StepRecord(status="end"))
                break
            t = float(world.times[k])
            for f in faults:
                if f.kind == "clock-back" and t >= f.at_s and id(f) not in jumped:
                    jumped.add(id(f))
                    episode.offset_s -= f.amount_s
            on_time, key, true_world = self._step(k, t, state, episode.offset_s, faults, lockstep, max_wait_s, period)
            if not on_time:
                episode.late_steps.append(k)
            v, w = self.command()
            episode.received.append((t, v, w, state.speed_mps))
            episode.records.append(StepRecord((v, w), v, late=not on_time))
            episode.worlds.append((key, true_world))
            state = kinematics.step(state, Command(v, w), world.limits, world.dt)
        episode.last_state = state
        return episode

    def _step(self, k: int, t: float, state, offset_s: float, faults, lockstep: bool, max_wait_s: float, period):
        """Publish step ``k`` (faults applied) and wait for the node; (command on time, stamp key, true world)."""
        from viapath.sim.perception import WorldSnapshot

        world = self.world
        odometry = not any(f.kind == "odom" and f.active(t) for f in faults)
        stamp, stamp_s = self.publish_state(t, offset_s, state, odometry)
        pose = np.array([state.x, state.y, state.heading_rad])
        standing = world.static_world.at(t)
        snapshot = WorldSnapshot(
            t, pose, world.spec.robot.radius, world.positions[k], world.velocities[k], world.radii,
            standing.segments, standing,
        )  # fmt: skip
        for scanner, ranges in zip(world.laser.scanners, world.laser.scan(snapshot), strict=True):
            active = [f for f in faults if f.scanner == scanner.name and f.active(t)]
            if any(f.kind == "silence" for f in active):
                continue
            if any(f.kind == "nan" for f in active):
                ranges = np.full_like(ranges, np.nan)
            if any(f.kind == "short" for f in active):
                ranges = ranges[:-10]
            self.publish_scan(scanner, stamp, ranges)
        count_before, key = self.got["cmd_count"], round(stamp_s, 6)
        published = sum(
            1 for n in world.names if not any(f.scanner == n and f.kind == "silence" and f.active(t) for f in faults)
        )

        def cycle_reported():
            if key in self.got["by_stamp"]:
                return self.got["cmd_count"] > count_before  # its command too (another topic: may come second)
            # no scan this step: the node's watchdog answers instead
            watchdog = self.got["watchdog"]
            return published == 0 and bool(watchdog) and watchdog[-1] >= key - 1e-6

        if lockstep:
            self.spin_until(time.monotonic() + max_wait_s, cycle_reported, heartbeat=True)
        self.spin_until(self.wall_start + (k + 1) * period)  # hold the rate
        return cycle_reported() and self.got["cmd_count"] > count_before, key, snapshot

    def linger(self, episode: _Episode, linger_s: float, period: float) -> None:
        """After the goal, keep the world going a little (not recorded): the node may report its goal."""
        from viapath.observation import Command
        from viapath.sim import robot as kinematics
        from viapath.sim.perception import WorldSnapshot

        world, state = self.world, episode.last_state
        last = min(len(episode.records) - 1, world.n_steps)
        for j in range(int(round(linger_s / world.dt))):
            if self.stop["flag"]:
                break
            t = float(world.times[last]) + (j + 1) * world.dt
            stamp, _ = self.publish_state(t, episode.offset_s, state)
            pose = np.array([state.x, state.y, state.heading_rad])
            snapshot = WorldSnapshot(
                t, pose, world.spec.robot.radius, world.positions[last], world.velocities[last] * 0.0, world.radii,
                world.static_world.segments,
            )  # fmt: skip
            for scanner, ranges in zip(world.laser.scanners, world.laser.scan(snapshot), strict=True):
                self.publish_scan(scanner, stamp, ranges)
            self.spin_until(time.monotonic() + period)
            v, w = self.command()
            state = kinematics.step(state, Command(v, w), world.limits, world.dt)

    def trace_and_metrics(self, episode: _Episode, seed: int | None):
        """The episode's trace (the node's reports matched by stamp) and its metrics, as ``viapath run``'s."""
        from viapath.observation import Obstacles
        from viapath.perception.laser import tracking_errors
        from viapath.ros2.core import parse_points, parse_tracks

        reported, truth, records, got = [], [], episode.records, self.got
        for rec, (key, true_world) in zip(records, episode.worlds):
            status = got["by_stamp"].get(key, {})
            rec.plan_speed = float(status.get("plan_speed_mps", rec.command[0]))
            rec.status = status.get("plan_status", status.get("mode", "none"))
            rec.side = int(status.get("plan_side", 0))
            rec.cycle_ms = float(status.get("plan_time_ms") or status.get("cycle_time_ms") or "nan")
            rec.perception_ms = float(status.get("perception_time_ms") or "nan")
            if status:
                ids, pos, vel, rad = parse_tracks(status.get("tracks_xyv", ""))
                rec.via = parse_points(status.get("via_xy", ""))
                reported.append(Obstacles(pos, vel, rad, ids=ids))
                truth.append(true_world)
        trace = self._trace(episode, seed)
        metrics = _shield_and_perception_metrics(trace, got, records)
        metrics.update(tracking_errors(reported, truth))
        perception_ms = np.array([r.perception_ms for r in records], dtype=float)
        perception_ms = perception_ms[np.isfinite(perception_ms)]
        metrics["perception_time_p50_ms"] = float(np.percentile(perception_ms, 50)) if len(perception_ms) else None
        metrics["perception_time_p99_ms"] = float(np.percentile(perception_ms, 99)) if len(perception_ms) else None
        return trace, {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in metrics.items()}

    def _trace(self, episode: _Episode, seed: int | None):
        from viapath.sim.loop import Trace

        world, rows, records, got = self.world, episode.rows, episode.records, self.got
        spec, n = world.spec, len(rows["pose"])
        return Trace(
            scenario_name=spec.name,
            planner_name=(got["status"][-1].get("planner", "viapath") if got["status"] else "viapath"),
            perception_mode="laser",
            dt_s=world.dt,
            path=world.path,
            robot_radius_m=spec.robot.radius,
            times_s=world.times[:n],
            robot_poses=np.array(rows["pose"]),
            robot_speeds_mps=np.array(rows["speed"]),
            robot_turn_rates_radps=np.array(rows["turn"]),
            commands=np.array([r.command for r in records]),
            obstacle_positions=world.positions[:n],
            obstacle_velocities=world.velocities[:n],
            obstacle_radii_m=world.radii,
            plan_speeds_mps=np.array([r.plan_speed for r in records]),
            plan_targets=np.tile(world.path.goal, (len(records), 1)),
            plan_status=[r.status for r in records],
            via_points=[r.via for r in records],
            plan_times_ms=np.array([r.cycle_ms for r in records[:-1]] + [np.nan]),
            reached_goal=episode.reached,
            walls=world.static_world.segments,
            wall_until_s=world.static_world.until_s,
            wall_closed_ids=world.static_world.closed_ids(),
            extras={"nominal_speed_mps": spec.robot.speed, "seed": spec.seed if seed is None else seed},
            plan_sides=np.array([r.side for r in records], dtype=int),
        )


def _shield_and_perception_metrics(trace, got: dict, records) -> dict:
    """``compute_metrics`` of the trace, with the shield's interventions the node reported."""
    from viapath.sim.metrics import compute_metrics

    metrics = compute_metrics(trace)
    shielded_cycles = [v for v in got["by_stamp"].values() if "shield_intervened" in v]
    metrics.update(
        {
            "shield": bool(shielded_cycles),
            "shield_interventions": (
                sum(int(v["shield_intervened"]) for v in shielded_cycles) if shielded_cycles else None
            ),
        }
    )
    if shielded_cycles:
        metrics["shield_mode"] = shielded_cycles[-1].get("shield_mode")
    return metrics


def run_sim(
    scenario_source: str,
    rate: float = 1.0,
    lockstep: bool = False,
    max_wait_s: float = 10.0,
    as_json: bool = False,
    seed: int | None = None,
    faults: list[Fault] | None = None,
    trace_file: str | None = None,
    wait_for_node_s: float = 60.0,
    commands_file: str | None = None,
    ros_args: list[str] | None = None,
    duration_s: float | None = None,
    status_file: str | None = None,
    tf: bool = True,
    map_offset: tuple[float, float, float] = (0.0, 0.0, 0.0),
    linger_s: float = 0.0,
) -> int:
    """Run one episode against whatever node listens; prints metrics; returns the exit code."""
    from viapath.ros2.process import finish_ros_process, start_ros_process

    faults = list(faults or [])
    world = _World.of(scenario_source, seed, duration_s, faults)
    node, stop, previous = start_ros_process("viapath_sim", ros_args)
    try:
        sim = _SimNode(node, stop, world, tf, map_offset)
        if not sim.wait_for_node(wait_for_node_s):
            return 3
        episode = sim.play(rate, lockstep, max_wait_s, faults)
        if episode.reached and linger_s > 0:
            sim.linger(episode, linger_s, world.dt / rate)
        sim.spin_until(time.monotonic() + 0.5)  # the last reports
        trace, metrics = sim.trace_and_metrics(episode, seed)
        _write_files(trace, sim.got["status"], episode.received, trace_file, status_file, commands_file)
        late_steps = episode.late_steps
        print(
            f"viapath ros2 sim: {len(episode.records) - 1} steps, {len(late_steps)} without the node's command in "
            f"time, rate {rate:g}{' lockstep' if lockstep else ''}, {time.monotonic() - sim.wall_start:.1f} s"
            + (f" (late steps: {late_steps[:10]})" if late_steps else ""),
            file=sys.stderr,
        )
        if as_json:
            from viapath.io.jsonable import dumps as json_dumps

            print(json_dumps(metrics))
        else:
            for key, value in metrics.items():
                print(f"{key}: {value}")
        return 0
    finally:
        finish_ros_process(node, previous)


def _write_files(trace, statuses, received, trace_file, status_file, commands_file) -> None:
    if trace_file:
        from viapath.io.trace import write_trace_csv

        write_trace_csv(trace, trace_file)
    if status_file:
        with open(status_file, "w") as handle:
            for values in statuses:
                handle.write(json.dumps(values) + "\n")
    if commands_file:
        np.savetxt(
            commands_file,
            np.array(received).reshape(-1, 4),
            delimiter=",",
            header="time_s,v_mps,w_radps,measured_speed_mps",
            comments="",
        )
