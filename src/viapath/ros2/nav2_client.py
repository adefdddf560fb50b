"""``viapath ros2 follow PATH``: plays Nav2's part against a controller: lifecycle, FollowPath goals.

Source: Nav2's lifecycle manager (configure, then activate the managed node through its
``change_state`` service; no bond) and its behaviour tree's ``FollowPath`` node, which sends the
planner's path as a goal and re-sends it about once a second while the goal runs (a preempt).

What we chose:
* The path (a scenario's or a path file's waypoints, in the odometry frame of the simulator) is
  densified to ``--spacing`` (as a planner's path is) and expressed in ``--frame`` through
  ``--map-offset`` (the pose of odom in map, as the simulator's ``/tf_static`` says).
* Times are the simulator's episode time: the node's clock (``use_sim_time``) minus 1 s (the
  simulator's episodes start at 1 s). Events: ``T:empty`` and ``T:nan`` send an invalid path,
  ``T:preempt:SOURCE`` switches to another path (re-sent from then on), ``T:cancel``,
  ``T:deactivate``, ``T:activate``, ``T:speed-limit:PERCENT``, ``T:clear`` (the costmap-clearing
  service), ``T:stop`` (no more re-sending).
* Every goal sent, result, feedback sample and event is one JSON line in ``--log`` (flushed).
* The run ends with the path's goal, as the behaviour tree's ``FollowPath`` node does: its result
  (not a preempt's) is printed as one line and gives the exit code: 0 when it succeeded, or was
  canceled by ``T:cancel``; 1 when it failed (aborted, or canceled by the controller). With no result,
  the run ends at ``--until`` or when the clock has not moved for ``--wait-s`` (exit 5).
"""

from __future__ import annotations

import json
import math
import sys
import time
from typing import Any

import numpy as np

EPISODE_START_S = 1.0
GOAL_STATUS = {4: "SUCCEEDED", 5: "CANCELED", 6: "ABORTED"}  # action_msgs/GoalStatus
NO_RESULT = 5  # exit code: the run ended without the path goal's result


def densify(points, spacing_m: float) -> np.ndarray:
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if spacing_m <= 0 or len(points) < 2:
        return points
    out = [points[0]]
    for a, b in zip(points[:-1], points[1:]):
        n = max(1, int(math.ceil(np.hypot(*(b - a)) / spacing_m)))
        out += [a + (b - a) * k / n for k in range(1, n + 1)]
    return np.array(out)


def to_frame(points, offset) -> np.ndarray:
    """Points of the odometry frame in the frame where odom sits at ``offset`` (x, y, yaw)."""
    x, y, yaw = offset
    c, s = math.cos(yaw), math.sin(yaw)
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    return np.column_stack([x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1]])


def parse_event(text: str) -> tuple[float, str, str]:
    at, _, rest = text.partition(":")
    kind, _, arg = rest.partition(":")
    try:
        t = float(at)
    except ValueError:
        raise ValueError(f"--at {text!r}: expected TIME:KIND[:ARG]") from None
    kinds = ("empty", "nan", "preempt", "cancel", "deactivate", "activate", "speed-limit", "clear", "stop")
    if kind not in kinds or not math.isfinite(t):
        raise ValueError(f"--at {text!r}: KIND is one of {', '.join(kinds)}")
    return t, kind, arg


