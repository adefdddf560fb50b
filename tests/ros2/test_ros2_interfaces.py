"""The generated Nav2 / tf2 interfaces: their type hashes equal those of Nav2 Kilted and tf2, and they
go over DDS with those hashes.

Where the expected hashes come from:
* ``tf2_msgs/msg/TFMessage``: the hash published in CARLA's ROS 2 type table
  (``carla-simulator/carla``, ``CdrTopicInfo<msg::TFMessage>``), whose ``nav_msgs/Odometry``,
  ``std_msgs/Header`` and ``geometry_msgs/PoseStamped`` hashes equal those the Kilted wheels here ship.
* ``nav2_msgs``: no Nav2 Kilted binary can be reached from this machine, so these were computed by
  the Kilted ``rosidl_generator_type_description`` from the ``kilted`` branch of
  ``ros-navigation/navigation2`` (its ``nav2_msgs/action/FollowPath.action``, ``msg/SpeedLimit.msg``,
  ``srv/ClearEntireCostmap.srv``): the files Nav2 Kilted's binaries are built from. Our own
  definitions are written independently (other comments), so equal hashes mean equal fields.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from viapath.ros2 import rclpy_available

OK, WHY = rclpy_available()
pytestmark = pytest.mark.skipif(not OK, reason=WHY)

EXPECTED = {
    "tf2_msgs/msg/TFMessage": "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
    "nav2_msgs/action/FollowPath": "RIHS01_9d95513552fb578cfb933d7e0160273911269cbdf4b348f1acb87d8a903b13cf",
    "nav2_msgs/action/FollowPath_Goal": "RIHS01_7ec8732a3a001bf92b87db3989ef6984b1a4b9b9e62e166543ffa72344ecd194",
    "nav2_msgs/action/FollowPath_Result": "RIHS01_432bc8fc1c0de59f8181d00bf8dcc7d58e76cebcfd2de471361e62f468ad4428",
    "nav2_msgs/action/FollowPath_Feedback": "RIHS01_496acbe672234cdb70be4f93d28a22aabbf441958e2e1ff443a44a96e9f3185b",
    "nav2_msgs/action/FollowPath_FeedbackMessage": "RIHS01_3f4008700ba56ac4c82b01ef2b7fdd3fc18dc194399c48e5c43ebf8008b891d5",
    "nav2_msgs/action/FollowPath_SendGoal": "RIHS01_5b662aee1159e1d7e7b5f8fef21f556b8bc67c818c730a68e18bb29b85f66946",
    "nav2_msgs/action/FollowPath_GetResult": "RIHS01_8ab4c588c878f0e997316ec559f172bb56fc210b484c2f6b280d391d3bd6890f",
    "nav2_msgs/msg/SpeedLimit": "RIHS01_83d8e4e842559f4d9a988b19d31b162216ec738536389f98438d1a166f91845a",
    "nav2_msgs/srv/ClearEntireCostmap": "RIHS01_553f54f9cadab44553fdf5627433fcb6701f71c1fc2eb55a7b4a004fdeeab952",
}


def type_hashes(prefix: Path) -> dict[str, str]:
    """Type name -> ``RIHS01_…`` of every generated type under ``prefix`` (from the generator's JSON
    descriptions)."""
    from viapath.ros2 import interfaces

    out: dict[str, str] = {}
    for package in interfaces.PACKAGES:
        for file in sorted((prefix / "share" / package).glob("*/*.json")):
            for item in json.loads(file.read_text())["type_hashes"]:
                if item["type_name"].startswith(package + "/"):
                    out[item["type_name"]] = item["hash_string"]
    return out


@pytest.fixture(scope="module")
def prefix():
    from viapath.ros2 import interfaces

    return interfaces.build()


def test_type_hashes_equal_nav2_kilted_and_tf2(prefix):

    ours = type_hashes(prefix)
    assert {name: ours.get(name) for name in EXPECTED} == EXPECTED


def test_the_cache_key_follows_the_definitions(tmp_path, monkeypatch):
    from viapath.ros2 import interfaces

    before = interfaces.cache_key()
    copy = tmp_path / "idl"
    import shutil

    shutil.copytree(interfaces.IDL, copy)
    monkeypatch.setattr(interfaces, "IDL", copy)
    assert interfaces.cache_key() == before
    speed = copy / "nav2_msgs" / "msg" / "SpeedLimit.msg"
    speed.write_text(speed.read_text() + "float64 another\n")
    assert interfaces.cache_key() != before
    monkeypatch.setenv("VIAPATH_CACHE_DIR", str(tmp_path / "cache"))
    assert str(interfaces.install_prefix()).startswith(str(tmp_path / "cache"))


def test_topics_carry_the_hashes_over_dds(prefix, tmp_path):
    """A process publishes /tf, speed_limit and serves follow_path; the graph reports Nav2's hashes."""
    from _ros2_procs import domain_id, ros_env

    script = tmp_path / "probe.py"
    script.write_text(
        textwrap.dedent("""
        import time
        from viapath.ros2 import interfaces
        interfaces.load()
        import rclpy
        from rclpy.action import ActionServer
        from nav2_msgs.action import FollowPath
        from nav2_msgs.msg import SpeedLimit
        from tf2_msgs.msg import TFMessage
        rclpy.init()
        node = rclpy.create_node("probe")
        node.create_publisher(TFMessage, "/tf", 10)
        node.create_publisher(SpeedLimit, "speed_limit", 10)
        ActionServer(node, FollowPath, "follow_path", lambda goal: FollowPath.Result())
        end = time.monotonic() + 10
        while time.monotonic() < end:
            rclpy.spin_once(node, timeout_sec=0.05)
            infos = {t: node.get_publishers_info_by_topic(t) for t in ("/tf", "/speed_limit", "/follow_path/_action/feedback")}
            if all(infos.values()):
                for t, i in infos.items():
                    print(t, i[0].topic_type, i[0].topic_type_hash)
                break
        node.destroy_node()
        rclpy.shutdown()
    """)
    )
    out = subprocess.run(
        [sys.executable, str(script)], env=ros_env(domain_id()), capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 0, out.stderr[-2000:]
    seen = {line.split()[1]: line.split()[2] for line in out.stdout.splitlines() if line.startswith("/")}
    assert seen == {
        "tf2_msgs/msg/TFMessage": EXPECTED["tf2_msgs/msg/TFMessage"],
        "nav2_msgs/msg/SpeedLimit": EXPECTED["nav2_msgs/msg/SpeedLimit"],
        "nav2_msgs/action/FollowPath_FeedbackMessage": EXPECTED["nav2_msgs/action/FollowPath_FeedbackMessage"],
    }, out.stdout
