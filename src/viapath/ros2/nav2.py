"""The node as Nav2's controller server: the ``follow_path`` action, ``speed_limit``, TF, costmap clearing.

Source: docs/design.md §12; Nav2's controller server (Kilted) as documented: a lifecycle node serving
``nav2_msgs/action/FollowPath`` (goal a ``nav_msgs/Path``; feedback ``distance_to_goal`` and
``speed``; result ``error_code`` / ``error_msg`` with the action's codes), re-sent the path about once
a second by the behaviour tree (a preempt: the new path replaces the old one without a stop, and the
old goal ends aborted with an empty result, as Nav2's ``SimpleActionServer`` does), honouring
``nav2_msgs/SpeedLimit``, and its progress checker (the robot must move ``progress_radius_m`` within
``progress_patience_s``). TF as REP 105 (``map → odom → base_link``) from ``/tf`` and ``/tf_static``.

What we chose:
* A goal request is taken as arrays (:mod:`viapath.ros2.lean`): a path of 100 000 poses costs no Python object
  per pose, which would hold the interpreter (and the control loop) for seconds.
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

from viapath.path_simplify import simplify_polyline
from viapath.ros2.lean import PathArrays, lean_action_server_class, lean_goal_request_type
from viapath.ros2.tf import TransformBuffer


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
        from rclpy.action import CancelResponse, GoalResponse
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from tf2_msgs.msg import TFMessage

        self.node = node
        self.core = node.core
        self.s = node.core.settings
        self.FollowPath = FollowPath
        self.Result = FollowPath.Result
        # A dynamic transform older than failure_tolerance_s is stale: a goal waits for a fresh one as long.
        self.buffer = TransformBuffer(max_age_s=self.s.failure_tolerance_s)
        self.goal: _Goal | None = None
        self.mounts_done = not self.s.use_tf
        self.finished: list[tuple[str, int, str]] = []
        self._subs = []
        self._GoalResponse = GoalResponse
        self._outcomes: dict[bytes, tuple[str, object]] = {}
        # Goals are taken by the node's input thread (a goal of 100 000 poses takes seconds to become
        # Python objects): its callbacks run under the node's lock, the control loop goes on meanwhile.
        lock = node.lock

        def locked(callback):
            def run(*args):
                with lock:
                    return callback(*args)

            return run

        self.server = lean_action_server_class()(
            node.inputs,
            FollowPath,
            node.resolve_input_name(self.s.follow_path_action),  # the inputs' node takes no global arguments
            locked(self._execute),
            goal_callback=locked(self._on_goal),
            handle_accepted_callback=locked(self._on_accepted),
            cancel_callback=lambda handle: CancelResponse.ACCEPT,
        )
        try:
            if not all(hasattr(self.server, name) for name in ("_handle", "_lock", "is_ready", "take_data")):
                raise TypeError("this rclpy's ActionServer takes goals otherwise")
            self.server.lean_request = lean_goal_request_type(FollowPath)
        except Exception as error:  # the ordinary messages then: slow for long paths, but right
            node.get_logger().warning(f"follow_path goals taken as Python messages: {type(error).__name__}: {error}")
        else:
            if self.server.lean_request is None:
                node.get_logger().warning("follow_path goals taken as Python messages: unknown message layout")
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

    def end_goal(self) -> None:
        """The running goal ends (cleanup, shutdown): its result is sent when the input thread runs its
        execution, so the caller waits for :attr:`results_pending` to clear before destroying the server."""
        with self.node.lock:
            self._finish_goal("abort", self.Result.UNKNOWN, "controller cleaned up")

    @property
    def results_pending(self) -> bool:
        return bool(self._outcomes)

    def destroy(self) -> None:
        """Destroy the server and subscriptions (the input thread is stopped by then)."""
        self.end_goal()
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
            try:  # a quaternion that is no rotation is refused, never read as some yaw
                yaw = convert.checked_yaw(q.x, q.y, q.z, q.w)
            except ValueError as error:
                self._refuse_transform(t, str(error))
                continue
            if not self.buffer.set(
                t.header.frame_id,
                t.child_frame_id,
                convert.stamp_seconds(t.header.stamp),
                float(p.x),
                float(p.y),
                yaw,
                static=static,
            ):
                self._refuse_transform(t, "a non-finite value, an empty frame or a loop")
        if not self.mounts_done:
            self.resolve_mounts()

    def _refuse_transform(self, t, why: str) -> None:
        self.core.events.append(f"transform {t.header.frame_id} -> {t.child_frame_id} refused: {why}")
        self.node.get_logger().error(self.core.events[-1])

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
            if not self.core.mount_acceptable(*pose):
                self._refuse_mount(scanner.name, pose)
                continue
            if self.core.set_mount(index, *pose):
                self.node.get_logger().info(
                    f"scanner {scanner.name}: mount from TF ({pose[0]:.3f}, {pose[1]:.3f} m, {pose[2]:.3f} rad)"
                )
        self.mounts_done = done

    def _refuse_mount(self, name: str, pose) -> None:
        """A mount beyond the parameters' bounds: the parameters' mount stays (once logged per scanner)."""
        event = f"scanner {name}: mount from TF ({pose[0]:g}, {pose[1]:g} m) refused: {self.core.mount_problem(*pose)}"
        if event not in self.core.events[-20:]:
            self.core.events.append(event)
            self.node.get_logger().error(event)

    def _on_speed_limit(self, msg) -> None:
        self.core.set_speed_limit(float(msg.speed_limit), bool(msg.percentage))

    def _on_clear(self, request, response):
        return response

    # -- goals -------------------------------------------------------------------------------
    def _on_goal(self, request):
        return self._GoalResponse.ACCEPT if self.core.active else self._GoalResponse.REJECT

    def _path_frame_pose(self, msg) -> tuple[int, str, Any]:
        """(error code, message, the ``path frame → odom`` transform or None when the frames agree); code
        NONE with message: wait for the transform. Cheap: run in the control loop."""
        R = self.Result
        frame = _frame_of(msg)
        target = self.s.odom_frame
        if frame and target and frame.lstrip("/") != target.lstrip("/"):
            if not self.s.use_tf:
                return R.TF_ERROR, f"path in frame {frame!r}, odometry in {target!r}, and use_tf is off", None
            pose = self.buffer.lookup(target, frame, now_s=self.node._now_s(alive=False))
            if pose is None:
                return (
                    R.NONE,
                    f"no transform {frame} -> {target} yet (or none newer than {self.buffer.max_age_s:g} s)",
                    None,
                )
            return R.NONE, "", pose
        return R.NONE, "", None

    def _prepare_path(self, msg, pose, robot) -> tuple[str, int, str, Any]:
        """A goal's path decoded, moved into the odometry frame, simplified and a planner built on it, in
        the worker thread (it grows with the path): (what, error code, message, value) with what one of
        "path" (value: a PreparedPath), "same" (the running path), "there" (every pose at the robot),
        "wait" (for odometry) or "abort"."""
        R = self.Result
        path = PathArrays.of(msg)
        if path.error:
            return "abort", R.INVALID_PATH, f"path refused: its poses could not be read ({path.error})", None
        points = path.positions
        if len(points) == 0:
            return "abort", R.INVALID_PATH, "empty path", None
        if not np.isfinite(points).all():
            return "abort", R.INVALID_PATH, "path with NaN or infinite coordinates", None
        if pose is not None:
            c, s_ = math.cos(pose[2]), math.sin(pose[2])
            points = points @ np.array([[c, s_], [-s_, c]]) + np.array(pose[:2])
        points = simplify_polyline(points, self.s.path_simplify_m)
        if len(points) == 1:
            if robot is None:
                return "wait", R.NONE, "a path of one pose: waiting for odometry", None
            if math.hypot(points[0][0] - robot[0], points[0][1] - robot[1]) <= self.s.goal_tolerance_m:
                return "there", R.NONE, "", None
            points = np.vstack([robot, points])
        if self.core.same_path(points):
            return "same", R.NONE, "", None
        try:
            return "path", R.NONE, "", self.core.build_path(points)
        except ValueError as error:
            return "abort", R.INVALID_PATH, f"path refused: {error}", None

    def _start_path(self, goal: _Goal) -> tuple[int, str]:
        """Hand the goal's path to the worker once its transform is known; (error code, message) when it
        cannot be (TF), code NONE and a message while waiting."""
        code, message, pose = self._path_frame_pose(goal.request_path)
        if code != self.Result.NONE or message:
            return code, message
        o = self.core.odometry
        robot = None if o is None else (o.x, o.y)
        msg = goal.request_path
        self.node.background.submit("goal", lambda: self._prepare_path(msg, pose, robot))
        goal.extra["submitted"] = True
        return code, ""

    def take_background(self) -> None:
        """The goal's path, once the worker has it ready (at each cycle and watchdog tick)."""
        outcome = self.node.background.take("goal")
        goal = self.goal
        if outcome is None or goal is None or goal.set:
            return
        goal.extra["submitted"] = False
        if outcome.error is not None:
            self._finish_goal("abort", self.Result.INVALID_PATH, f"path refused: {outcome.error}")
            return
        what, code, message, value = outcome.value
        if what == "abort":
            self._finish_goal("abort", code, message)
        elif what == "there":
            self._finish_goal("succeed", self.Result.NONE, "")
        elif what == "same":
            goal.set = True
        elif what == "path":
            self.core.use_prepared(value)
            goal.set = True

    def _on_accepted(self, handle) -> None:
        """A new goal: it replaces the running one, whose path is driven on until the new one is ready
        (decoded and simplified by the worker thread). Its execution (the action's EXECUTING state and
        result) is started only when it ends, by :meth:`_end`: a goal waiting in a coroutine would be
        resumed without pause by rclpy's events executor."""
        goal = _Goal(handle, None, handle.request.path, self.node._now_s())
        code, message, _pose = self._path_frame_pose(goal.request_path)
        if code == self.Result.NONE:
            code, message = _quickly_invalid(handle.request.path, self.Result.INVALID_PATH)
        if code != self.Result.NONE:
            self._end(goal, "abort", code, message)  # the running goal, if any, goes on
            return
        previous = self.goal
        if previous is not None:
            goal.checkpoint = previous.checkpoint  # a preempt is no fresh start for the progress check
            self._finish_goal("abort", self.Result.NONE, "preempted by a new path", keep_path=True)
        self.goal = goal
        self._start_path(goal)

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

    def _result(self, code: int, message: str):
        result = self.Result()
        result.error_code = int(code)
        result.error_msg = message
        return result

    def _finish_goal(self, outcome: str, code: int, message: str, keep_path: bool = False) -> None:
        goal, self.goal = self.goal, None
        if goal is None:
            return
        if not goal.set:
            self.node.background.cancel("goal")
        if not keep_path:
            self.core.clear_path()
        self.core.events.append(f"follow_path: {outcome} ({code}{': ' + message if message else ''})")
        self._end(goal, outcome, code, message)

    def deactivated(self) -> None:
        with self.node.lock:
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
            if not goal.extra.get("submitted"):
                code, message = self._start_path(goal)
                if code != R.NONE:
                    self._finish_goal("abort", code, message)
                    return
                if message and now_s - goal.accepted_s > self.s.failure_tolerance_s:
                    self._finish_goal("abort", R.TF_ERROR, message)
                    return
            return  # the previous path (if any) is driven on meanwhile
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