class _FollowSession:
    """Nav2's part in one run: the node's action client, lifecycle and costmap clients, the speed-limit
    publisher, the path being (re-)sent and the JSON log. Everything runs in this thread's spins."""

    def __init__(
        self,
        node: Any,
        stop: dict,
        log: Any,
        action: str,
        frame: str,
        offset,
        spacing_m: float,
        lifecycle_node: str | None,
    ) -> None:
        import rclpy
        from lifecycle_msgs.srv import ChangeState
        from nav2_msgs.action import FollowPath
        from nav2_msgs.msg import SpeedLimit
        from nav2_msgs.srv import ClearEntireCostmap
        from rclpy.action import ActionClient

        self.rclpy = rclpy
        self.node, self.stop, self.log = node, stop, log
        self.frame, self.offset, self.spacing_m = frame, offset, spacing_m
        self.FollowPath, self.SpeedLimit, self.ChangeState = FollowPath, SpeedLimit, ChangeState
        self.ClearEntireCostmap = ClearEntireCostmap
        self.client: Any = ActionClient(node, FollowPath, action)
        self.speed_pub = node.create_publisher(SpeedLimit, "speed_limit", 10)
        self.clear = node.create_client(ClearEntireCostmap, "local_costmap/clear_entirely_local_costmap")
        self.change: Any = node.create_client(ChangeState, f"{lifecycle_node}/change_state") if lifecycle_node else None
        self.started = time.monotonic()
        self.points: np.ndarray = np.zeros((0, 2))  # the path re-sent (set by load_points' caller)
        self.goal: Any = None  # the handle of the path's goal last accepted
        self.sent_s = -math.inf
        self.resend = True
        self.count = 0
        self.due = True
        self.cancel = False
        self.outcome: dict | None = None  # the path goal's final result, once it came

    # -- helpers ---------------------------------------------------------------------------------
    def write(self, **item) -> None:
        self.log.write(json.dumps(item) + "\n")
        self.log.flush()

    def now(self) -> float:
        return self.node.get_clock().now().nanoseconds * 1e-9 - EPISODE_START_S

    def spin(self, seconds: float = 0.01) -> None:
        self.rclpy.spin_once(self.node, timeout_sec=seconds)

    def timed_out(self, wait_s: float) -> bool:
        return bool(self.stop["flag"]) or time.monotonic() - self.started > wait_s

    def path_msg(self, points) -> Any:
        from geometry_msgs.msg import PoseStamped
        from nav_msgs.msg import Path as PathMsg

        msg = PathMsg()
        msg.header.frame_id = self.frame
        for x, y in np.asarray(points, dtype=float).reshape(-1, 2):
            pose = PoseStamped()
            pose.header.frame_id = self.frame
            pose.pose.position.x, pose.pose.position.y = float(x), float(y)
            pose.pose.orientation.w = 1.0
            msg.poses.append(pose)
        return msg

    def load_points(self, text: str) -> np.ndarray:
        from viapath.ros2 import convert

        waypoints, _ = convert.load_path_file(text)
        return to_frame(densify(waypoints, self.spacing_m), self.offset)

    # -- lifecycle and servers -------------------------------------------------------------------
    def transition(self, transition_id: int, label: str, wait_s: float = 60.0) -> bool:
        request = self.ChangeState.Request()
        request.transition.id = transition_id
        future = self.change.call_async(request)
        end = time.monotonic() + wait_s  # configuring loads (or compiles) the planner: slow on a loaded machine
        while not future.done() and time.monotonic() < end and not self.stop["flag"]:
            self.spin(0.05)
        ok = future.done() and future.result() is not None and future.result().success
        self.write(kind="lifecycle", transition=label, ok=bool(ok), t=self.now())
        return bool(ok)

    def bring_up(self, lifecycle_node: str | None, action: str, wait_s: float) -> int:
        """Configure and activate the controller (with a lifecycle node), then wait for its action
        server: 0, or the exit code (3: a service or server missing, 4: a transition failed)."""
        if self.change is not None:
            while not self.change.wait_for_service(timeout_sec=0.1):
                self.spin(0.05)
                if self.timed_out(wait_s):
                    print(f"error: no lifecycle service {lifecycle_node}/change_state", file=sys.stderr)
                    return 3
            if not (self.transition(1, "configure", wait_s) and self.transition(3, "activate", wait_s)):
                print(
                    f"error: {lifecycle_node}: configure or activate failed or took over {wait_s:g} s", file=sys.stderr
                )
                return 4
        while not self.client.wait_for_server(timeout_sec=0.1):
            self.spin(0.05)
            if self.timed_out(wait_s):
                print(f"error: no action server {action}", file=sys.stderr)
                return 3
        return 0

    # -- goals -----------------------------------------------------------------------------------
    def send(self, points, label: str):
        index = self.count
        self.count += 1
        goal = self.FollowPath.Goal()
        goal.path = self.path_msg(points)
        goal.controller_id = "FollowPath"
        goal.goal_checker_id = "general_goal_checker"
        goal.progress_checker_id = "progress_checker"
        future = self.client.send_goal_async(
            goal,
            feedback_callback=lambda fb, i=index: self.write(
                kind="feedback",
                goal=index,
                t=self.now(),
                distance_to_goal=fb.feedback.distance_to_goal,
                speed=fb.feedback.speed,
            ),
        )
        self.write(kind="sent", goal=index, label=label, t=self.now(), poses=len(goal.path.poses))
        future.add_done_callback(lambda f, i=index: self.accepted(f, i, label))
        return future

    def accepted(self, future, index: int, label: str) -> None:
        handle = future.result()
        self.write(kind="accepted" if handle.accepted else "rejected", goal=index, t=self.now())
        if handle.accepted:
            if label == "path":
                self.goal = handle
                if self.cancel:  # sent before the cancel, accepted after it: cancel it too
                    handle.cancel_goal_async()
            handle.get_result_async().add_done_callback(lambda r, i=index: self.finished(i, label, r.result()))

    def finished(self, index: int, label: str, response) -> None:
        message = response.result.error_msg
        self.write(
            kind="result",
            goal=index,
            label=label,
            t=self.now(),
            status=int(response.status),
            error_code=int(response.result.error_code),
            error_msg=message,
        )
        if label == "path" and message != "preempted by a new path":
            self.resend = False  # as the behaviour tree: the goal is over (succeeded, failed, canceled)
            if self.outcome is None:
                self.outcome = dict(
                    goal=index, t=self.now(), status=int(response.status), code=int(response.result.error_code),
                    message=message,
                )  # fmt: skip

    def exit_code(self) -> int:
        """0: the path goal succeeded (or was canceled as asked); 1: it failed; NO_RESULT: no result came."""
        if self.outcome is None:
            return NO_RESULT
        status = self.outcome["status"]
        return 0 if status == 4 or (status == 5 and self.cancel) else 1

    def report(self, until_s: float) -> str:
        """The run's end in one line."""
        o = self.outcome
        if o is None:
            if self.stop["flag"]:
                why = "interrupted"
            else:
                why = f"--until {until_s:g} s came" if self.now() > until_s else "the clock stopped"
            return f"follow_path: no result ({why}; {self.count} goals sent)"
        detail = f"error_code {o['code']}" + (f": {o['message']}" if o["message"] else "")
        name = GOAL_STATUS.get(o["status"], f"status {o['status']}")
        return f"follow_path: {name} at t = {o['t']:.1f} s (goal {o['goal']}, {detail})"

    # -- the run ---------------------------------------------------------------------------------
    def handle_event(self, at: float, kind: str, arg: str, t: float) -> None:
        self.write(kind="event", event=kind, arg=arg, at=at, t=t)
        if kind == "empty":
            self.send(np.zeros((0, 2)), "empty")
        elif kind == "nan":
            self.send(np.array([[0.0, 0.0], [np.nan, 1.0]]), "nan")
        elif kind == "preempt":
            self.points = self.load_points(arg)
            self.resend = self.due = True
        elif kind == "cancel":
            self.resend, self.cancel = False, True
            if self.goal is not None:
                self.goal.cancel_goal_async()
        elif kind == "stop":
            self.resend = False
        elif kind in ("deactivate", "activate") and self.change is not None:
            self.resend = self.due = kind == "activate"
            self.transition(4 if kind == "deactivate" else 3, kind)
        elif kind == "speed-limit":
            msg = self.SpeedLimit()
            msg.percentage = True
            msg.speed_limit = float(arg)
            self.speed_pub.publish(msg)
            self.write(kind="speed-limit", percent=float(arg), t=self.now())
        elif kind == "clear":
            future = self.clear.call_async(self.ClearEntireCostmap.Request())
            future.add_done_callback(lambda f: self.write(kind="cleared", ok=f.result() is not None, t=self.now()))

    def follow(self, schedule: list[tuple[float, str, str]], resend_s: float, until_s: float, wait_s: float) -> None:
        """Wait for the simulated clock to start the episode (warm-up ticks lie below it), then play
        the events as their times come and re-send the path every ``resend_s`` until the path goal's
        result, ``until_s``, or a clock that has not moved for ``wait_s`` (wall time)."""
        while self.now() < -0.999 and not self.stop["flag"] and time.monotonic() - self.started < wait_s:
            self.spin(0.02)
        last_t, moved = self.now(), time.monotonic()
        while not self.stop["flag"] and self.outcome is None:
            t = self.now()
            if t > until_s:
                break
            if t != last_t:
                last_t, moved = t, time.monotonic()
            elif time.monotonic() - moved > wait_s:
                break
            while schedule and schedule[0][0] <= t:
                self.handle_event(*schedule.pop(0), t)
            if self.resend and (self.due or (resend_s > 0 and t - self.sent_s >= resend_s)):
                self.send(self.points, "path")
                self.sent_s, self.due = t, False
            self.spin(0.01)


