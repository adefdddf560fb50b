"""Start and end of a viapath ROS 2 process (simulator node, bag player): rclpy without its own
signal handlers, SIGINT/SIGTERM setting a stop flag the loop polls, and everything restored at the end."""

from __future__ import annotations

import signal
import sys


def start_ros_process(node_name: str, ros_args: list[str] | None):
    """``(node, stop, previous)``: the node, a ``{"flag": bool}`` set by SIGINT/SIGTERM, and the signal
    handlers to restore with :func:`finish_ros_process`."""
    import rclpy
    from rclpy.signals import SignalHandlerOptions

    rclpy.init(
        args=[sys.argv[0]] + (["--ros-args", *ros_args] if ros_args else []),
        signal_handler_options=SignalHandlerOptions.NO,
    )
    stop = {"flag": False}
    previous = {s: signal.signal(s, lambda *_: stop.__setitem__("flag", True)) for s in (signal.SIGINT, signal.SIGTERM)}
    return rclpy.create_node(node_name), stop, previous


def finish_ros_process(node, previous) -> None:
    import rclpy

    node.destroy_node()
    for s, h in previous.items():
        signal.signal(s, h)
    if rclpy.ok():
        rclpy.shutdown()
