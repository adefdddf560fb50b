"""Test helper process: record every planner status of ``viapath/status`` as JSON lines until SIGTERM."""

import json
import signal
import sys

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.signals import SignalHandlerOptions

rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
stop = []
signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
signal.signal(signal.SIGINT, lambda *_: stop.append(1))
node = rclpy.create_node("viapath_test_recorder")
out = open(sys.argv[1], "w")


def on_status(msg):
    for status in msg.status:
        if status.name.endswith(": planner"):
            out.write(json.dumps({kv.key: kv.value for kv in status.values}) + "\n")
            out.flush()


node.create_subscription(DiagnosticArray, "viapath/status", on_status, 100)
print("recording", flush=True)
while not stop:
    rclpy.spin_once(node, timeout_sec=0.05)
out.close()
node.destroy_node()
rclpy.shutdown()