QUICK_CHECK_POSES = 1000  # a path of Python messages this short is checked when it arrives (arrays: any length)


def _frame_of(path: Any) -> str:
    """A path's frame: its header's, else its first pose's."""
    if isinstance(path, PathArrays):
        return path.frame_id or path.first_pose_frame_id
    return path.header.frame_id or (path.poses[0].header.frame_id if len(path.poses) else "")


def _quickly_invalid(path: Any, invalid_path: int) -> tuple[int, str]:
    """(INVALID_PATH, why) for a path whose poses could not be read, an empty path, or one with a non-finite
    coordinate; (0, "") otherwise. Checked as the goal arrives, before it preempts the running goal, so that a bad
    goal is refused with its own code even when the next goal follows at once (a path of Python messages longer
    than ``QUICK_CHECK_POSES``: its points are checked by the worker thread)."""
    if isinstance(path, PathArrays):
        if path.error:
            return invalid_path, f"path refused: its poses could not be read ({path.error})"
        if len(path) == 0:
            return invalid_path, "empty path"
        if not np.isfinite(path.positions).all():
            return invalid_path, "path with NaN or infinite coordinates"
        return 0, ""
    poses = path.poses
    if len(poses) == 0:
        return invalid_path, "empty path"
    if len(poses) <= QUICK_CHECK_POSES:
        coordinates = [value for p in poses for value in (p.pose.position.x, p.pose.position.y)]
        if not all(math.isfinite(value) for value in coordinates):
            return invalid_path, "path with NaN or infinite coordinates"
    return 0, ""
