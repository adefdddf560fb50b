"""The way's state on /diagnostics, over DDS: ``viapath ros2 node`` driven by ``viapath ros2 sim`` (lock-step,
sim time) and a listener (``_diagnostics_listener.py``), each scene's three processes in a ROS domain of their
own, ended by pid. A wall across the corridor: WARN "blocked" with where the robot waits, within 3 s of sim
time, and the robot never reaches the wall; the open corridor: OK, "the way is open", throughout."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from _ros2_procs import Processes, domain_id, viapath

WALL_X_M, ROBOT_RADIUS_M = 1.8, 0.25
SCENES = {
    "wall": """name: wall-across
robot: {start: [0.0, 0.0], heading: 0.0, speed: 0.3, radius: 0.25}
path: {waypoints: [[0.0, 0.0], [6.0, 0.0]], half_width: 0.4}
walls:
  - [[1.8, -1.0], [1.8, 1.0]]
duration_s: 6
""",
    "open": """name: open-corridor
robot: {start: [0.0, 0.0], heading: 0.0, speed: 0.3, radius: 0.25}
path: {waypoints: [[0.0, 0.0], [6.0, 0.0]], half_width: 0.4}
duration_s: 6
""",
}
OK_LEVEL, WARN_LEVEL = 0, 1


@pytest.fixture(scope="module")
def ways(tmp_path_factory):
    """Per scene: the way statuses the listener received and the simulator's metrics."""
    from viapath.ros2 import rclpy_available

    ok, why = rclpy_available()
    if not ok:
        pytest.skip(why)
    folder = tmp_path_factory.mktemp("diagnostics")
    procs = Processes(folder)
    started = {}
    try:
        for name, text in SCENES.items():  # both scenes at once, each in its own domain
            scene = folder / f"{name}.yaml"
            scene.write_text(text)
            domain, out = domain_id(), folder / f"{name}_ways.jsonl"
            listener = procs.start(
                f"{name}_listener",
                [sys.executable, str(Path(__file__).with_name("_diagnostics_listener.py")), str(out)],
                domain,
            )
            node = procs.start(
                f"{name}_node",
                viapath(
                    "ros2",
                    "node",
                    "--use-sim-time",
                    "--ros-args",
                    "-p",
                    "half_width_m:=0.4",
                    "-p",
                    "nominal_speed_mps:=0.3",
                ),
                domain,
            )
            sim = procs.start(
                f"{name}_sim",
                viapath("ros2", "sim", str(scene), "--rate", "2", "--lockstep", "--json", "--wait-s", "300"),
                domain,
            )
            started[name] = (listener, node, sim, out)
        results = {}
        for name, (listener, node, sim, out) in started.items():
            code = procs.wait(sim, 300.0)
            sim_out, sim_err = procs.output(sim)
            procs.stop(node)
            procs.stop(listener)
            assert code == 0, sim_err[-3000:]
            records = [json.loads(line) for line in out.read_text().splitlines() if line.strip()]
            results[name] = (records, json.loads(sim_out.strip().splitlines()[-1]))
        yield results
    finally:
        procs.stop_all()


def test_a_wall_across_the_way_is_a_blocked_warning_with_where_the_robot_waits(ways):
    records, metrics = ways["wall"]
    assert records, "no way status on /diagnostics"
    first = records[0]["stamp_s"]
    warned = [r for r in records if r["level"] == WARN_LEVEL]
    assert warned and warned[0]["stamp_s"] - first <= 3.0, [(r["stamp_s"], r["message"]) for r in records[:10]]
    assert warned[0]["message"].startswith("blocked: static geometry closes the way")
    wait_x = float(warned[-1]["values"]["wait_x_m"])
    said_x = float(warned[-1]["message"].split("waits at (")[1].split(",")[0])
    assert wait_x < WALL_X_M - ROBOT_RADIUS_M and abs(said_x - wait_x) <= 0.006
    assert records[-1]["level"] == WARN_LEVEL  # still blocked at the end: the wall stays
    assert metrics["static_contact"] == 0 and not metrics["reached_goal"]


def test_an_open_way_is_ok_throughout(ways):
    records, metrics = ways["open"]
    assert len(records) >= 3  # once a second at least, over 6 s of sim time
    assert all(r["level"] == OK_LEVEL and r["values"]["blocked"] == "0" for r in records), records[:5]
    assert any(r["message"] == "the way is open" for r in records)
    assert metrics["static_contact"] == 0 and not metrics["collision"]
