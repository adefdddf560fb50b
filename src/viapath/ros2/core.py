"""What the ROS 2 node does each scan cycle, without ROS: inputs checked, perception, planning, safe stops.

Source: docs/design.md §3 (two URG-04LX, invalid readings 0 / NaN / inf), §8 (topics); the perception chain
of :mod:`viapath.perception` (fusion, detection, tracking: the same code ``viapath run --perception
laser`` runs) and any registered planner. The rclpy node (:mod:`viapath.ros2.node`) only converts
messages and calls this; tests drive it directly too.

What we chose where the sources are silent:
* **A cycle** runs when every scanner that is alive has delivered a scan since the last cycle, or
  when one scanner delivers its second scan meanwhile (the others are late: do not wait for them).
  Scans of one cycle lie within half a cycle period of each other: an older waiting scan missed its
  cycle and is dropped. All scans of a cycle are placed with the pose at the newest stamp
  (unsynchronised scanners, up to 50 ms apart, put a point at most 2.5 cm off at 0.5 m/s). At
  start the first cycle waits (up to ``scan_timeout_s``) for every scanner's first scan. The robot pose for the scans is the latest
  odometry moved to the scan stamp along its own twist (odometry and scans are never stamped alike).
* **Bad scans** are refused and counted per reason: wrong frame_id, a beam count or angle range
  other than the scanner's, a stamp older than the scanner's previous one, more than
  ``max_invalid_fraction`` of NaN / zero readings (a failing scanner; +inf is "no return" and fine).
  With ``scan_geometry: from_message`` the first good scan sets the layout, so a first scan whose
  layout is no scanner's (range_min not below range_max, beams × increment beyond a full turn, a
  non-positive increment) is refused (``layout``) and the next one tried. A scan that cannot be read
  at all is refused as ``error``: no message ends the node. A scanner with no good scan for
  ``scan_timeout_s`` is *silent*.
* **Odometry that lies** is a fault: a twist beyond the limits (plus ``odom_speed_tolerance_mps`` /
  ``odom_turn_tolerance_radps``), above every speed (or outside the turn rates) commanded in the last
  ``odom_timeout_s`` once the node has driven, a twist its own pose change does not bear out, a
  quaternion that is no rotation: the message is refused. A pose or heading that moves further than
  the twist explains is a jump: kept as the new reference, tracks reset, the robot held for
  ``reset_hold_s``. Either way the robot brakes for ``reset_hold_s`` (status: "odometry fault: …"),
  from the last *commanded* speed: a faulty measurement is never the base of a command. (The first
  message after start or a reset has nothing to be compared with but the limits.)
* **The designated path**: an empty ``nav_msgs/Path`` clears it (the robot brakes to a stop, status
  "designated path cleared by an empty path"); a path with a NaN position, a bad quaternion or another
  frame is refused and the previous path stays.
* **All scanners silent**, or no odometry for ``odom_timeout_s``, or no path: the robot brakes to a
  stop within its limits (the command ramps down by ``max_accel_mps2`` per cycle from the measured
  speed) and the status says why. While scans arrive the cycles brake for these reasons themselves; the
  watchdog, every ``cycle_period_s`` of the node's clock, sends the braking command only when no cycle
  ran in the last 1.5 periods: one command per period, never a second one beside a cycle's (two brakes
  in one period would also take twice a cycle's braking off the speed). A second watchdog runs on the
  wall clock: with ``use_sim_time`` the node's clock stops with /clock, so
  when nothing at all (no input, no /clock) arrived for ``wall_timeout_s`` of wall time, it brakes
  from the last command.
* **Some scanners silent**: the cycle goes on with the others; their field of view is the one the
  planner has, and the rest is *blind* (:func:`viapath.perception.fusion.blind_region` of the live
  scanners). The robot never drives into a blind sector: if the directions within 30° of its heading
  are blind beyond its body, it does not drive forward (it may turn on the spot). Otherwise the speed
  is capped so that it comes to rest before an unseen person could reach it: someone unseen is taken
  to be at least ``blind_clearance_m`` from the body and to walk at ``blind_person_speed_mps``, so
  they need ``T = blind_clearance_m / blind_person_speed_mps``; the robot stops within one cycle plus
  ``v / max_accel``, hence ``v ≤ max_accel · (T − cycle_period_s)`` (0.16 m/s with the defaults).
  Tracks of people seen before the scanner fell silent coast for the tracker's ``max_unseen_s``.
* **A time jump backwards** (a scan or odometry stamp earlier than the last cycle's): the tracker and
  odometry are reset, and the robot is held stopped for ``reset_hold_s`` of the new time so that
  tracks confirm again before it moves.
* **Static geometry**: every scan return no person track explains (:mod:`viapath.perception.static_layer`,
  parameter ``static_layer``) and, with ``map_topic``, a known map's occupied cells are the observation's
  static layer: the planner, the guard and the shield keep clear of them (docs/design.md §10).
* **Every command** is finite and inside the limits: speed in [0, max_speed_mps], turn rate in
  ±max_turn_rate_radps, at most one cycle's acceleration above the measured speed, and at most one
  cycle's braking below the *lower* of the measured and the last commanded speed (a turn rate may
  likewise go toward zero from either): the ramp slows a stop down but never turns a planner's stop
  into motion that was not commanded.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from viapath.guard import DEFAULT_CONFIG as GUARD_DEFAULTS
from viapath.observation import Command, MotionLimits, Observation, Obstacles, RobotState
from viapath.path import DesignatedPath, SubgoalPolicy
from viapath.perception.detection import DetectorParams, detect
from viapath.perception.fusion import blind_region
from viapath.perception.scanner import ScannerModel
from viapath.perception.static_layer import StaticLayerParams, StaticObstacleLayer
from viapath.perception.tracking import MultiTargetTracker, TrackerParams
from viapath.planning import Decision, make_planner
from viapath.ros2.convert import QUATERNION_TOLERANCE
from viapath.ros2.settings import MAX_MOUNT_OFFSET_M, NodeSettings
from viapath.static import StaticLayer

FORWARD_CONE_RAD = math.radians(30.0)
# The watchdog is quiet this many cycle periods after a scan cycle: more than one, so that scans a little
# late (a busy machine) do not let it add a command beside the cycles'; a cycle missed is made up for
# within 2.5 periods.
WATCHDOG_QUIET_PERIODS = 1.5
NO_PATH = "no designated path"
PATH_CLEARED = "designated path cleared by an empty path"


@dataclass
class ScannerHealth:
    model: ScannerModel | None
    expected_frame: str
    last_good_s: float | None = None  # node clock time of the last good scan
    pending: tuple[float, np.ndarray] | None = None  # (stamp, ranges) not yet used by a cycle
    good: int = 0
    refused: dict[str, int] = field(default_factory=dict)
    last_problem: str = ""
    invalid_fraction: float = 0.0
    mount: tuple[float, float, float] | None = None  # from TF; None: the parameters'

    def refuse(self, reason: str, detail: str) -> None:
        self.refused[reason] = self.refused.get(reason, 0) + 1
        self.last_problem = detail


@dataclass
class Odometry:
    stamp_s: float
    received_s: float
    x: float
    y: float
    heading_rad: float
    speed_mps: float
    turn_rate_radps: float


@dataclass
class CycleResult:
    """What one cycle (or one watchdog tick) sends out."""

    command: Command
    mode: str  # driving | degraded | braking | stopped | goal | waiting
    reasons: list[str]
    stamp_s: float
    decision: Decision | None = None
    obstacles: Obstacles = field(default_factory=Obstacles.empty)
    robot_pose: np.ndarray | None = None
    blind_sectors_rad: list[tuple[float, float]] = field(default_factory=list)
    speed_cap_mps: float | None = None
    cycle_time_ms: float | None = None
    perception_time_ms: float | None = None  # detection and tracking of this cycle's scans
    plan_time_ms: float | None = None  # the planner's own call
    status: dict[str, dict[str, str]] = field(default_factory=dict)  # name -> key/values, for diagnostics
    static: StaticLayer = field(default_factory=StaticLayer.empty)  # the static layer the planner was given


def urg04lx_models(settings: NodeSettings) -> list[ScannerModel]:
    return [
        ScannerModel(name=s.name, mount_x_m=s.mount_x_m, mount_y_m=s.mount_y_m, mount_yaw_rad=s.mount_yaw_rad)
        for s in settings.scanners
    ]


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


def scan_layout_problem(beams: int, angle_increment_rad: float, range_min_m: float, range_max_m: float) -> str:
    """Why a scan's beam layout cannot be a scanner's ('' when it can): the first scan of a scanner
    with ``scan_geometry: from_message`` sets its layout, so it must make sense on its own."""
    if beams < 2:
        return f"{beams} beams (at least 2)"
    if not (math.isfinite(angle_increment_rad) and angle_increment_rad > 0.0):
        return f"angle_increment {angle_increment_rad} rad (must be > 0)"
    if (beams - 1) * angle_increment_rad > 2.0 * math.pi + 1e-6:
        return (
            f"{beams} beams x {angle_increment_rad:.6g} rad = {math.degrees((beams - 1) * angle_increment_rad):.1f} deg, "
            f"more than a full turn"
        )
    if not (math.isfinite(range_min_m) and math.isfinite(range_max_m)):
        return f"range_min {range_min_m} / range_max {range_max_m} m (must be finite)"
    if not max(range_min_m, 0.0) < range_max_m:
        return f"range_min {range_min_m:g} m is not below range_max {range_max_m:g} m"
    return ""


@dataclass
class PreparedPath:
    """A designated path and a planner on it, built beside the control loop (:meth:`PlannerCore.build_path`)."""

    path: DesignatedPath
    planner: Any
    what: str = ""


class PlannerCore:
    """The node's logic; times are seconds of the node's clock (sim time with ``use_sim_time``)."""

    def __init__(self, settings: NodeSettings):
        self.settings = settings
        s = settings
        self.limits = MotionLimits(s.max_speed_mps, s.max_accel_mps2, s.max_turn_rate_radps, s.max_turn_accel_radps2)
        self.subgoal_policy = SubgoalPolicy(s.reach_threshold_m, s.goal_tolerance_m, s.bypass_distance_m)
        fixed = s.scan_geometry == "urg04lx"
        models = urg04lx_models(s) if fixed else [None] * len(s.scanners)
        self.health = [ScannerHealth(m, sc.frame_id) for m, sc in zip(models, s.scanners, strict=True)]
        if s.detector == "legs":
            self.detector_params = DetectorParams.for_legs()
        else:
            self.detector_params = DetectorParams(keep_segments=False)
        self.tracker = MultiTargetTracker(
            TrackerParams(
                acceleration_sigma_mps2=s.tracker_acceleration_sigma_mps2,
                static_after_s=s.tracker_static_after_s or math.inf,  # 0: never static
            )
        )
        self.static_layer = StaticObstacleLayer((), StaticLayerParams(enabled=bool(s.static_layer)))
        self.map_layer = StaticLayer.empty()  # a known map (set_map), in the odometry frame
        self.path: DesignatedPath | None = None
        self.path_cleared = False  # by an empty path message
        self.paths_refused = 0
        self.planner: Any = None  # made with the path
        self.odometry: Odometry | None = None
        self.odom_refused: dict[str, int] = {}
        self.last_cycle_stamp_s: float | None = None
        self.hold_until_stamp_s: float | None = None
        self.last_command = Command.stop()
        self.last_command_s: float | None = None
        self.last_cycle_s: float | None = None  # the node's time of the last scan cycle (its command sent)
        self.last_result: CycleResult | None = None
        self.cycle_times_ms: list[float] = []
        self.events: list[str] = []  # things reported once (time jumps, refused path)
        self.active = True
        self.goal_reached = False
        self.speed_limit_mps: float | None = None  # from Nav2's speed_limit topic (None: no limit)
        self._now_s = 0.0
        self._first_scan_s: float | None = None
        self.odom_problem = ""
        self.odom_fault: tuple[float, str] | None = None  # (until, why) on the node's clock
        self._odom_history: list[Odometry] = []  # recent finite messages, refused ones too
        self._commands: list[tuple[float, float, float]] = []  # (time, v, w) sent while driving
        self._commands_armed = False  # from the first planned cycle on (not the start-up watchdog's stops)
        self.hold_reason = ""
        self._alive_wall_s: float | None = None  # wall time of the last input or move of the node's clock
        self.static_now = StaticLayer.empty()  # the last cycle's static layer from the scans
        self.static_planned = StaticLayer.empty()  # the last cycle's static layer the planner got (map and scans)
        self.blocked_since_s: float | None = None  # since when the plans say static geometry closes the way

    def _make_planner(self, path: DesignatedPath, subgoal_policy: SubgoalPolicy):
        """The configured planner on ``path``, behind the shield when ``use_shield`` says so."""
        from viapath.ros2.options import planner_kwargs
        from viapath.safety import shielded

        s = self.settings
        planner = make_planner(
            s.planner_name,
            path,
            nominal_speed_mps=s.nominal_speed_mps,
            limits=self.limits,
            robot_radius_m=s.robot_radius_m,
            subgoal_policy=subgoal_policy,
            **planner_kwargs(s.planner_name, dict(s.planner_values)),
        )
        return shielded(planner, s.shield_flag, s.cycle_period_s, dict(s.shield_values), s.planner_name)

    def warm_up(self) -> None:
        """Run detection and one plan on made-up input, so the first real cycle is not slowed by imports."""
        from viapath.perception.raycast import simulate_scan

        models = [h.model for h in self.health if h.model is not None]
        if models:  # a person beside the robot, so that every step of detection runs (and compiles) once
            scans = [
                simulate_scan(m, np.zeros(3), np.array([[1.0, 0.4], [-1.0, -0.4]]), np.array([0.25, 0.25]))
                for m in models
            ]
            found = detect(models, scans, self.detector_params)
            tracker = MultiTargetTracker(self.tracker.params)
            for k in range(4):
                tracker.step(0.1 * k, found.centres, found.position_sigma_m, found.radii_m)
        path = DesignatedPath([[0.0, 0.0], [5.0, 0.0]], half_width_m=1.0)
        from viapath.precompile import precompile

        precompile()  # the compiled shield and planner: once per machine, before the node makes its own
        planner = self._make_planner(path, SubgoalPolicy())
        planner.plan(
            Observation(0.0, RobotState(np.zeros(2), 0.0, 0.2), Obstacles([[2.0, 0.0]], [[-0.3, 0.0]], [0.25]))  # type: ignore[arg-type]  # lists: Obstacles makes arrays of them
        )

    # -- inputs --------------------------------------------------------------------------------
    def set_path(self, waypoints, half_widths_m=None) -> None:
        """A new designated path (world frame = odometry frame); the planner starts again on it."""
        self.use_prepared(self.build_path(waypoints, half_widths_m))

    def build_path(self, waypoints, half_widths_m=None) -> PreparedPath:
        """The path and a planner on it, changing nothing of the core (so a worker thread may build them
        while the cycles go on with the current path); ``ValueError`` for waypoints that cannot be one."""
        waypoints = np.asarray(waypoints, dtype=float).reshape(-1, 2)
        bound = GUARD_DEFAULTS.max_coordinate_m
        if not (np.isfinite(waypoints).all() and (np.abs(waypoints) <= bound).all()):
            worst = waypoints[~(np.isfinite(waypoints) & (np.abs(waypoints) <= bound)).all(axis=1)][0]
            raise ValueError(f"path waypoints: expected finite coordinates within ±{bound:g} m, found {worst.tolist()}")
        s = self.settings
        if half_widths_m is None:
            widths = (
                [w if w > 0 else s.half_width_m for w in s.half_widths_m]
                if any(w > 0 for w in s.half_widths_m)
                else None
            )
        else:
            widths = list(half_widths_m)
        if widths is not None and len(widths) != len(waypoints) - 1:
            widths = None  # one width per segment or the single half_width_m
            self.events.append(
                f"half_widths_m has {len(s.half_widths_m)} values for {len(waypoints) - 1} segments: using half_width_m"
            )
        if widths is None:
            path = DesignatedPath(waypoints, half_width_m=s.half_width_m)
        else:
            path = DesignatedPath(waypoints, half_widths_m=widths)
        return PreparedPath(path, self._make_planner(path, self.subgoal_policy))

    def use_prepared(self, prepared: PreparedPath) -> None:
        """Drive on a path :meth:`build_path` made (an assignment: cheap in the control loop)."""
        self.path, self.planner = prepared.path, prepared.planner
        self.goal_reached = False
        self.path_cleared = False

    def clear_path(self, why: str | None = None) -> None:
        """No designated path any more: the cycles brake the robot to rest. With ``why`` (an empty path
        message) the status says the path was cleared and why; without (a goal that ended), "no designated path"."""
        self.path, self.planner = None, None
        self.goal_reached = False
        self.path_cleared = why is not None
        if why is not None:
            self.events.append(f"designated path cleared ({why}): stopping")

    def on_path(self, frame_id: str, waypoints, orientations=None) -> tuple[bool, str]:
        """A ``nav_msgs/Path`` as arrays: (N, 2) positions and (N, 4) quaternions. An empty path clears the
        designated path (the robot stops); a bad one is refused (the old path stays). Returns (accepted, what)."""
        return self.use_path_message(self.prepare_path_message(frame_id, waypoints, orientations))

    def prepare_path_message(self, frame_id: str, waypoints, orientations=None) -> tuple[str, Any]:
        """:meth:`on_path` up to the point of driving on it, changing nothing of the core (a worker thread
        runs it): ("path", PreparedPath), ("clear", why) or ("refused", why)."""
        from viapath.ros2.convert import checked_yaw

        expected = self.settings.odom_frame
        if expected and frame_id and frame_id != expected:
            return "refused", f"frame_id {frame_id!r}, expected {expected!r}"
        try:
            points = np.asarray(waypoints, dtype=float).reshape(-1, 2)
            quaternions = None if orientations is None else np.asarray(orientations, dtype=float).reshape(-1, 4)
        except (TypeError, ValueError) as error:
            return "refused", f"not (x, y) positions: {error}"
        if len(points) == 0:
            return "clear", "an empty path was received"
        if not np.isfinite(points).all():
            return "refused", "a NaN or infinite position"
        if quaternions is not None and len(quaternions):
            with np.errstate(over="ignore", invalid="ignore"):  # 1e300: an infinite norm, refused below
                norms = np.sqrt((quaternions**2).sum(axis=1))
            bad = np.flatnonzero(~(np.isfinite(norms) & (np.abs(norms - 1.0) <= QUATERNION_TOLERANCE)))
            if len(bad):
                try:
                    checked_yaw(*quaternions[bad[0]])
                except ValueError as error:
                    return "refused", f"pose {bad[0]}: {error}"
        try:
            prepared = self.build_path(points)
        except ValueError as error:
            return "refused", str(error)
        prepared.what = f"designated path: {len(points)} waypoints, goal ({points[-1][0]:.2f}, {points[-1][1]:.2f})"
        return "path", prepared

    def use_path_message(self, prepared: tuple[str, Any]) -> tuple[bool, str]:
        """Apply what :meth:`prepare_path_message` made; returns (accepted, what)."""
        kind, value = prepared
        if kind == "clear":
            self.clear_path(value)
            return True, self.events[-1]
        if kind == "refused":
            return self._path_refused(value)
        self.use_prepared(value)
        return True, value.what

    def _path_refused(self, why: str) -> tuple[bool, str]:
        self.paths_refused += 1
        self.events.append(f"path refused: {why}" + (" (the previous path stays)" if self.path is not None else ""))
        return False, self.events[-1]

    def on_odometry_quaternion(
        self,
        now_s: float,
        stamp_s: float,
        frame_id: str,
        x: float,
        y: float,
        quaternion,
        speed_mps: float,
        turn_rate_radps: float,
    ) -> bool:
        """:meth:`on_odometry` with the orientation as a quaternion (x, y, z, w): one that is not a rotation
        (not finite, not of unit length) is refused as a fault, never read as some heading."""
        from viapath.ros2.convert import checked_yaw

        try:
            heading = checked_yaw(*quaternion)
        except (TypeError, ValueError) as error:
            self.refuse_odometry(now_s, "quaternion", f"orientation: {error}")
            return False
        return self.on_odometry(now_s, stamp_s, frame_id, x, y, heading, speed_mps, turn_rate_radps)

    def same_path(self, waypoints, tolerance_m: float = 1e-3) -> bool:
        """Whether ``waypoints`` are the current path's (a re-sent path: keep the planner as it is)."""
        if self.path is None:
            return False
        waypoints = np.asarray(waypoints, dtype=float).reshape(-1, 2)
        current = np.asarray(self.path.waypoints, dtype=float)
        return current.shape == waypoints.shape and bool(np.all(np.abs(current - waypoints) <= tolerance_m))

    def distance_to_goal(self) -> float | None:
        """Distance along the path from the robot's projection to the goal (m), or None."""
        if self.path is None or self.odometry is None:
            return None
        _, arc, _ = self.path.project(np.array([self.odometry.x, self.odometry.y]))
        return max(float(self.path.length_m - arc), 0.0)

    def set_speed_limit(self, limit: float, percentage: bool) -> None:
        """Nav2's ``SpeedLimit``: a percentage of ``max_speed_mps`` or m/s; 0 (or not finite) lifts it."""
        if not math.isfinite(limit) or limit <= 0.0:
            self.speed_limit_mps = None
        else:
            self.speed_limit_mps = (limit / 100.0 * self.limits.max_speed_mps) if percentage else float(limit)

    def mount_problem(self, x_m: float, y_m: float, yaw_rad: float) -> str:
        """Why a mount cannot be a scanner's on this robot ('' when it can): the bounds of the
        ``scanners.*.mount_*`` parameters hold for a mount from TF too."""
        bound = MAX_MOUNT_OFFSET_M
        if not all(math.isfinite(v) for v in (x_m, y_m, yaw_rad)):
            return "not finite"
        if abs(x_m) > bound or abs(y_m) > bound:
            return f"expected x and y within ±{bound:g} m of the robot centre (as the scanners.* parameters)"
        return ""

    def mount_acceptable(self, x_m: float, y_m: float, yaw_rad: float) -> bool:
        return not self.mount_problem(x_m, y_m, yaw_rad)

    def set_mount(self, index: int, x_m: float, y_m: float, yaw_rad: float) -> bool:
        """Scanner ``index``'s mount from TF (the parameters' mount is the fallback); True when it changed.
        A mount beyond the parameters' bounds raises ``ValueError`` (the mount in use stays)."""
        problem = self.mount_problem(float(x_m), float(y_m), float(yaw_rad))
        if problem:
            raise ValueError(f"scanner mount ({x_m:g}, {y_m:g} m, {yaw_rad:g} rad): {problem}")
        h = self.health[index]
        mount = (float(x_m), float(y_m), float(yaw_rad))
        if getattr(h, "mount", None) == mount:
            return False
        h.mount = mount
        if h.model is not None:
            if self.settings.scan_geometry == "urg04lx":
                yaw = mount[2]
            else:  # the model's axis is the middle beam of the message's layout
                yaw = mount[2] + h.angle_min_rad + 0.5 * (h.model.beam_count - 1) * h.model.angle_increment_rad  # type: ignore[attr-defined]  # set with the model, by on_scan
            h.model = replace(h.model, mount_x_m=mount[0], mount_y_m=mount[1], mount_yaw_rad=_wrap(yaw))
        return True

    def on_odometry(
        self,
        now_s: float,
        stamp_s: float,
        frame_id: str,
        x: float,
        y: float,
        heading_rad: float,
        speed_mps: float,
        turn_rate_radps: float,
    ) -> bool:
        """Store one odometry message; False (counted, and a fault that brakes the robot) when refused.

        A message is refused when its twist is beyond the limits (plus ``odom_speed_tolerance_mps`` /
        ``odom_turn_tolerance_radps``), above every speed (or outside the turn rates) commanded in the
        last ``odom_timeout_s``, or larger than its own pose change over the recent messages explains.
        A pose (or heading) that moved further than the twist explains is a jump: the message is kept
        as the new reference, but tracks are reset and the robot is held for ``reset_hold_s``."""
        expected = self.settings.odom_frame
        if expected and frame_id and frame_id != expected:
            self.refuse_odometry(now_s, "frame", f"frame_id {frame_id!r}, expected {expected!r}", fault=False)
            return False
        values = (stamp_s, x, y, heading_rad, speed_mps, turn_rate_radps)
        if not all(math.isfinite(v) for v in values):
            self.refuse_odometry(now_s, "not_finite", "a NaN or infinite value")
            return False
        if self.odometry is not None and stamp_s < self.odometry.stamp_s - 1e-9:
            self._time_jump(f"odometry stamp went back {self.odometry.stamp_s - stamp_s:.3f} s")
        elif self._odom_history and stamp_s < self._odom_history[-1].stamp_s - 1e-9:
            self._odom_history.clear()  # a refused message's stamp: nothing to compare with
        sample = Odometry(stamp_s, now_s, x, y, heading_rad, speed_mps, turn_rate_radps)
        problem = self._twist_problem(sample, now_s)
        jump = None
        if problem is None:
            problem, jump = self._pose_problem(sample)
        window = self.settings.odom_timeout_s
        self._odom_history = [o for o in self._odom_history if o.stamp_s >= stamp_s - window] + [sample]
        if jump:  # the pose is the new reference: tracks placed in the old one are wrong
            self._odom_history = [sample]
            self.refuse_odometry(now_s, "jump", problem[1], counted_as_refused=False)  # type: ignore[index]  # a jump has a problem
            self._reset_tracks(f"odometry: {problem[1]}")  # type: ignore[index]
            self.odometry = sample
            return True
        if problem is not None:
            self.refuse_odometry(now_s, problem[0], problem[1])
            return False
        self.odometry = sample
        return True

    def refuse_odometry(
        self, now_s: float, reason: str, detail: str, fault: bool = True, counted_as_refused: bool = True
    ) -> None:
        """Count a bad odometry message; a fault (all but a wrong frame) brakes the robot for ``reset_hold_s``."""
        key = reason if counted_as_refused else f"{reason} (kept, tracks reset)"
        self.odom_refused[key] = self.odom_refused.get(key, 0) + 1
        self.odom_problem = detail
        if fault:
            self.odom_fault = (now_s + max(self.settings.reset_hold_s, self.settings.cycle_period_s), detail)

    def _twist_problem(self, o: Odometry, now_s: float) -> tuple[str, str] | None:
        """Why the twist cannot be the robot's: beyond the limits, or not what was commanded."""
        s, lim = self.settings, self.limits
        v_tol, w_tol = s.odom_speed_tolerance_mps, s.odom_turn_tolerance_radps
        if abs(o.speed_mps) > lim.max_speed_mps + v_tol:
            return "limits", f"speed {o.speed_mps:.4g} m/s beyond the limit {lim.max_speed_mps:g} m/s"
        if abs(o.turn_rate_radps) > lim.max_turn_rate_radps + w_tol:
            return (
                "limits",
                f"turn rate {o.turn_rate_radps:.4g} rad/s beyond the limit {lim.max_turn_rate_radps:g} rad/s",
            )
        commanded = self._recent_commands(now_s)
        if commanded:
            v_high = max(c[1] for c in commanded)
            w_low, w_high = min(c[2] for c in commanded), max(c[2] for c in commanded)
            if o.speed_mps > v_high + v_tol:
                return "command", (
                    f"speed {o.speed_mps:.4g} m/s, but at most {v_high:.3f} m/s was commanded in the "
                    f"last {s.odom_timeout_s:g} s"
                )
            if not w_low - w_tol <= o.turn_rate_radps <= w_high + w_tol:
                return "command", (
                    f"turn rate {o.turn_rate_radps:.4g} rad/s, but {w_low:.3f} to {w_high:.3f} rad/s "
                    f"was commanded in the last {s.odom_timeout_s:g} s"
                )
        return None

    def _pose_problem(self, o: Odometry) -> tuple[tuple[str, str] | None, bool]:
        """Whether the pose change since the recent messages is what their twists explain: (problem, is a jump).
        Checked from the previous message (a jump) and from the oldest one kept (a twist that drifts off)."""
        history = self._odom_history
        if not history:
            return None, False
        s, lim = self.settings, self.limits
        for start in (len(history) - 1, 0):
            samples = history[start:] + [o]
            dx = dy = dh = 0.0
            slack_m = s.odom_pose_tolerance_m
            slack_rad = s.odom_heading_tolerance_rad
            travelled = twist_m = 0.0
            for a, b in zip(samples[:-1], samples[1:]):
                dt = b.stamp_s - a.stamp_s
                v, w = 0.5 * (a.speed_mps + b.speed_mps), 0.5 * (a.turn_rate_radps + b.turn_rate_radps)
                mid = a.heading_rad + 0.5 * _wrap(b.heading_rad - a.heading_rad)
                dx += (b.x - a.x) - v * dt * math.cos(mid)
                dy += (b.y - a.y) - v * dt * math.sin(mid)
                dh += _wrap(b.heading_rad - a.heading_rad - w * dt)
                slack_m += 0.5 * lim.max_accel_mps2 * dt * dt + 0.5 * abs(v) * dt * abs(
                    _wrap(b.heading_rad - a.heading_rad)
                )
                slack_rad += 0.5 * lim.max_turn_accel_radps2 * dt * dt
                travelled += math.hypot(b.x - a.x, b.y - a.y)
                twist_m += abs(v) * dt
            span = o.stamp_s - samples[0].stamp_s
            error = math.hypot(dx, dy)
            if error > slack_m:
                if travelled > twist_m:
                    return (
                        "jump",
                        f"pose moved {travelled:.3f} m in {span:.3f} s, its twist explains {twist_m:.3f} m",
                    ), True
                return ("pose", f"twist says {twist_m:.3f} m in {span:.3f} s, the pose moved {travelled:.3f} m"), False
            if abs(dh) > slack_rad:
                return ("jump", f"heading changed {dh:+.3f} rad more than its turn rate explains in {span:.3f} s"), True
        return None, False

    def _recent_commands(self, now_s: float) -> list[tuple[float, float, float]]:
        """Commands sent while driving in the last ``odom_timeout_s`` (and the one in effect before them)."""
        if not self._commands:
            return []
        start = now_s - self.settings.odom_timeout_s
        recent = [c for c in self._commands if c[0] >= start]
        older = [c for c in self._commands if c[0] < start]
        return ([older[-1]] if older else []) + recent

    def _record_command(self, command: Command, now_s: float, planned: bool = False) -> None:
        self.last_command, self.last_command_s = command, now_s
        if not self.active:
            self._commands = []
            self._commands_armed = False
            return
        self._commands_armed |= planned
        if self._commands_armed:
            start = now_s - 2.0 * self.settings.odom_timeout_s
            self._commands = [c for c in self._commands if c[0] >= start] + [
                (now_s, command.speed_mps, command.turn_rate_radps)
            ]

    def on_scan(
        self,
        index: int,
        now_s: float,
        stamp_s: float,
        frame_id: str,
        angle_min_rad: float,
        angle_increment_rad: float,
        ranges,
        range_min_m: float = 0.02,
        range_max_m: float = 5.6,
    ) -> bool:
        """Store one scan of scanner ``index``; returns whether a cycle is due now. A scan that cannot be
        read at all is refused (reason ``error``, with the exception's text) like any other bad scan."""
        h = self.health[index]
        try:
            ranges = np.asarray(ranges, dtype=float).reshape(-1)
            stamp_s, angle_min_rad, angle_increment_rad = (
                float(stamp_s),
                float(angle_min_rad),
                float(angle_increment_rad),
            )
            range_min_m, range_max_m = float(range_min_m), float(range_max_m)
            if h.expected_frame and frame_id != h.expected_frame:
                h.refuse("frame", f"frame_id {frame_id!r}, expected {h.expected_frame!r}")
                return False
            if not (math.isfinite(stamp_s) and math.isfinite(angle_min_rad) and math.isfinite(angle_increment_rad)):
                h.refuse("header", "a NaN or infinite stamp or angle")
                return False
            if angle_increment_rad < 0:  # clockwise scanner: store it counter-clockwise
                ranges = ranges[::-1]
                angle_min_rad, angle_increment_rad = (
                    angle_min_rad + (len(ranges) - 1) * angle_increment_rad,
                    -angle_increment_rad,
                )
            if h.model is None and not self._make_scanner_model(
                index, len(ranges), angle_min_rad, angle_increment_rad, range_min_m, range_max_m
            ):
                return False
            if not self._scan_fits_model(h, ranges, angle_min_rad, angle_increment_rad):
                return False
            return self._store_scan(h, now_s, stamp_s, ranges)
        except Exception as error:
            h.refuse("error", f"{type(error).__name__}: {error}")
            return False

    def _make_scanner_model(
        self,
        index: int,
        beams: int,
        angle_min_rad: float,
        angle_increment_rad: float,
        range_min_m: float,
        range_max_m: float,
    ) -> bool:
        """Scanner ``index``'s model from its first readable scan (counter-clockwise angles); False
        (and the scan refused) when the layout cannot be one."""
        h = self.health[index]
        setting = self.settings.scanners[index]
        problem = scan_layout_problem(beams, angle_increment_rad, range_min_m, range_max_m)
        if problem:
            h.refuse("layout", problem)
            return False
        n = beams
        mx, my, myaw = getattr(h, "mount", None) or (setting.mount_x_m, setting.mount_y_m, setting.mount_yaw_rad)
        try:
            h.model = ScannerModel(
                name=setting.name,
                mount_x_m=mx,
                mount_y_m=my,
                mount_yaw_rad=_wrap(myaw + angle_min_rad + 0.5 * (n - 1) * angle_increment_rad),
                beam_count=n,
                angle_increment_rad=float(angle_increment_rad),
                range_min_m=max(float(range_min_m), 0.0),
                range_max_m=float(range_max_m),
            )
        except ValueError as error:  # anything the scanner model refuses that the check above let through
            h.refuse("layout", str(error))
            return False
        h.angle_min_rad = angle_min_rad  # type: ignore[attr-defined]
        return True

    def _scan_fits_model(
        self, h: ScannerHealth, ranges: np.ndarray, angle_min_rad: float, angle_increment_rad: float
    ) -> bool:
        """Whether a scan has its scanner's beams and angles and few enough erroneous readings (else
        it is refused); sets the scanner's invalid fraction."""
        model = h.model
        assert model is not None
        expected_min = getattr(h, "angle_min_rad", model.angle_min_rad)
        if len(ranges) != model.beam_count:
            h.refuse("length", f"{len(ranges)} beams, expected {model.beam_count}")
            return False
        if (
            abs(angle_increment_rad - model.angle_increment_rad) > 1e-4
            or abs(_wrap(angle_min_rad - expected_min)) > 1e-3
        ):
            h.refuse(
                "angles",
                f"angle_min {angle_min_rad:.4f} / increment {angle_increment_rad:.6f} rad, expected "
                f"{expected_min:.4f} / {model.angle_increment_rad:.6f}",
            )
            return False
        with np.errstate(invalid="ignore"):
            erroneous = np.isnan(ranges) | (ranges <= 0.0)
        h.invalid_fraction = float(erroneous.mean()) if len(ranges) else 1.0
        if h.invalid_fraction > self.settings.max_invalid_fraction:
            h.refuse("invalid", f"{100 * h.invalid_fraction:.0f} % of the readings are NaN or zero")
            return False
        return True

    def _store_scan(self, h: ScannerHealth, now_s: float, stamp_s: float, ranges: np.ndarray) -> bool:
        """Keep an accepted scan for the next cycle; returns whether that cycle is due now."""
        if self.last_cycle_stamp_s is not None and stamp_s < self.last_cycle_stamp_s - 1e-9:
            self._time_jump(f"scan stamp went back {self.last_cycle_stamp_s - stamp_s:.3f} s")
        h.last_good_s = now_s
        h.good += 1
        waited_a_period = h.pending is not None  # this scanner delivered twice: the others are late, go on
        h.pending = (stamp_s, ranges)
        # Scans of one cycle lie within half a period of each other; an older one missed its cycle.
        window_s = 0.5 * self.settings.cycle_period_s
        for other in self.health:
            if other.pending is not None and other.pending[0] < stamp_s - window_s:
                other.pending = None
        if self._first_scan_s is None:
            self._first_scan_s = now_s
        live = set(self.live_scanners(now_s))
        if now_s - self._first_scan_s <= self.settings.scan_timeout_s + 1e-9:  # at start, wait for every scanner
            live |= {i for i, other in enumerate(self.health) if other.good == 0}
        return waited_a_period or all(self.health[i].pending is not None for i in live)

    def set_map(self, layer: StaticLayer) -> None:
        """A known map's static geometry (e.g. from a nav_msgs/OccupancyGrid), in the odometry frame."""
        self.map_layer = layer.finite()
        self.events.append(f"map: {len(self.map_layer)} static segments")

    def static_for(self, robot: RobotState) -> StaticLayer:
        """The map near the robot (a large map's part within the guard's reach: the same object while the
        robot stays among the same cells of its index, so its discs are sampled once) and the scans' static
        layer."""
        from viapath.guard import static_range_for

        reach = static_range_for(robot, self.limits, GUARD_DEFAULTS) + GUARD_DEFAULTS.static_spacing_m
        return self.map_layer.near(robot.position, reach).concatenate(self.static_now)

    def prepare_map(self, layer: StaticLayer) -> StaticLayer:
        """``layer`` with what the guard will ask of it each cycle made once, beside the control loop (its
        spatial index and its discs for the robot's radius); changes nothing of the core."""
        from viapath.guard import LONGEST_SAMPLED_M

        layer = layer.finite()
        o = self.odometry
        centre = np.zeros(2) if o is None else np.array([o.x, o.y])
        near = layer.near(centre, GUARD_DEFAULTS.static_range_m + GUARD_DEFAULTS.static_spacing_m)
        plain, _wide = near.split_wide(GUARD_DEFAULTS.max_coordinate_m, LONGEST_SAMPLED_M)
        plain.discs(self.settings.robot_radius_m, GUARD_DEFAULTS.static_spacing_m)
        return layer

    def _time_jump(self, why: str) -> None:
        self.tracker.reset()
        self.static_layer.reset()
        self.static_now = StaticLayer.empty()
        for h in self.health:
            h.pending = None
        self.odometry = None
        self._odom_history = []
        self._commands, self._commands_armed = [], False
        self.odom_fault = None
        self.last_cycle_stamp_s = None
        self.last_command_s = None
        self.hold_until_stamp_s = -math.inf  # set from the next cycle's stamp
        self.hold_reason = "a time jump backwards"
        self.events.append(
            f"time jump backwards ({why}): tracks and odometry reset, robot held for {self.settings.reset_hold_s:g} s"
        )

    def _reset_tracks(self, why: str) -> None:
        """The world frame moved under the tracks: forget them and hold the robot while they confirm again."""
        self.tracker.reset()
        self.hold_until_stamp_s = -math.inf
        self.hold_reason = "an odometry jump"
        self.events.append(f"{why}: tracks reset, robot held for {self.settings.reset_hold_s:g} s")

    def clock_jumped_back(self, why: str) -> None:
        """The node's own clock went back (e.g. /clock restarted): forget receipt times too."""
        for h in self.health:
            h.last_good_s = None
        self._time_jump(why)

    # -- state ---------------------------------------------------------------------------------
    def live_scanners(self, now_s: float) -> list[int]:
        timeout = self.settings.scan_timeout_s
        return [
            i
            for i, h in enumerate(self.health)
            if h.last_good_s is not None and now_s - h.last_good_s <= timeout + 1e-9
        ]

    def odometry_fresh(self, now_s: float) -> bool:
        return self.odometry is not None and now_s - self.odometry.received_s <= self.settings.odom_timeout_s + 1e-9

    def odometry_fault_active(self, now_s: float) -> bool:
        return self.odom_fault is not None and now_s < self.odom_fault[0]

    def odometry_trusted(self, now_s: float) -> bool:
        """Fresh and without a fault: only then is its twist the base of a command."""
        return self.odometry_fresh(now_s) and not self.odometry_fault_active(now_s)

    def _stop_reasons(self, now_s: float) -> list[str]:
        reasons = []
        if not self.active:
            reasons.append("inactive")
        if self.path is None:
            reasons.append(PATH_CLEARED if self.path_cleared else NO_PATH)
        if not self.odometry_fresh(now_s):
            reasons.append(
                f"no odometry for {self.settings.odom_timeout_s:.2f} s"
                if self.odometry is not None or any(h.good for h in self.health)
                else "no odometry yet"
            )
        if self.odometry_fault_active(now_s):
            reasons.append(f"odometry fault: {self.odom_fault[1]}")  # type: ignore[index]  # active: set
        if not self.live_scanners(now_s):
            reasons.append(
                f"no scan for {self.settings.scan_timeout_s:g} s" if any(h.good for h in self.health) else "no scan yet"
            )
        return reasons

    def _measured(self) -> tuple[float, float, float]:
        """Speed, turn rate and the time over which they may change now: the odometry's while trusted
        (one cycle), else what was last commanded (the time since that command, at most one cycle)."""
        dt = self.settings.cycle_period_s
        if self.odometry is not None and self.odometry_trusted(self._now_s):
            return self.odometry.speed_mps, self.odometry.turn_rate_radps, dt
        since = dt if self.last_command_s is None else min(max(self._now_s - self.last_command_s, 0.0), dt)
        return self.last_command.speed_mps, self.last_command.turn_rate_radps, since

    def _bases(self) -> tuple[float, float, float, float, float]:
        """(speed to ramp down from, speed to ramp up from, turn rates ramped from (low, high), dt).
        Slowing down ramps from the lower of the measured and the last commanded speed, and a turn rate
        may go toward zero from either: a measurement can never hold the robot in motion (or spinning)
        that was not commanded."""
        lim = self.limits
        v_meas, w_meas, dt = self._measured()
        v_meas = min(max(v_meas, 0.0), lim.max_speed_mps)
        last = self.last_command  # a stop before anything was commanded
        v_down = min(v_meas, last.speed_mps)
        w_low, w_high = min(w_meas, last.turn_rate_radps), max(w_meas, last.turn_rate_radps)
        return v_down, v_meas, w_low, w_high, dt

    def brake_command(self) -> Command:
        """One cycle's hardest braking within the limits, from the measured (or last commanded) motion."""
        v_down, _, w_low, w_high, dt = self._bases()
        v_new = max(0.0, v_down - self.limits.max_accel_mps2 * dt)
        dw = self.limits.max_turn_accel_radps2 * dt
        w = 0.0 if w_low <= 0.0 <= w_high else (w_low if w_low > 0.0 else w_high)  # the one nearer zero
        w_new = 0.0 if abs(w) <= dw else w - math.copysign(dw, w)
        return self._limit(Command(v_new, w_new))

    def _limit(self, command: Command, speed_cap_mps: float | None = None) -> Command:
        v, w = float(command.speed_mps), float(command.turn_rate_radps)
        if not (math.isfinite(v) and math.isfinite(w)):
            v, w = 0.0, 0.0
        lim = self.limits
        v_down, v_up, w_low, w_high, dt = self._bases()
        v = min(max(v, 0.0), lim.max_speed_mps)
        if speed_cap_mps is not None:
            v = min(v, speed_cap_mps)
        v = min(max(v, v_down - lim.max_accel_mps2 * dt), v_up + lim.max_accel_mps2 * dt)
        v = min(max(v, 0.0), lim.max_speed_mps)
        w = min(max(w, w_low - lim.max_turn_accel_radps2 * dt), w_high + lim.max_turn_accel_radps2 * dt)
        w = min(max(w, -lim.max_turn_rate_radps), lim.max_turn_rate_radps)
        return Command(float(v), float(w))

    def watchdog(self, now_s: float) -> CycleResult | None:
        """Called every cycle period: brakes when inputs are stale; None when the scan cycles run (a cycle
        in the last ``WATCHDOG_QUIET_PERIODS`` periods: it braked for the same reasons itself)."""
        self._now_s = now_s
        reasons = self._stop_reasons(now_s)
        if not reasons:
            return None
        since = None if self.last_cycle_s is None else now_s - self.last_cycle_s
        if since is not None and 0.0 <= since < WATCHDOG_QUIET_PERIODS * self.settings.cycle_period_s:
            return None
        command = self.brake_command()
        self._record_command(command, now_s)
        mode = "stopped" if command.speed_mps == 0.0 and command.turn_rate_radps == 0.0 else "braking"
        result = CycleResult(command, mode, reasons, now_s, robot_pose=self._pose_at(now_s))
        result.status = self._status(result, now_s)
        self.last_result = result
        return result

    def fault_result(self, now_s: float, why: str) -> CycleResult:
        """A cycle that could not run (``why``): one cycle's braking, with the reason in the status."""
        self._now_s = now_s
        self.last_cycle_s = now_s
        self.events.append(why)
        command = self.brake_command()
        self._record_command(command, now_s)
        mode = "stopped" if command.speed_mps == 0.0 and command.turn_rate_radps == 0.0 else "braking"
        result = CycleResult(command, mode, self._stop_reasons(now_s) + [why], now_s, robot_pose=self._pose_at(now_s))
        result.status = self._status(result, now_s)
        self.last_result = result
        return result

    def note_alive(self, wall_s: float) -> None:
        """An input arrived, or the node's clock moved, at wall time ``wall_s`` (a monotonic clock)."""
        self._alive_wall_s = wall_s

    def wall_watchdog(self, wall_s: float) -> CycleResult | None:
        """Called every cycle period on the wall clock: when nothing arrived and the node's clock did not
        move for ``wall_timeout_s`` (with ``use_sim_time``, /clock stopped too, so :meth:`watchdog` is not
        called), brake from the last command; None otherwise."""
        timeout = self.settings.wall_timeout_s
        if self._alive_wall_s is None or wall_s - self._alive_wall_s <= timeout + 1e-9:
            return None
        lim, dt = self.limits, self.settings.cycle_period_s
        last = self.last_command
        dw = lim.max_turn_accel_radps2 * dt
        w = last.turn_rate_radps
        command = Command(
            max(0.0, min(last.speed_mps, lim.max_speed_mps) - lim.max_accel_mps2 * dt),
            0.0
            if abs(w) <= dw
            else min(max(w - math.copysign(dw, w), -lim.max_turn_rate_radps), lim.max_turn_rate_radps),
        )
        self._record_command(command, self._now_s)
        mode = "stopped" if command.speed_mps == 0.0 and command.turn_rate_radps == 0.0 else "braking"
        reasons = self._stop_reasons(self._now_s) + [
            f"no input and no clock for {wall_s - self._alive_wall_s:.2f} s of wall time"
        ]
        result = CycleResult(command, mode, reasons, self._now_s, robot_pose=self._pose_at(self._now_s))
        result.status = self._status(result, self._now_s)
        result.status["planner"]["source"] = "wall watchdog"
        self.last_result = result
        return result

    def _pose_at(self, stamp_s: float) -> np.ndarray | None:
        o = self.odometry
        if o is None:
            return None
        dt = min(max(stamp_s - o.stamp_s, -0.5), 0.5)  # extrapolate at most half a second
        heading = o.heading_rad + o.turn_rate_radps * dt
        mid = o.heading_rad + 0.5 * o.turn_rate_radps * dt
        return np.array(
            [o.x + o.speed_mps * dt * math.cos(mid), o.y + o.speed_mps * dt * math.sin(mid), _wrap(heading)]
        )

    def blind_speed_cap(self, live: list[int]) -> tuple[float | None, list[tuple[float, float]]]:
        """Speed cap and blind sectors (robot frame) with only the ``live`` scanners (module notes)."""
        if len(live) == len(self.health):
            return None, []
        models = tuple(self.health[i].model for i in live if self.health[i].model is not None)
        if not models:
            return 0.0, [(-math.pi, math.pi)]
        region = blind_region(models, self.settings.robot_radius_m)
        ahead = np.abs(region.angles_rad) <= FORWARD_CONE_RAD
        if np.any(region.blind_depth_m[ahead] > self.settings.robot_radius_m + 0.01):
            return 0.0, region.sectors_rad
        s = self.settings
        reach_s = s.blind_clearance_m / s.blind_person_speed_mps if s.blind_person_speed_mps > 0 else math.inf
        cap = max(0.0, self.limits.max_accel_mps2 * (reach_s - s.cycle_period_s))
        return cap, region.sectors_rad

    # -- the cycle -----------------------------------------------------------------------------
    def cycle(self, now_s: float) -> CycleResult:
        """Perceive and plan on the pending scans; the command is always finite and within the limits."""
        started = time.perf_counter()
        self._now_s = self.last_cycle_s = now_s
        live = self.live_scanners(now_s)
        used = [i for i in live if self.health[i].pending is not None]
        stamp = max(self.health[i].pending[0] for i in used) if used else now_s  # type: ignore[index]  # used: pending
        reasons = self._stop_reasons(now_s)
        scans = [(self.health[i].model, self.health[i].pending[1]) for i in used]  # type: ignore[index]
        for h in self.health:
            h.pending = None
        if self.hold_until_stamp_s == -math.inf:
            self.hold_until_stamp_s = stamp + self.settings.reset_hold_s
        if not used:
            reasons.append("no scan in this cycle")
        pose = self._pose_at(stamp)
        obstacles = Obstacles.empty()
        perception_ms = None
        if used and pose is not None:
            obstacles, perception_ms = self._perceive(stamp, pose, scans)
        cap, sectors = self.blind_speed_cap(live)
        decision, plan_ms = (None, None) if reasons else self._plan(stamp, pose, obstacles, reasons)
        if decision is None:
            command = self.brake_command()
            mode = "braking"
        else:
            command, mode = self._drive(decision, stamp, cap, live, reasons)
        if command.speed_mps == 0.0 and command.turn_rate_radps == 0.0 and mode == "braking":
            mode = "stopped"
        self._record_command(command, now_s, planned=decision is not None)
        elapsed = (time.perf_counter() - started) * 1e3
        self.cycle_times_ms.append(elapsed)
        if len(self.cycle_times_ms) > 1000:
            del self.cycle_times_ms[:-100]
        result = CycleResult(
            command,
            mode,
            reasons,
            stamp,
            decision,
            obstacles,
            pose,
            sectors,
            cap,
            elapsed,
            perception_time_ms=perception_ms,
            plan_time_ms=plan_ms,
            static=self.static_planned if decision is not None else self.static_now,
        )
        result.status = self._status(result, now_s)
        self.last_result = result
        return result

    def _perceive(self, stamp: float, pose: np.ndarray, scans: list) -> tuple[Obstacles, float]:
        """Detect in this cycle's scans, track, update the static layer: (tracked obstacles, time in ms)."""
        perceiving = time.perf_counter()
        detections = detect([m for m, _ in scans], [r for _, r in scans], self.detector_params).transformed(pose)
        if self.tracker.time_s is not None and stamp < self.tracker.time_s:
            self._time_jump("scan stamp before the tracker's time")
            self.hold_until_stamp_s = stamp + self.settings.reset_hold_s
        self.tracker.step(stamp, detections.centres, detections.position_sigma_m, detections.radii_m)
        # (the static layer the scans showed up to last cycle: a tentative track on it is not reported early)
        obstacles = self.tracker.people(pose[:2], self.static_now).finite()
        self.static_now = self.static_layer.update(
            stamp, pose, [r for _, r in scans], *self.tracker.explaining(), scanners=[m for m, _ in scans]
        )
        perception_ms = (time.perf_counter() - perceiving) * 1e3
        self.last_cycle_stamp_s = stamp
        return obstacles, perception_ms

    def _plan(self, stamp: float, pose, obstacles: Obstacles, reasons: list[str]):
        """The planner's decision and its time in ms; (None, None) with the error in ``reasons`` when it fails."""
        o = self.odometry
        robot = RobotState(
            pose[:2].copy(),  # no stop reason: pose and odometry known
            float(pose[2]),
            min(max(o.speed_mps, 0.0), self.limits.max_speed_mps),  # type: ignore[union-attr]
            o.turn_rate_radps,  # type: ignore[union-attr]
            self.settings.robot_radius_m,
        )
        static = self.static_planned = self.static_for(robot)
        try:
            planning = time.perf_counter()
            decision = self.planner.plan(Observation(stamp, robot, obstacles, static))
            plan_ms = (time.perf_counter() - planning) * 1e3
        except Exception as error:
            reasons.append(f"planner error: {type(error).__name__}: {error}")
            self.events.append(reasons[-1])
            return None, None
        return decision, plan_ms

    def _drive(self, decision, stamp: float, cap: float | None, live: list[int], reasons: list[str]):
        """(command, mode) from the planner's decision: within the speed limit and the blind-scanner
        cap, a brake while holding after a reset; the goal noted."""
        limit = (
            cap
            if self.speed_limit_mps is None
            else (self.speed_limit_mps if cap is None else min(cap, self.speed_limit_mps))
        )
        command = self._limit(decision.command, limit)
        mode = "driving" if cap is None else "degraded"
        if cap is not None:
            reasons.append(
                "scanner(s) silent: "
                + ", ".join(self.settings.scanners[i].name for i in range(len(self.health)) if i not in live)
                + f"; speed capped at {cap:.2f} m/s"
            )
        if decision.plan.status == "goal":
            self.goal_reached = True
            mode = "goal"
        if self.hold_until_stamp_s is not None and stamp < self.hold_until_stamp_s:
            command = self.brake_command()
            mode = "braking"
            reasons.append(f"holding after {self.hold_reason}")
        elif self.hold_until_stamp_s is not None:
            self.hold_until_stamp_s = None
        return command, mode

    def stop_command(self) -> Command:
        self._record_command(Command.stop(), self._now_s)
        return self.last_command

    # -- reporting -----------------------------------------------------------------------------
    def _status(self, result: CycleResult, now_s: float) -> dict[str, dict[str, str]]:
        out: dict[str, dict[str, str]] = {}
        plan = result.decision.plan if result.decision is not None else None
        planner = {
            "mode": result.mode,
            "reasons": "; ".join(result.reasons),
            "planner": self.settings.planner_name,
            "command_speed_mps": f"{result.command.speed_mps:.4f}",
            "command_turn_rate_radps": f"{result.command.turn_rate_radps:.4f}",
            "tracks": str(len(result.obstacles)),
            "stamp_s": f"{result.stamp_s:.6f}",
            "source": "cycle" if result.cycle_time_ms is not None else "watchdog",
            "cycle_time_ms": f"{result.cycle_time_ms:.3f}" if result.cycle_time_ms is not None else "",
        }
        for key in ("perception_time_ms", "plan_time_ms"):
            if getattr(result, key) is not None:
                planner[key] = f"{getattr(result, key):.4f}"
        if plan is not None:
            from viapath.sim.metrics import plan_side

            planner.update(
                plan_status=plan.status,
                plan_speed_mps=f"{plan.speed_mps:.4f}",
                plan_side=str(plan_side(plan.waypoints)),
                via_points=str(len(plan.via_points)),
                subgoal_index=str(plan.subgoal_index),
            )
        if plan is not None and len(plan.via_points):
            planner["via_xy"] = ";".join(f"{x:.4f},{y:.4f}" for x, y in np.asarray(plan.via_points).reshape(-1, 2))
        o = result.obstacles
        if len(o):  # id,x,y,vx,vy,radius per confirmed track (tests and the simulator read them back)
            planner["tracks_xyv"] = ";".join(
                f"{i},{p[0]:.4f},{p[1]:.4f},{v[0]:.4f},{v[1]:.4f},{r:.3f}"
                for i, p, v, r in zip(o.ids.tolist(), o.positions, o.velocities, o.radii_m.tolist(), strict=True)
            )
        if result.speed_cap_mps is not None:
            planner["speed_cap_mps"] = f"{result.speed_cap_mps:.4f}"
        if self.paths_refused:
            planner["paths_refused"] = str(self.paths_refused)
        if self.events:
            planner["events"] = " | ".join(self.events[-3:])
        out["planner"] = planner
        out["way"] = self._way_status(result)
        if plan is not None and "shield" in plan.extras:
            shield = plan.extras["shield"]
            out["shield"] = (
                {k: str(v) for k, v in shield.items()} if isinstance(shield, dict) else {"shield": str(shield)}
            )
            intervened = bool(shield.get("intervened")) if isinstance(shield, dict) else False
            planner["shield_intervened"] = str(int(intervened))
            planner["shield_mode"] = str(
                getattr(getattr(self.planner, "shield", None), "config", None) and self.planner.shield.config.mode
            )
        live = set(self.live_scanners(now_s))
        for i, (h, s) in enumerate(zip(self.health, self.settings.scanners, strict=True)):
            out[f"scanner {s.name}"] = {
                "state": "ok" if i in live else ("silent" if h.good else "no scan yet"),
                "topic": s.topic,
                "good_scans": str(h.good),
                "refused": ", ".join(f"{k}: {v}" for k, v in sorted(h.refused.items())) or "none",
                "last_problem": h.last_problem,
                "invalid_fraction": f"{h.invalid_fraction:.3f}",
                "mount_source": "tf" if h.mount is not None else "parameters",
            }
        out["odometry"] = {
            "state": "fault" if self.odometry_fault_active(now_s) else "ok" if self.odometry_fresh(now_s) else "stale",
            "refused": ", ".join(f"{k}: {v}" for k, v in sorted(self.odom_refused.items())) or "none",
            "last_problem": self.odom_problem,
        }
        times = sorted(self.cycle_times_ms[-100:])  # the last 100 cycles (np.percentile costs 0.7 ms a call)
        out["timing"] = {
            "cycle_time_ms": f"{result.cycle_time_ms:.3f}" if result.cycle_time_ms is not None else "",
            "cycle_time_p50_ms": f"{times[len(times) // 2]:.3f}" if times else "",
            "cycle_time_p99_ms": f"{times[min(len(times) - 1, int(0.99 * len(times)))]:.3f}" if times else "",
        }
        return out

    def _way_status(self, result: CycleResult) -> dict[str, str]:
        """Whether static geometry closes the way (the plan's status ``blocked``, also under a guard's brake):
        state ``blocked`` with where the robot waits, else ``ok``. A cycle without a plan changes nothing."""
        plan = result.decision.plan if result.decision is not None else None
        if plan is None:
            last = (self.last_result.status if self.last_result is not None else {}).get("way")
            if self.blocked_since_s is not None and last is not None and self.path is not None and self.active:
                return dict(last)  # a watchdog tick while blocked (inputs late): the last plan's word stands
            self.blocked_since_s = None
            return {"state": "ok", "message": "no plan this cycle", "blocked": "0"}
        if "blocked" not in (plan.status, plan.extras.get("guard_planner_status")):
            self.blocked_since_s = None
            return {"state": "ok", "message": "the way is open", "blocked": "0"}
        if self.blocked_since_s is None:
            self.blocked_since_s = result.stamp_s
        x, y = (float(v) for v in np.asarray(plan.target, dtype=float)[:2])
        why = str(plan.extras.get("blocked", "static geometry closes the way"))
        frame = self.settings.odom_frame or "odom"
        return {
            "state": "blocked",
            "message": f"blocked: {why}; the robot waits at ({x:.2f}, {y:.2f}) m in {frame}",
            "blocked": "1",
            "wait_x_m": f"{x:.3f}",
            "wait_y_m": f"{y:.3f}",
            "blocked_for_s": f"{result.stamp_s - self.blocked_since_s:.1f}",
        }


def parse_tracks(text: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(ids, positions, velocities, radii) from a status' ``tracks_xyv`` value."""
    rows = [tuple(float(v) for v in item.split(",")) for item in text.split(";") if item]
    a = np.array(rows, dtype=float).reshape(-1, 6)
    return a[:, 0].astype(int), a[:, 1:3], a[:, 3:5], a[:, 5]


def parse_points(text: str) -> np.ndarray:
    return np.array([[float(v) for v in item.split(",")] for item in text.split(";") if item], dtype=float).reshape(
        -1, 2
    )


def severity(result: CycleResult) -> int:
    """Diagnostic level: 0 OK (driving, goal), 1 WARN (degraded, waiting), 2 ERROR (braking or stopped for a fault)."""
    if result.mode in ("driving", "goal"):
        return 0
    if result.mode == "degraded" or result.reasons in ([NO_PATH], [PATH_CLEARED], ["inactive"]):
        return 1
    return 2
