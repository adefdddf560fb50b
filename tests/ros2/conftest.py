"""One launcher for every ROS 2 end-to-end test: all process groups start at once (each pair in a
ROS domain of its own), so their start-up and lock-step waiting overlap; each test module then
collects its group. Every process is ended by pid when the session ends, also on failure."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from _ros2_procs import Pair, Processes, domain_id, viapath

DATA = Path(os.environ.get("VIAPATH_DATA", Path(__file__).resolve().parents[3] / "shared" / "data"))
BAG = DATA / "leg_tracker_laser" / "positive_2.bag"
PAPER = ("paper-behind", "paper-front", "paper-side")
EMPTY = """name: empty-corridor
robot: {start: [0.0, 0.0], heading: 0.0, speed: 0.3, radius: 0.25}
path: {waypoints: [[0.0, 0.0], [12.0, 0.0]], half_width: 1.0}
obstacles: []
duration_s: 60
"""
FRONT_FAULTS = ["silence:front@1.0-2.5", "nan:front@4.0-5.5", "odom@7.0-8.5", "clock-back:3@10.0"]
REAR_FAULTS = ["silence:rear@1.0-4.0", "short:rear@5.0-8.0"]
PLAY_PARAMS = """viapath:
  ros__parameters:
    scanner_names: ["laser"]
    scanners:
      laser: {topic: scan_front, frame_id: "", mount_x_m: 0.0, mount_y_m: 0.0, mount_yaw_rad: 0.0}
    scan_geometry: from_message
    detector: legs
    tracker_acceleration_sigma_mps2: 0.5
"""


class Launcher:
    def __init__(self, folder: Path):
        self.folder = folder
        self.procs = Processes(folder)
        self.groups: dict[str, dict] = {}
        self.results: dict[str, object] = {}

    def start_all(self) -> None:
        if self.groups:
            return
        procs, folder = self.procs, self.folder
        self.groups["paper"] = {
            "pairs": {name: Pair(procs, name, name) for name in PAPER},
            "references": {name: procs.start(f"{name}_run", viapath("run", name, "--perception", "laser", "--json"), domain_id())
                           for name in PAPER},
        }
        scenario = folder / "empty.yaml"
        scenario.write_text(EMPTY)
        node_args = ["--ros-args", "-p", "nominal_speed_mps:=0.3"]
        faults = lambda items: sum((["--fault", f] for f in items), [])  # noqa: E731
        self.groups["faults"] = {
            "front": Pair(procs, "front", str(scenario), ["--duration", "13", *faults(FRONT_FAULTS)], node_args),
            "rear": Pair(procs, "rear", str(scenario), ["--duration", "10", *faults(REAR_FAULTS)], node_args),
        }
        if BAG.is_file():
            params = folder / "play.yaml"
            params.write_text(PLAY_PARAMS)
            domain = domain_id()
            record = folder / "play_status.jsonl"
            self.groups["play"] = {
                "node": procs.start("play_node", viapath("ros2", "node", "--use-sim-time", "--params-file", str(params)), domain),
                "recorder": procs.start("play_recorder", [viapath("x")[0], str(Path(__file__).parent / "_ros2_record.py"), str(record)], domain),
                "play": procs.start("play_play", viapath("ros2", "play", str(BAG), "--topic", "right_scan", "--rate", "3"), domain),
                "record": record,
            }

    def paper(self):
        if "paper" not in self.results:
            from test_ros2_e2e import read_trace

            group = self.groups["paper"]
            runs, reference = {}, {}
            for name, pair in group["pairs"].items():
                runs[name] = (pair.finish(), read_trace(pair.trace), pair.sim_stderr)
            for name, proc in group["references"].items():
                assert self.procs.wait(proc, 150) == 0
                reference[name] = json.loads(self.procs.output(proc)[0].strip().splitlines()[-1])
            self.results["paper"] = (runs, reference)
        return self.results["paper"]

    def faults(self):
        if "faults" not in self.results:
            from test_ros2_e2e import read_trace

            out = {}
            for name, pair in self.groups["faults"].items():
                metrics = pair.finish()
                out[name] = (metrics, read_trace(pair.trace), pair.statuses)
            self.results["faults"] = out
        return self.results["faults"]

    def play(self):
        if "play" not in self.groups:
            pytest.skip(f"{BAG} not found (../shared/data absent)")
        if "play" not in self.results:
            group = self.groups["play"]
            code = self.procs.wait(group["play"], 150)
            _, err = self.procs.output(group["play"])
            assert code == 0, err
            import time

            time.sleep(1.0)
            self.procs.stop(group["node"])
            self.procs.stop(group["recorder"])
            lines = group["record"].read_text().splitlines()
            self.results["play"] = [json.loads(line) for line in lines if line.strip()]
        return self.results["play"]


@pytest.fixture(scope="session")
def ros2_launcher(tmp_path_factory):
    from viapath.ros2 import rclpy_available

    ok, why = rclpy_available()
    if not ok:
        pytest.skip(why)
    launcher = Launcher(tmp_path_factory.mktemp("ros2_e2e"))
    try:
        launcher.start_all()
        yield launcher
    finally:
        launcher.procs.stop_all()


def pytest_collection_modifyitems(session, config, items):
    """Tests that read the launched processes go last, so the fast ones run while those processes work."""
    items.sort(key=lambda item: "ros2_launcher" in getattr(item, "fixturenames", ()) or
               any(name in getattr(item, "fixturenames", ()) for name in ("paper_runs", "fault_runs", "play_tracks")))


@pytest.fixture(scope="session", autouse=True)
def _start_ros2_processes_early(request):
    """Start the launcher with the first test when any collected test needs it."""
    wanted = ("ros2_launcher", "paper_runs", "fault_runs", "play_tracks", "in_process")
    if any(any(n in getattr(item, "fixturenames", ()) for n in wanted) for item in request.session.items):
        from viapath.ros2 import rclpy_available

        if rclpy_available()[0]:
            request.getfixturevalue("ros2_launcher")
    yield