def run_follow(
    source: str,
    action: str = "follow_path",
    frame: str = "map",
    offset=(0.0, 0.0, 0.0),
    spacing_m: float = 0.05,
    resend_s: float = 1.0,
    lifecycle_node: str | None = None,
    events: list[str] | None = None,
    log_file: str | None = None,
    until_s: float = math.inf,
    ros_args: list[str] | None = None,
    wait_s: float = 120.0,
) -> int:
    from viapath.ros2 import interfaces
    from viapath.ros2.process import finish_ros_process, start_ros_process

    interfaces.load()
    schedule = sorted(parse_event(e) for e in (events or []))
    log = open(log_file, "a") if log_file else sys.stdout  # noqa: SIM115 -- the file or stdout, for the whole run
    node, stop, previous = start_ros_process("viapath_follow", ros_args)
    try:
        session = _FollowSession(node, stop, log, action, frame, offset, spacing_m, lifecycle_node)
        code = session.bring_up(lifecycle_node, action, wait_s)
        if code:
            return code
        session.points = session.load_points(source)
        session.follow(schedule, resend_s, until_s, wait_s)
        print(session.report(until_s), file=sys.stderr if log is sys.stdout else sys.stdout, flush=True)
        return session.exit_code()
    finally:
        if log is not sys.stdout:
            log.close()
        finish_ros_process(node, previous)
