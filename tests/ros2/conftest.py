"""One launcher for every ROS 2 end-to-end test: all process groups start at once (each pair in a
ROS domain of its own), so their start-up and lock-step waiting overlap; each test module then
collects its group. Every process is ended by pid when the session ends, also on failure."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest
from _ros2_procs import Nav2Run, Pair, Processes, domain_id, viapath

DATA = Path(os.environ.get("VIAPATH_DATA", Path(__file__).resolve().parents[3] / "shared" / "data"))
BAG = DATA / "leg_tracker_laser" / "positive_2.bag"
PAPER = ("paper-behind", "paper-front", "paper-side")
EMPTY = """name: empty-corridor
robot: {start: [0.0, 0.0], heading: 0.0, speed: 0.3, radius: 0.25}
path: {waypoints: [[0.0, 0.0], [12.0, 0.0]], half_width: 1.0}
obstacles: []
duration_s: 60
"""
FRONT_FAULTS = ["silence:front@1.0-2.2", "nan:front@3.0-4.2", "odom@5.0-6.4", "clock-back:3@7.5"]
REAR_FAULTS = ["silence:rear@1.0-2.5", "short:rear@3.5-5.0"]
FRONT_DURATION_S, REAR_DURATION_S = 9.5, 6.0


def reference_metrics(name: str) -> dict:
    """``viapath run NAME --perception laser --json``, in this process."""
    from viapath.scenarios import load_scenario
    from viapath.sim.loop import run_episode

    spec = load_scenario(name)
    spec = spec.model_copy(
        update={"perception": spec.perception.model_copy(update={"options": {"detector": {"keep_segments": False}}})}
    )
    return run_episode(spec, perception="laser").metrics


NAV2_EMPTY = """name: nav2-corridor
robot: {start: [0.0, 0.0], heading: 0.0, speed: 0.3, radius: 0.25}
path: {waypoints: [[0.0, 0.0], [8.0, 0.0]], half_width: 1.0}
obstacles: []
duration_s: 12
"""
NAV2_BEND = "waypoints: [[0.0, 0.0], [1.0, 0.0], [4.0, 1.0], [8.0, 1.0]]\n"
# A closed door across the corridor (a person standing there is, after the tracker's static_after_s, static
# geometry too, which makes when the robot stands depend on the node's timing).
NAV2_BLOCKED = """name: nav2-blocked
robot: {start: [0.0, 0.0], heading: 0.0, speed: 0.3, radius: 0.25}
path: {waypoints: [[0.0, 0.0], [6.0, 0.0]], half_width: 0.4}
walls:
  - [[1.8, -1.0], [1.8, 1.0]]
