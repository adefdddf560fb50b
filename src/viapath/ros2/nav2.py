"""The node as Nav2's controller server: the ``follow_path`` action, ``speed_limit``, TF, costmap clearing.

Source: DESIGN §12; Nav2's controller server (Kilted) as documented: a lifecycle node serving
``nav2_msgs/action/FollowPath`` (goal a ``nav_msgs/Path``; feedback ``distance_to_goal`` and
``speed``; result ``error_code`` / ``error_msg`` with the action's codes), re-sent the path about once
a second by the behaviour tree (a preempt: the new path replaces the old one without a stop, and the
old goal ends aborted with an empty result, as Nav2's ``SimpleActionServer`` does), honouring
``nav2_msgs/SpeedLimit``, and its progress checker (the robot must move ``progress_radius_m`` within
``progress_patience_s``). TF as REP 105 (``map → odom → base_link``) from ``/tf`` and ``/tf_static``.

What we chose:
* A goal's path is moved into the odometry frame with the latest ``path frame → odom`` transform
  and simplified (Douglas-Peucker, ``path_simplify_m``) to the subgoals the planner heads for; a path
  of one pose starts at the robot. Empty, non-finite or degenerate paths end with INVALID_PATH at
  once. A missing transform is waited for up to ``failure_tolerance_s`` (the node's clock), then
  TF_ERROR.
* A re-sent path equal to the running one (within 1 mm) keeps the planner as it is; a changed one
  starts the planner on it from the robot's current motion (the command stays within one cycle's
  acceleration of the measured speed, so the robot does not stop). The progress check carries over.
* Success: the planner reports the goal reached (within ``goal_tolerance_m``). Then, and on cancel,
  the path is dropped and the cycles brake the robot to rest within its limits.
* No command can be computed (inputs stale: scans, odometry) for ``failure_tolerance_s`` while a
  goal runs: NO_VALID_CONTROL. No progress: FAILED_TO_MAKE_PROGRESS. Deactivation: the robot is
  stopped and the goal aborted (UNKNOWN, "controller deactivated"); goals are refused while inactive.
* A goal is held in the action's ACCEPTED state while it runs and executed only as it ends (its
  final state and result at once): rclpy's events executor resumes a coroutine that awaits the end
  of a goal without pause, which kept a core busy. Feedback flows meanwhile.
* The costmap-clearing service Nav2's behaviour tree calls on the controller's costmap is answered
  (there is no costmap; the tracks are not touched) and counted.
* Scanner mounts: ``base_frame → scanner frame`` from ``/tf_static`` (or ``/tf``) when there, else
  the ``scanners.*`` parameters.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from viapath.ros2.tf import TransformBuffer, apply


@dataclass
class _Goal:
    handle: Any  # rclpy's ServerGoalHandle
    future: object
    request_path: object
    accepted_s: float
    set: bool = False  # the path is in the core
    checkpoint: tuple[float, float, float] | None = None  # x, y, node time
    stale_since_s: float | None = None
    extra: dict = field(default_factory=dict)


class Nav2Interface:
    """Owned by the node in ``interface: nav2``; everything runs in the node's executor thread."""

    def __init__(self, node: Any) -> None:
        from viapath.ros2 import interfaces

        interfaces.load(progress=lambda text: node.get_logger().info(text))
        from nav2_msgs.action import FollowPath
        from nav2_msgs.msg import SpeedLimit
        from nav2_msgs.srv import ClearEntireCostmap
        from rclpy.action import ActionServer, CancelResponse, GoalResponse
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from tf2_msgs.msg import TFMessage

        self.node = node
        self.core = node.core
        self.s = node.core.settings
        self.FollowPath = FollowPath
        self.Result = FollowPath.Result
        self.buffer = TransformBuffer()
        self.goal: _Goal | None = None
        self.mounts_done = not self.s.use_tf
        self.clear_calls = 0
        self.finished: list[tuple[str, int, str]] = []
        self._subs = []
        self._GoalResponse, self._CancelResponse = GoalResponse, CancelResponse
        self._outcomes: dict[bytes, tuple[str, object]] = {}
        self.server = ActionServer(
            node,
            FollowPath,
            self.s.follow_path_action,
            self._execute,
            goal_callback=self._on_goal,
            handle_accepted_callback=self._on_accepted,
            cancel_callback=lambda handle: CancelResponse.ACCEPT,
        )
        self._subs.append(node.create_subscription(SpeedLimit, self.s.speed_limit_topic, self._on_speed_limit, 10))
        self.service = node.create_service(ClearEntireCostmap, self.s.clear_costmap_service, self._on_clear)
        if self.s.use_tf:
            dynamic = QoSProfile(
                depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE
            )
            static = QoSProfile(
                depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
            )
            self._subs.append(node.create_subscription(TFMessage, "/tf", lambda m: self._on_tf(m, False), dynamic))
            self._subs.append(node.create_subscription(TFMessage, "/tf_static", lambda m: self._on_tf(m, True), static))

    def destroy(self) -> None:
        self._finish_goal("abort", self.Result.UNKNOWN, "controller cleaned up")
        for sub in self._subs:
            self.node.destroy_subscription(sub)
        self._subs = []
        self.node.destroy_service(self.service)
        self.server.destroy()

    # -- inputs ------------------------------------------------------------------------------
    def _on_tf(self, msg, static: bool) -> None:
        from viapath.ros2 import convert

        for t in msg.transforms:
            q, p = t.transform.rotation, t.transform.translation
            self.buffer.set(
                t.header.frame_id,
                t.child_frame_id,
                convert.stamp_seconds(t.header.stamp),
                float(p.x),
                float(p.y),
                convert.yaw_from_quaternion(q.x, q.y, q.z, q.w),
                static=static,
            )
        if not self.mounts_done:
            self.resolve_mounts()

    def resolve_mounts(self) -> None:
        """Each scanner's mount from TF (``base_frame → frame_id``), once found."""
        done = True
        for index, scanner in enumerate(self.s.scanners):
            if not scanner.frame_id:
                continue
            pose = self.buffer.lookup(self.s.base_frame, scanner.frame_id)
            if pose is None:
                done = False
                continue
            if self.core.set_mount(index, *pose):
                self.node.get_logger().info(
                    f"scanner {scanner.name}: mount from TF ({pose[0]:.3f}, {pose[1]:.3f} m, {pose[2]:.3f} rad)"
                )
        self.mounts_done = done

    def _on_speed_limit(self, msg) -> None:
        self.core.set_speed_limit(float(msg.speed_limit), bool(msg.percentage))

    def _on_clear(self, request, response):
        self.clear_calls += 1
        return response

    # -- goals -------------------------------------------------------------------------------
    def _on_goal(self, request):
        return self._GoalResponse.ACCEPT if self.core.active else self._GoalResponse.REJECT

    def _path_in_odom(self, msg) -> tuple[int, str, np.ndarray | None]:
        """(error code, message, waypoints in the odometry frame); code NONE with None: wait (TF)."""
        R = self.Result
        points = np.array([[p.pose.position.x, p.pose.position.y] for p in msg.poses], dtype=float).reshape(-1, 2)
        if len(points) == 0:
            return R.INVALID_PATH, "empty path", None
        if not np.isfinite(points).all():
            return R.INVALID_PATH, "path with NaN or infinite coordinates", None
        frame = msg.header.frame_id or (msg.poses[0].header.frame_id if msg.poses else "")
        target = self.s.odom_frame
        if frame and target and frame.lstrip("/") != target.lstrip("/"):
            if not self.s.use_tf:
                return R.TF_ERROR, f"path in frame {frame!r}, odometry in {target!r}, and use_tf is off", None
            pose = self.buffer.lookup(target, frame)
            if pose is None:
                return R.NONE, f"no transform {frame} -> {target} yet", None
            points = np.array([apply(pose, x, y) for x, y in points], dtype=float).reshape(-1, 2)
        from viapath.ros2.core import simplify_polyline

        points = simplify_polyline(points, self.s.path_simplify_m)
        if len(points) == 1:
            o = self.core.odometry
            if o is None:
                return R.NONE, "a path of one pose: waiting for odometry", None
            points = np.vstack([[o.x, o.y], points])
        if np.hypot(*(points[-1] - points[0])) < 1e-6 and len(points) == 2:
            points = points[1:]
            o = self.core.odometry
            if o is None:
                return R.NONE, "waiting for odometry", None
            points = np.vstack([[o.x, o.y], points])
        return R.NONE, "", points

    def _on_accepted(self, handle) -> None:
        """A new goal: checked, then it replaces the running one. Its execution (the action's
        EXECUTING state and result) is started only when it ends, by :meth:`_end`: a goal
        waiting in a coroutine would be resumed without pause by rclpy's events executor."""
        goal = _Goal(handle, None, handle.request.path, self.node._now_s())
        code, message, points = self._path_in_odom(goal.request_path)
        if code != self.Result.NONE:
            self._end(goal, "abort", code, message)
            return
        previous = self.goal
        if previous is not None:
            goal.checkpoint = previous.checkpoint  # a preempt is no fresh start for the progress check
            self._finish_goal("abort", self.Result.NONE, "preempted by a new path", keep_path=True)
        self.goal = goal
        if points is not None:
            self._use_path(goal, points)

    def _end(self, goal: _Goal, outcome: str, code: int, message: str) -> None:
        self.finished.append((outcome, int(code), message))
        self._outcomes[bytes(goal.handle.goal_id.uuid)] = (outcome, self._result(code, message))
        goal.handle.execute()

    def _execute(self, handle):
        """Runs once a goal has ended: its final state and result."""
        outcome, result = self._outcomes.pop(
            bytes(handle.goal_id.uuid), ("abort", self._result(self.Result.UNKNOWN, ""))
        )
        if handle.is_active:
            {"succeed": handle.succeed, "canceled": handle.canceled}.get(outcome, handle.abort)()
        return result

    def _use_path(self, goal: _Goal, points: np.ndarray) -> bool:
        try:
            if not self.core.same_path(points):
                self.core.set_path(points)
        except ValueError as error:
            self._finish_goal("abort", self.Result.INVALID_PATH, f"path refused: {error}")
            return False
        goal.set = True
        return True

    def _result(self, code: int, message: str):
        result = self.Result()
        result.error_code = int(code)
        result.error_msg = message
        return result

    def _finish_goal(self, outcome: str, code: int, message: str, keep_path: bool = False) -> None:
        goal, self.goal = self.goal, None
        if goal is None:
            return
        if not keep_path:
            self.core.clear_path()
        self.core.events.append(f"follow_path: {outcome} ({code}{': ' + message if message else ''})")
        self._end(goal, outcome, code, message)

    def deactivated(self) -> None:
        self._finish_goal("abort", self.Result.UNKNOWN, "controller deactivated")

    def supervise(self, result, now_s: float) -> None:
        """After each cycle or watchdog tick: cancel, pending paths, success, progress, failures, feedback."""
        goal = self.goal
        if goal is None:
            return
        R = self.Result
        if goal.handle.is_cancel_requested:
            self._finish_goal("canceled", R.NONE, "canceled")
            return
        if not goal.set:
            code, message, points = self._path_in_odom(goal.request_path)
            if code != R.NONE:
                self._finish_goal("abort", code, message)
                return
            if points is None:
                if now_s - goal.accepted_s > self.s.failure_tolerance_s:
                    self._finish_goal("abort", R.TF_ERROR, message)
                return
            if not self._use_path(goal, points):
                return
        if self.core.goal_reached:
            self._finish_goal("succeed", R.NONE, "")
            return
        o = self.core.odometry
        if o is not None:
            if (
                goal.checkpoint is None
                or math.hypot(o.x - goal.checkpoint[0], o.y - goal.checkpoint[1]) >= self.s.progress_radius_m
            ):
                goal.checkpoint = (o.x, o.y, now_s)
            elif now_s - goal.checkpoint[2] > self.s.progress_patience_s:
                self._finish_goal(
                    "abort",
                    R.FAILED_TO_MAKE_PROGRESS,
                    f"moved less than {self.s.progress_radius_m:g} m in {self.s.progress_patience_s:g} s",
                )
                return
        stale = (
            result is not None
            and result.decision is None
            and any(r.startswith(("no odometry", "no scan")) for r in result.reasons)
        )
        if stale:
            goal.stale_since_s = now_s if goal.stale_since_s is None else goal.stale_since_s
            if now_s - goal.stale_since_s > self.s.failure_tolerance_s:
                self._finish_goal("abort", R.NO_VALID_CONTROL, "no command: " + "; ".join(result.reasons))
                return
        elif result is not None and result.decision is not None:
            goal.stale_since_s = None
        if result is not None and result.decision is not None:
            feedback = self.FollowPath.Feedback()
            distance = self.core.distance_to_goal()
            feedback.distance_to_goal = float(distance if distance is not None else 0.0)
            feedback.speed = float(o.speed_mps if o is not None else 0.0)
            goal.handle.publish_feedback(feedback)


def make_nav2_interface_class():
    """The interface's class, for the node class made once rclpy is there (the interface imports rclpy
    and the Nav2 messages only when an instance is made)."""
    return Nav2Interface
