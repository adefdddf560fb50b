"""Start and end the processes of a ROS 2 test: each keeps DDS on this machine, in a domain of its own.

Every process gets ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and a ``ROS_DOMAIN_ID`` that no
other test (nor another pytest worker or run started at the same time) uses; :class:`Processes` ends
each by its pid (SIGTERM, then SIGKILL after a timeout), also when the test fails.

A domain is claimed with an exclusive lock on a file of its own in the temporary folder, held until
this process exits: pytest-xdist's workers (and other runs with this code) never share one, even
when two ask at the same instant, before either has started a process in it.
"""

from __future__ import annotations

import fcntl
import itertools
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

_counter = itertools.count()
_claimed: dict[int, object] = {}  # domain -> its lock file, open (locked) until this process exits


def _domains_in_use() -> set[int]:
    """ROS_DOMAIN_IDs of processes running on this machine (other test runs share it)."""
    used = set()
    for environ in Path("/proc").glob("[0-9]*/environ"):
        try:
            for item in environ.read_bytes().split(b"\0"):
                if item.startswith(b"ROS_DOMAIN_ID="):
                    used.add(int(item.split(b"=", 1)[1] or 0))
        except (OSError, ValueError):
            continue
    return used


def _claim(domain: int) -> bool:
    """Lock the domain's file for this process (True), unless another process holds it."""
    if domain in _claimed:
        return True
    handle = (Path(tempfile.gettempdir()) / f"viapath-ros2-domain-{domain}.lock").open("a")
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        handle.close()
        return False
    _claimed[domain] = handle
    return True


def domain_id() -> int:
    """A ROS_DOMAIN_ID in 1..100: claimed by this process (see the module's docstring), not the last
    ones this process handed out (taken in turn), and used by no process on this machine now (DDS in
    one domain would mix the runs)."""
    used = _domains_in_use()
    for _ in range(200):
        domain = 1 + (os.getpid() * 17 + next(_counter)) % 100
        if domain not in used and _claim(domain):
            return domain
    raise RuntimeError("no free ROS_DOMAIN_ID in 1..100 on this machine")


def ros_env(domain: int) -> dict[str, str]:
    env = dict(os.environ)
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_DOMAIN_ID=str(domain), PYTHONUNBUFFERED="1")
    env.pop("ROS_STATIC_PEERS", None)
    return env


def viapath(*args: str) -> list[str]:
    return [sys.executable, "-m", "viapath.cli", *args]


class Processes:
    """Processes started by one test or fixture; :meth:`stop_all` ends every one of them by pid."""

    def __init__(self, folder: Path):
        self.folder = Path(folder)
        self.started: list[tuple[subprocess.Popen, Path, Path]] = []

    def start(self, name: str, args: list[str], domain: int) -> subprocess.Popen:
        out, err = self.folder / f"{name}.out", self.folder / f"{name}.err"
        proc = subprocess.Popen(
            args, env=ros_env(domain), stdout=out.open("w"), stderr=err.open("w"), stdin=subprocess.DEVNULL
        )
        self.started.append((proc, out, err))
        return proc

    def output(self, proc) -> tuple[str, str]:
        for p, out, err in self.started:
            if p is proc:
                return out.read_text(), err.read_text()
        raise KeyError(proc)

    def wait(self, proc, timeout_s: float) -> int:
        try:
            return proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            _out, err = self.output(proc)
            raise AssertionError(
                f"process {proc.args} still running after {timeout_s} s; stderr: {err[-2000:]}"
            ) from None

    @staticmethod
    def stop(proc, timeout_s: float = 10.0) -> None:
        if proc.poll() is not None:
            return
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=timeout_s)

    def stop_all(self) -> None:
        for proc, _, _ in reversed(self.started):
            self.stop(proc)


