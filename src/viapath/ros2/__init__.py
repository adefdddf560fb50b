"""viapath on a robot: a ROS 2 planner node, a simulator node and a bag player (docs/design.md §8).

Install with ``pip install -e '.[ros2]'`` (the PyPI wheels of ROS 2 Kilted: rclpy over Fast DDS; no
system ROS and no environment variables are needed), or run from a sourced ROS 2 installation.
Modules that need rclpy import it inside their functions: ``settings``, ``core``, ``options``,
``markers.MarkerScenes`` and ``convert.load_path_file`` work without it.
"""


def rclpy_available() -> tuple[bool, str]:
    """Whether rclpy and the message packages import, and if not, why (one line)."""
    try:
        import diagnostic_msgs.msg  # noqa: F401
        import nav_msgs.msg  # noqa: F401
        import rclpy
        import rclpy.lifecycle  # noqa: F401
        import rosgraph_msgs.msg  # noqa: F401
        import sensor_msgs.msg  # noqa: F401
        import visualization_msgs.msg  # noqa: F401
    except ImportError as error:
        return False, f"ROS 2 (rclpy) is not available: {error}; install with: pip install 'viapath[ros2]'"
    return True, ""
