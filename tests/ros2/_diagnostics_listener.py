"""Record the ``way`` status a viapath node publishes on /diagnostics (for test_ros2_diagnostics).

``python _diagnostics_listener.py OUT.jsonl``: one JSON line per message with a way status: its header stamp
(the node's clock, sim time under ``viapath ros2 sim``), level, message and key/values. Runs until SIGTERM.
"""

from __future__ import annotations

import json
import signal
import sys


def main(out_path: str) -> int:
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.signals import SignalHandlerOptions

    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    stop = {"flag": False}
    signal.signal(signal.SIGTERM, lambda *_: stop.update(flag=True))
    node = rclpy.create_node("diagnostics_listener")
    with open(out_path, "w") as handle:

        def on_diagnostics(msg) -> None:
            for status in msg.status:
                if status.name.endswith(": way"):
                    level = status.level[0] if isinstance(status.level, bytes) else int(status.level)
                    record = {
                        "stamp_s": msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec,
                        "level": level,
                        "message": status.message,
                        "values": {kv.key: kv.value for kv in status.values},
                    }
                    handle.write(json.dumps(record) + "\n")
                    handle.flush()

        node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 50)
        while not stop["flag"] and rclpy.ok():
            rclpy.spin_once(node, timeout_sec=0.05)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1]))