class Pair:
    """A planner node and a simulator node in one domain."""

    def __init__(self, procs: Processes, name: str, scenario: str, sim_args=(), node_args=(), rate: float = 20.0):
        self.procs, self.name = procs, name
        self.domain = domain_id()
        self.trace = procs.folder / f"{name}_trace.csv"
        self.commands = procs.folder / f"{name}_commands.csv"
        self.status = procs.folder / f"{name}_status.jsonl"
        self.node = procs.start(f"{name}_node", viapath("ros2", "node", "--use-sim-time", *node_args), self.domain)
        self.sim = procs.start(
            f"{name}_sim",
            viapath(
                "ros2",
                "sim",
                scenario,
                "--rate",
                str(rate),
                "--lockstep",
                "--json",
                "--trace",
                str(self.trace),
                "--commands",
                str(self.commands),
                "--status-log",
                str(self.status),
                "--wait-s",
                "300",  # for the node to come up: slow on a loaded machine
                *sim_args,
            ),
            self.domain,
        )

    def finish(self, timeout_s: float = 150.0) -> dict:
        code = self.procs.wait(self.sim, timeout_s)
        out, err = self.procs.output(self.sim)
        _node_out, node_err = self.procs.output(self.node)
        self.procs.stop(self.node)
        assert code == 0, f"{self.name}: sim exited {code}: {err[-3000:]}\nnode: {node_err[-2000:]}"
        self.sim_stderr = err
        self.statuses = [json.loads(line) for line in self.status.read_text().splitlines() if line.strip()]
        return json.loads(out.strip().splitlines()[-1])


def wait_until(predicate, timeout_s: float, period_s: float = 0.05) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(period_s)
    return predicate()


class Nav2Run:
    """viapath as Nav2's controller (``viapath ros2 nav2``), the simulator with TF, and a client of
    ours in Nav2's part (``viapath ros2 follow``: lifecycle, goals re-sent every second), in one domain."""

    MAP_OFFSET = "1.5,-2.0,0.6"  # map -> odom: the paths go in the map frame, the node must use TF

    def __init__(
        self,
        procs: Processes,
        name: str,
        scenario: str,
        node_params=(),
        client_args=(),
        sim_args=(),
        rate: float = 20.0,
        lockstep: bool = True,
    ):
        self.procs, self.name = procs, name
        self.domain = domain_id()
        self.trace = procs.folder / f"{name}_trace.csv"
        self.log = procs.folder / f"{name}_client.jsonl"
        params = [a for p in node_params for a in ("-p", p)]
        self.node = procs.start(
            f"{name}_node",
            viapath("ros2", "nav2", "--use-sim-time", *(["--ros-args", *params] if params else [])),
            self.domain,
        )
        self.sim = procs.start(
            f"{name}_sim",
            viapath(
                "ros2",
                "sim",
                scenario,
                "--rate",
                str(rate),
                *(["--lockstep"] if lockstep else []),
                "--json",
                "--trace",
                str(self.trace),
                "--map-offset",
                self.MAP_OFFSET,
                "--linger",
                "1.5",
                "--wait-s",
                "300",
                *sim_args,
            ),
            self.domain,
        )
        self.client = procs.start(
            f"{name}_client",
            viapath(
                "ros2",
                "follow",
                scenario,
                "--map-offset",
                self.MAP_OFFSET,
                "--lifecycle",
                "controller_server",
                "--log",
                str(self.log),
                "--wait-s",
                "300",
                *client_args,
            ),
            self.domain,
        )

    def records(self) -> list[dict]:
        if not self.log.is_file():
            return []
        return [json.loads(line) for line in self.log.read_text().splitlines() if line.strip()]

    def finish(self, timeout_s: float = 420.0) -> tuple[dict, list[dict]]:
        code = self.procs.wait(self.sim, timeout_s)
        out, err = self.procs.output(self.sim)
        # the last result may still be on its way
        wait_until(
            lambda: any(
                r["kind"] == "result" and r["label"] == "path" and r["error_msg"] != "preempted by a new path"
                for r in self.records()
            ),
            5.0,
        )
        try:  # the client ends with the path goal's result (its exit code says how it ended)
            self.client_code = self.client.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.client_code = None
        self.procs.stop(self.client)
        self.procs.stop(self.node)
        _, node_err = self.procs.output(self.node)
        _, client_err = self.procs.output(self.client)
        assert code == 0, (
            f"{self.name}: sim exited {code}: {err[-3000:]}\nnode: {node_err[-2000:]}\nclient: {client_err[-1500:]}"
        )
        self.sim_stderr, self.node_stderr = err, node_err
        return json.loads(out.strip().splitlines()[-1]), self.records()
