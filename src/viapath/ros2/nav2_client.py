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
"""

from __future__ import annotations

import json
import math
import sys
import time
from typing import Any

import numpy as np

EPISODE_START_S = 1.0


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
    from geometry_msgs.msg import PoseStamped
    from lifecycle_msgs.srv import ChangeState
    from nav_msgs.msg import Path as PathMsg
    from rclpy.action import ActionClient

    from viapath.ros2 import convert, interfaces
    from viapath.ros2.process import finish_ros_process, start_ros_process

    interfaces.load()
    import rclpy
    from nav2_msgs.action import FollowPath
    from nav2_msgs.msg import SpeedLimit
    from nav2_msgs.srv import ClearEntireCostmap

    schedule = sorted(parse_event(e) for e in (events or []))
    log = open(log_file, "a") if log_file else sys.stdout  # noqa: SIM115 -- the file or stdout, for the whole run

    def write(**item) -> None:
        log.write(json.dumps(item) + "\n")
        log.flush()

    def path_msg(points) -> PathMsg:
        msg = PathMsg()
        msg.header.frame_id = frame
        for x, y in np.asarray(points, dtype=float).reshape(-1, 2):
            pose = PoseStamped()
            pose.header.frame_id = frame
            pose.pose.position.x, pose.pose.position.y = float(x), float(y)
            pose.pose.orientation.w = 1.0
            msg.poses.append(pose)
        return msg

    def load_points(text: str) -> np.ndarray:
        waypoints, _ = convert.load_path_file(text)
        return to_frame(densify(waypoints, spacing_m), offset)

    node, stop, previous = start_ros_process("viapath_follow", ros_args)
    try:
        client: Any = ActionClient(node, FollowPath, action)
        speed_pub = node.create_publisher(SpeedLimit, "speed_limit", 10)
        clear = node.create_client(ClearEntireCostmap, "local_costmap/clear_entirely_local_costmap")
        change: Any = node.create_client(ChangeState, f"{lifecycle_node}/change_state") if lifecycle_node else None
        started = time.monotonic()

        def now() -> float:
            return node.get_clock().now().nanoseconds * 1e-9 - EPISODE_START_S

        def spin(seconds: float = 0.01) -> None:
            rclpy.spin_once(node, timeout_sec=seconds)

        def transition(transition_id: int, label: str) -> bool:
            request = ChangeState.Request()
            request.transition.id = transition_id
            future = change.call_async(request)
            end = time.monotonic() + 60
            while not future.done() and time.monotonic() < end and not stop["flag"]:
                spin(0.05)
            ok = future.done() and future.result() is not None and future.result().success
            write(kind="lifecycle", transition=label, ok=bool(ok), t=now())
            return bool(ok)

        if change is not None:
            while not change.wait_for_service(timeout_sec=0.1):
                spin(0.05)
                if stop["flag"] or time.monotonic() - started > wait_s:
                    print(f"error: no lifecycle service {lifecycle_node}/change_state", file=sys.stderr)
                    return 3
            if not (transition(1, "configure") and transition(3, "activate")):
                return 4
        while not client.wait_for_server(timeout_sec=0.1):
            spin(0.05)
            if stop["flag"] or time.monotonic() - started > wait_s:
                print(f"error: no action server {action}", file=sys.stderr)
                return 3

        state: dict[str, Any] = {
            "points": load_points(source),
            "goal": None,
            "sent": -math.inf,
            "resend": True,
            "count": 0,
            "due": True,
            "cancel": False,
        }

        def send(points, label: str):
            index = state["count"]
            state["count"] += 1
            goal = FollowPath.Goal()
            goal.path = path_msg(points)
            goal.controller_id = "FollowPath"
            goal.goal_checker_id = "general_goal_checker"
            goal.progress_checker_id = "progress_checker"
            future = client.send_goal_async(
                goal,
                feedback_callback=lambda fb, i=index: write(
                    kind="feedback",
                    goal=index,
                    t=now(),
                    distance_to_goal=fb.feedback.distance_to_goal,
                    speed=fb.feedback.speed,
                ),
            )
            write(kind="sent", goal=index, label=label, t=now(), poses=len(goal.path.poses))

            def accepted(f, i=index):
                handle = f.result()
                write(kind="accepted" if handle.accepted else "rejected", goal=i, t=now())
                if handle.accepted:
                    if label == "path":
                        state["goal"] = handle
                        if state["cancel"]:  # sent before the cancel, accepted after it: cancel it too
                            handle.cancel_goal_async()
                    handle.get_result_async().add_done_callback(lambda r, i=i: finished(i, label, r.result()))

            future.add_done_callback(accepted)
            return future

        def finished(index: int, label: str, response) -> None:
            message = response.result.error_msg
            write(
                kind="result",
                goal=index,
                label=label,
                t=now(),
                status=int(response.status),
                error_code=int(response.result.error_code),
                error_msg=message,
            )
            if label == "path" and message != "preempted by a new path":
                state["resend"] = False  # as the behaviour tree: the goal is over (succeeded, failed, canceled)

        # wait for the simulated clock to start the episode (warm-up ticks lie below it)
        while now() < -0.999 and not stop["flag"] and time.monotonic() - started < wait_s:
            spin(0.02)
        while not stop["flag"]:
            t = now()
            if t > until_s:
                break
            while schedule and schedule[0][0] <= t:
                at, kind, arg = schedule.pop(0)
                write(kind="event", event=kind, arg=arg, at=at, t=t)
                if kind == "empty":
                    send(np.zeros((0, 2)), "empty")
                elif kind == "nan":
                    send(np.array([[0.0, 0.0], [np.nan, 1.0]]), "nan")
                elif kind == "preempt":
                    state["points"] = load_points(arg)
                    state["resend"] = state["due"] = True
                elif kind == "cancel":
                    state["resend"], state["cancel"] = False, True
                    if state["goal"] is not None:
                        state["goal"].cancel_goal_async()
                elif kind == "stop":
                    state["resend"] = False
                elif kind in ("deactivate", "activate") and change is not None:
                    state["resend"] = state["due"] = kind == "activate"
                    transition(4 if kind == "deactivate" else 3, kind)
                elif kind == "speed-limit":
                    msg = SpeedLimit()
                    msg.percentage = True
                    msg.speed_limit = float(arg)
                    speed_pub.publish(msg)
                elif kind == "clear":
                    future = clear.call_async(ClearEntireCostmap.Request())
                    future.add_done_callback(lambda f: write(kind="cleared", ok=f.result() is not None, t=now()))
            if state["resend"] and (state["due"] or (resend_s > 0 and t - state["sent"] >= resend_s)):
                send(state["points"], "path")
                state["sent"], state["due"] = t, False
            spin(0.01)
        return 0
    finally:
        if log is not sys.stdout:
            log.close()
        finish_ros_process(node, previous)