duration_s: 12
"""
NAV2_PREEMPT_EVENTS = ["1:clear", "2:preempt:{bend}", "4.5:speed-limit:25", "7:cancel"]
NAV2_DEACTIVATE_AT_S = 2.0
NAV2_PATIENCE_S = 3.0


def mixed_scenario(folder: Path) -> tuple[Path, dict]:
    """One scene of the ``mixed`` suite (seed 0, three people): the same file ``viapath suite mixed`` writes."""
    from viapath.bench.suites import generate_suite, write_suite

    scenario = generate_suite("mixed", 5, seed=0)[4]
    return write_suite([scenario], folder / "mixed")[0], scenario


PLAY_PARAMS = Path(__file__).resolve().parents[2] / "docs" / "ros2_real_scans.yaml"  # the documented recipe's file


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
        from viapath.precompile import precompile

        # The compiled planner and shield into numba's on-disk cache once, here: on a fresh clone each of the
        # dozen node processes below would compile them at once (minutes on two cores; the sims gave up).
        precompile()
        self.groups["paper"] = {
            "pairs": {name: Pair(procs, name, name) for name in PAPER},
        }
        import threading

        references: dict[str, dict] = {}
        thread = threading.Thread(
            target=lambda: references.update({n: reference_metrics(n) for n in PAPER}), daemon=True
        )
        thread.start()
        self.groups["paper"]["references"] = (thread, references)
        scenario = folder / "empty.yaml"
        scenario.write_text(EMPTY)
        node_args = ["--ros-args", "-p", "nominal_speed_mps:=0.3"]
        faults = lambda items: [word for f in items for word in ("--fault", f)]
        self.groups["faults"] = {
            "front": Pair(
                procs, "front", str(scenario), ["--duration", str(FRONT_DURATION_S), *faults(FRONT_FAULTS)], node_args
            ),
            "rear": Pair(
                procs, "rear", str(scenario), ["--duration", str(REAR_DURATION_S), *faults(REAR_FAULTS)], node_args
            ),
        }
        from viapath.ros2 import interfaces

        interfaces.build()  # once, before any process needs it (about two minutes on a fresh machine)
        domain = domain_id()
        out = folder / "hostile.json"
        self.groups["hostile"] = {
            "node": procs.start(
                "hostile_node", viapath("ros2", "node", "--use-sim-time", "--params-file", str(PLAY_PARAMS)), domain
            ),
            "driver": procs.start(
                "hostile_driver",
                [sys.executable, str(Path(__file__).with_name("_hostile_driver.py")), str(out)],
                domain,
            ),
            "out": out,
        }
        if BAG.is_file():
            domain = domain_id()
            record = folder / "play_status.jsonl"
            self.groups["play"] = {  # the commands of docs/ros2.md, "Real scans" (+ --rate, --lockstep, --status-log)
                "node": procs.start(
                    "play_node", viapath("ros2", "node", "--use-sim-time", "--params-file", str(PLAY_PARAMS)), domain
                ),
                "play": procs.start(
                    "play_play",
                    viapath(
                        "ros2",
                        "play",
                        str(BAG),
                        "--topic",
                        "right_scan",
                        "--rate",
                        "4",
                        "--lockstep",
                        "--wait-s",
                        "180",
                        "--status-log",
                        str(record),
                    ),
                    domain,
                ),
                "record": record,
            }
            refusing = folder / "refusing.yaml"  # the bag's frame_id is not laser_refusing: every scan refused
            refusing.write_text(PLAY_PARAMS.read_text().replace('frame_id: ""', "frame_id: laser_refusing"))
            domain = domain_id()
            self.groups["play_refused"] = {
                "node": procs.start(
                    "refused_node", viapath("ros2", "node", "--use-sim-time", "--params-file", str(refusing)), domain
                ),
                "play": procs.start(
                    "refused_play",
                    viapath(
                        "ros2",
                        "play",
                        str(BAG),
                        "--topic",
                        "right_scan",
                        "--rate",
                        "4",
                        "--lockstep",
                        "--wait-s",
                        "180",
                    ),
                    domain,
                ),
            }

    def start_nav2(self) -> None:
        """Started when the first Nav2 test asks (after the other groups are collected), so that the
        two sets of processes do not compete for the cores at start-up."""
        procs, folder = self.procs, self.folder
        empty, bend, blocked = folder / "nav2_empty.yaml", folder / "nav2_bend.yaml", folder / "nav2_blocked.yaml"
        empty.write_text(NAV2_EMPTY)
        bend.write_text(NAV2_BEND)
        blocked.write_text(NAV2_BLOCKED)
        mixed, spec = mixed_scenario(folder)
        at = lambda items: [word for e in items for word in ("--at", e)]
        runs = {
            name: Nav2Run(
                procs, f"nav2_{name}", name, client_args=at(["0:empty", "0:nan"]) if name == "paper-front" else ()
            )
            for name in PAPER
        }
        runs["mixed"] = Nav2Run(
            procs,
            "nav2_mixed",
            str(mixed),
            node_params=[f"half_width_m:={spec['path']['half_width']}", f"nominal_speed_mps:={spec['robot']['speed']}"],
        )
        runs["preempt"] = Nav2Run(
            procs,
            "nav2_preempt",
            str(empty),
            node_params=["nominal_speed_mps:=0.3"],
            client_args=at([e.format(bend=bend) for e in NAV2_PREEMPT_EVENTS]),
            sim_args=["--duration", "10"],
        )
        runs["deactivate"] = Nav2Run(
            procs,
            "nav2_deactivate",
            str(empty),
            node_params=["nominal_speed_mps:=0.3"],
            client_args=at([f"{NAV2_DEACTIVATE_AT_S}:deactivate"]),
            sim_args=["--duration", "4", "--max-wait", "0.3"],
        )  # inactive: no command, no wait
        runs["blocked"] = Nav2Run(
            procs,
            "nav2_blocked",
            str(blocked),
            node_params=["half_width_m:=0.4", "nominal_speed_mps:=0.3", f"progress_patience_s:={NAV2_PATIENCE_S}"],
            sim_args=["--duration", "10"],
        )
        self.groups["nav2"] = {"runs": runs, "mixed": spec}

    def nav2(self):
        if "nav2" not in self.groups:
            self.start_nav2()
        if "nav2" not in self.results:
            self.results["nav2"] = {name: run.finish() for name, run in self.groups["nav2"]["runs"].items()}
        return self.results["nav2"]

    def paper(self):
        if "paper" not in self.results:
            from test_ros2_e2e import read_trace

            group = self.groups["paper"]
            runs, reference = {}, {}
            for name, pair in group["pairs"].items():
                runs[name] = (pair.finish(), read_trace(pair.trace), pair.sim_stderr)
            thread, computed = group["references"]
            thread.join(timeout=300)
            reference = dict(computed)
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

    def hostile(self) -> dict:
        """The phases recorded by _hostile_driver.py against a node run with the real-scans parameters."""
        if "hostile" not in self.results:
            group = self.groups["hostile"]
            code = self.procs.wait(group["driver"], 240)
            _, err = self.procs.output(group["driver"])
            node_alive = group["node"].poll() is None
            self.procs.stop(group["node"])
            assert code == 0, err
            self.results["hostile"] = (
                json.loads(group["out"].read_text()),
                node_alive,
                self.procs.output(group["node"])[1],
            )
        return self.results["hostile"]

    def play_refused(self) -> tuple[int, str]:
        if "play_refused" not in self.groups:
            pytest.skip(f"{BAG} not found (../shared/data absent)")
        group = self.groups["play_refused"]
        code = self.procs.wait(group["play"], 300)
        self.procs.stop(group["node"])
        return code, self.procs.output(group["play"])[1]

    def play(self):
        if "play" not in self.groups:
            pytest.skip(f"{BAG} not found (../shared/data absent)")
        if "play" not in self.results:
            group = self.groups["play"]
            code = self.procs.wait(group["play"], 300)
            _, err = self.procs.output(group["play"])
            assert code == 0, err
            self.procs.stop(group["node"])
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


LAUNCHED = ("ros2_launcher", "paper_runs", "fault_runs", "play_tracks", "in_process", "nav2_runs")


def _launched(item) -> bool:
    return any(name in getattr(item, "fixturenames", ()) for name in LAUNCHED)


def _xdist_worker() -> bool:
    return bool(os.environ.get("PYTEST_XDIST_WORKER"))


def pytest_collection_modifyitems(session, config, items):
    """Tests that read the launched processes go last, so the fast ones run while those processes work.

    Under pytest-xdist they go first: their files are one group, run by one worker (tests/conftest.py),
    which starts the processes at once and waits on them while the other workers run the rest."""
    items.sort(key=lambda item: _launched(item) != _xdist_worker())


@pytest.fixture(scope="session", autouse=True)
def _start_ros2_processes_early(request):
    """Start the launcher with the first test when any collected test needs it (in one process; a
    pytest-xdist worker starts it with the first test of the group, and only the one that runs it)."""
    if not _xdist_worker() and any(_launched(item) for item in request.session.items):
        from viapath.ros2 import rclpy_available

        if rclpy_available()[0]:
            request.getfixturevalue("ros2_launcher")
    yield
