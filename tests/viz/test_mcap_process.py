"""The MCAP written by its own process (viapath.viz.mcap_process) is the file an in-process view
writes, message for message; a run that stops part-way keeps the cycles it ran; a writer that
dies is reported, not hidden."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

pytest.importorskip("foxglove", reason="needs the viz extra (foxglove-sdk)")
mcap_reader = pytest.importorskip("mcap.reader", reason="needs the viz extra (mcap)")

from viapath.scenarios import load_scenario  # noqa: E402
from viapath.sim.loop import run_episode  # noqa: E402
from viapath.viz.foxglove import FoxglovePublisher, ViewError, Views  # noqa: E402
from viapath.viz.mcap_process import MCAPWriterProcess  # noqa: E402


def _messages(file: Path) -> list[tuple[str, int, bytes]]:
    with open(file, "rb") as handle:
        reader = mcap_reader.make_reader(handle)
        return [(channel.topic, message.log_time, message.data) for _, channel, message in reader.iter_messages()]


def _record(scenario, file: Path, in_process: bool, perception: str = "oracle", stop_after: int | None = None):
    with Views(scenario, scenario.planner.name, mcap=file, in_process=in_process) as views:
        if not in_process:
            assert isinstance(views.on_step, MCAPWriterProcess)
            pid = views.on_step.process.pid
            assert pid != os.getpid()

        def on_step(record):
            if stop_after is not None and record.step >= stop_after:
                raise KeyboardInterrupt
            views.on_step(record)

        try:
            return run_episode(
                scenario, perception=perception, planner_overrides=views.planner_overrides, on_step=on_step, seed=0
            )
        except KeyboardInterrupt:
            return None


@pytest.mark.parametrize("name, perception", [("paper-front", "oracle"), ("paper-side", "laser")])
def test_writer_process_writes_the_same_messages_as_in_process(tmp_path, name, perception):
    scenario = load_scenario(name)
    episode = _record(scenario, tmp_path / "child.mcap", in_process=False, perception=perception)
    _record(scenario, tmp_path / "here.mcap", in_process=True, perception=perception)
    child, here = _messages(tmp_path / "child.mcap"), _messages(tmp_path / "here.mcap")
    assert len(child) == len(here) > 0
    cycles = len(episode.trace.times_s) - 1
    assert sum(topic == "/tf" for topic, _, _ in child) == cycles
    # Same order of topics and times; same bytes except where the content is the wall clock.
    assert [(t, s) for t, s, _ in child] == [(t, s) for t, s, _ in here]
    differing = {topic for (topic, _, a), (_, _, b) in zip(child, here) if a != b}
    assert differing <= {"/metrics", "/plan/costs"}  # plan_time_ms is measured, so it differs run to run


def test_a_run_stopped_part_way_keeps_its_cycles(tmp_path):
    file = tmp_path / "stopped.mcap"
    assert _record(load_scenario("paper-front"), file, in_process=False, stop_after=40) is None
    messages = _messages(file)  # a complete, readable file
    assert sum(topic == "/tf" for topic, _, _ in messages) == 40
    assert max(time for _, time, _ in messages) == pytest.approx(39 * 0.1e9, abs=1e3)


def test_a_writer_that_dies_is_reported(tmp_path):
    scenario = load_scenario("paper-front")
    file = tmp_path / "killed.mcap"
    with pytest.raises(ViewError, match="writer"), Views(scenario, scenario.planner.name, mcap=file) as views:
        writer = views.on_step

        def on_step(record):
            if record.step == 5:
                os.kill(writer.process.pid, signal.SIGKILL)
                writer.process.join()
            views.on_step(record)

        run_episode(scenario, planner_overrides=views.planner_overrides, on_step=on_step)
    assert writer.process is None  # ended and reaped


def test_the_writer_refuses_a_file_it_cannot_open(tmp_path):
    scenario = load_scenario("paper-front")
    existing = tmp_path / "there.mcap"
    existing.write_bytes(b"keep me")
    from viapath.path import DesignatedPath

    path = DesignatedPath(scenario.path.waypoints, half_widths_m=scenario.path.widths())
    with pytest.raises(ViewError, match="could not start"):
        MCAPWriterProcess(existing, False, path, scenario.robot.radius, FoxglovePublisher, ViewError)
    assert existing.read_bytes() == b"keep me"


def test_ctrl_c_ends_the_run_and_keeps_a_readable_file(tmp_path):
    """SIGINT to the whole process group (as a terminal's Ctrl-C): the writer ignores it, the run
    ends with 'interrupted' (exit 130) and the file holds the cycles run so far."""
    import subprocess
    import sys
    import time

    import yaml

    long_run = {
        "name": "long-corridor",
        "dt_s": 0.1,
        "duration_s": 300.0,
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.3, "radius": 0.25},
        "path": {"waypoints": [[0.0, 0.0], [80.0, 0.0]], "half_width": 1.5},
        "obstacles": [
            {"start": [6.0 + 3.0 * k, (-1) ** k * 0.4], "velocity": [-0.3, 0.0], "radius": 0.25} for k in range(20)
        ],
    }
    scenario = tmp_path / "long.yaml"
    scenario.write_text(yaml.safe_dump(long_run))
    file = tmp_path / "long.mcap"
    process = subprocess.Popen(
        [sys.executable, "-m", "viapath.cli", "run", str(scenario), "--mcap", str(file)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        deadline = time.monotonic() + 60
        while not (file.exists() and file.stat().st_size > 20_000) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert process.poll() is None, process.communicate()[1]
        os.killpg(process.pid, signal.SIGINT)
        _, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    assert process.returncode == 130, stderr  # stderr says how it ended otherwise
    assert "interrupted" in stderr and "Traceback" not in stderr
    cycles = sum(topic == "/tf" for topic, _, _ in _messages(file))
    assert 0 < cycles < 3000


def test_a_writer_that_cannot_open_its_file_says_so_without_holding_up_the_run(tmp_path):
    """The run does not wait for the writer to open the file: a failure to open it (here a folder
    that does not exist, which the views check first) is raised at the first batch or the end."""
    from viapath.path import DesignatedPath

    scenario = load_scenario("paper-front")
    path = DesignatedPath(scenario.path.waypoints, half_widths_m=scenario.path.widths())
    writer = MCAPWriterProcess(
        tmp_path / "missing" / "x.mcap", False, path, scenario.robot.radius, FoxglovePublisher, ViewError
    )
    with pytest.raises(ViewError, match="could not start"):
        writer.close()
    assert writer.process is None


def test_a_ctrl_c_during_a_send_waits_for_the_whole_message(tmp_path):
    """A batch above 16 kB is written in parts: Ctrl-C in between is held until it is out (then
    raised as it came), so the writer never waits for the rest of a message and the file ends with
    every cycle handed over."""
    scenario = load_scenario("paper-front")
    file = tmp_path / "interrupted.mcap"
    sends = []

    class Interrupting:
        def __init__(self, connection):
            self.connection = connection

        def send_bytes(self, message):
            sends.append(len(message))
            if len(sends) == 3:
                os.kill(os.getpid(), signal.SIGINT)  # arrives while the batch is being sent
            self.connection.send_bytes(message)

        def __getattr__(self, name):
            return getattr(self.connection, name)

    with pytest.raises(KeyboardInterrupt), Views(scenario, scenario.planner.name, mcap=file) as views:
        writer = views.on_step
        writer._connection = Interrupting(writer._connection)
        run_episode(scenario, planner_overrides=views.planner_overrides, on_step=writer, seed=0)
    assert len(sends) >= 4  # three batches, then what was kept and "done" from the clean-up
    cycles = sum(topic == "/tf" for topic, _, _ in _messages(file))
    assert cycles == writer.cycles > 0
