"""``viapath run --live``: a WebSocket client on loopback (Foxglove's protocol, subprotocol
foxglove.sdk.v1) sees the advertised channels and messages while a run plays, and the server is gone
when the run ends or is interrupted (SIGINT)."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("foxglove", reason="needs the viz extra (foxglove-sdk)")
ws_client = pytest.importorskip("websockets.sync.client", reason="needs the viz-test extra (websockets)")

SRC = Path(__file__).resolve().parents[2] / "src"
TOPICS = {
    "/tf",
    "/robot/footprint",
    "/perception/tracks",
    "/path",
    "/world/static",
    "/plan/candidates",
    "/plan/chosen",
    "/plan/costs",
    "/xyt",
    "/metrics",
}


class _Run:
    """``viapath run ... --live --port 0`` in a process of its own, its output in files (no pipe to fill)."""

    def __init__(self, folder: Path, *args: str):
        env = {**os.environ, "PYTHONPATH": str(SRC) + os.pathsep + os.environ.get("PYTHONPATH", "")}
        self.out, self.err = folder / "stdout.txt", folder / "stderr.txt"
        with open(self.out, "w") as out, open(self.err, "w") as err:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "viapath.cli", "run", *args, "--live", "--port", "0"],
                stdout=out,
                stderr=err,
                env=env,
            )
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            found = re.search(r"ws://127\.0\.0\.1:(\d+)", self.err.read_text())
            if found:
                self.port = int(found.group(1))
                return
            if self.process.poll() is not None:
                break
            time.sleep(0.05)
        self.kill()
        pytest.fail(f"the live run did not announce its address: {self.err.read_text()}")

    def wait(self, timeout_s: float) -> tuple[int, str, str]:
        code = self.process.wait(timeout=timeout_s)
        return code, self.out.read_text(), self.err.read_text()

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


class _Client:
    """Subscribes to every advertised channel; keeps (topic -> [log_time_ns]) and receive times."""

    def __init__(self, port: int):
        self._connection = ws_client.connect(
            f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"], open_timeout=10
        )
        self.socket = self._connection.__enter__()  # left in close()
        self.channels: dict[int, dict] = {}
        self.log_times: dict[str, list[int]] = {}
        self.received_at: dict[str, list[float]] = {}
        self.ops: list[str] = []

    def pump(self, until_messages: int | None = None, timeout_s: float = 60.0) -> str:
        """Read until the server closes (returns 'closed') or ``until_messages`` arrived ('enough')."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            try:
                frame = self.socket.recv(timeout=max(0.1, deadline - time.monotonic()))
            except TimeoutError:
                break
            except Exception:  # the server closed the connection
                return "closed"
            if isinstance(frame, str):
                message = json.loads(frame)
                self.ops.append(message["op"])
                if message["op"] == "advertise":
                    subscriptions = []
                    for channel in message["channels"]:
                        self.channels[channel["id"]] = channel
                        subscriptions.append({"id": channel["id"], "channelId": channel["id"]})
                    self.socket.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
            elif frame[0] == 1:  # message data: opcode, subscription id (u32), log time (u64), payload
                subscription, log_time = struct.unpack_from("<IQ", frame, 1)
                topic = self.channels[subscription]["topic"]
                self.log_times.setdefault(topic, []).append(log_time)
                self.received_at.setdefault(topic, []).append(time.monotonic())
                if until_messages is not None and sum(map(len, self.log_times.values())) >= until_messages:
                    return "enough"
        return "timeout"

    def close(self):
        self._connection.__exit__(None, None, None)


def _refused(port: int) -> bool:
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=2):
            return False
    except OSError:
        return True


def test_live_run_serves_every_topic_and_stops_at_the_end(tmp_path):
    rate = 8.0
    run = _Run(tmp_path, "paper-behind", "--rate", str(rate), "--json")
    port = run.port
    client = _Client(port)
    try:
        outcome = client.pump(timeout_s=120)
        code, stdout, stderr = run.wait(60)
    finally:
        client.close()
        run.kill()
    assert code == 0, stderr
    assert outcome == "closed", (outcome, stderr)
    assert "serverInfo" in client.ops and "advertise" in client.ops
    assert {c["topic"] for c in client.channels.values()} == TOPICS
    schemas = {c["topic"]: c["schemaName"] for c in client.channels.values()}
    assert schemas["/tf"] == "foxglove.FrameTransforms" and schemas["/xyt"] == "foxglove.SceneUpdate"
    metrics = json.loads(stdout.strip().splitlines()[-1])
    cycles = round(metrics["time_to_goal_s"] / 0.1)
    for topic in TOPICS:
        times = client.log_times.get(topic, [])
        # From the moment the client's subscription took effect (it connects while the run plays,
        # so under load it may miss a few seconds of simulated time) to the last cycle, every cycle
        # arrives, in order, on the 0.1 s grid of simulated time.
        assert len(times) >= cycles // 2, (topic, len(times), cycles, client.ops, stderr)
        assert all(b - a == 100_000_000 for a, b in zip(times, times[1:])), topic
        assert times[-1] == (cycles - 1) * 100_000_000, (topic, times[-1], cycles)
    # Paced: simulated time does not run faster than `rate` times the wall clock.
    tf_times, arrivals = client.log_times["/tf"], client.received_at["/tf"]
    simulated_s = (tf_times[-1] - tf_times[0]) / 1e9
    assert arrivals[-1] - arrivals[0] >= 0.8 * simulated_s / rate
    assert _refused(port)


def test_live_run_interrupted_stops_the_server(tmp_path):
    run = _Run(tmp_path, "paper-front", "--rate", "1")
    port = run.port
    client = _Client(port)
    try:
        assert client.pump(until_messages=30, timeout_s=60) == "enough"
        run.process.send_signal(signal.SIGINT)
        code, _, stderr = run.wait(20)
        assert client.pump(timeout_s=10) == "closed"
    finally:
        client.close()
        run.kill()
    assert code == 130
    assert "interrupted" in stderr and "Traceback" not in stderr
    assert _refused(port)
