"""Write a run's MCAP in a process of its own, so the run is not slowed by building its messages.

Source: writing the MCAP may cost at most 20 % of the run's wall time and docs/design.md §9.
Building and encoding one cycle's Foxglove messages takes 0.2-0.5 ms of CPU in Python, about as
much as a whole cycle of the paper's scenarios (0.3 ms for paper-front), so in the run's own
process an MCAP doubles a run. A recorder beside the robot is how ROS does it (``ros2 bag
record`` is its own process); we do the same:

* The run's process keeps, per cycle, only what the scene is built from (step, time, robot state,
  the tracks, the command and plan, plan time, the perception's scans/detections/blind region, the
  simulator's truth): the numbers and strings as they are, every array of the cycle in one float
  array with the row counts (:func:`cycle_input`). What stays the same for the run (forecast
  settings, the scanners' names, mounts and beam geometry) goes once, with the first cycle
  (:func:`static_input`). Pickling costs about 2-3 µs per array, so one array instead of a dozen
  is most of the run's share; the rows the scene drops (tracks with a NaN field, people not in
  the scene) are dropped by the writer, and of the plan's extras only those a scene reads go.
* Cycles are pickled and sent down a pipe in batches of up to 8 (or 64 kB): a send and the
  writer's wake-up cost the run ~70 µs of CPU, more than a cycle's packing, and the writer waits
  on the pipe (polling it every millisecond cost the run more). A send is never cut by Ctrl-C
  (:func:`_whole_message`): a batch above 16 kB goes in several writes.
* The writer process builds the :class:`~viapath.viz.scene.CycleScene` with the same
  :class:`~viapath.viz.scene.SceneBuilder` and logs it with the same
  :class:`~viapath.viz.foxglove.FoxglovePublisher` as an in-process view, so the file is the same.
* It is started by ``fork`` where the platform has it (it then inherits the imports: starts in a few
  ms) and ``spawn`` elsewhere. The run does not wait for it: a file that exists without ``force``
  is refused before the process starts (the views check the folder and the rights before that),
  and the writer's report of opening the file is read when the first batch goes (a failure is
  then raised as "could not start"). At the end the run's process sends what it kept and "done",
  and waits for the count of cycles written (the file is then complete; the writer's exit is
  waited for by a thread, not by the run). A run that stops (Ctrl-C, an error) ends the same way,
  so the file holds every cycle that ran. If the writer fails mid-run, the next send or the end
  raises the given error (the views pass :class:`~viapath.viz.foxglove.ViewError`) with its reason.

What the run still pays (paper-front, 239 cycles, ~75 ms of CPU alone; ``benchmarks/bench_mcap.py``):
the fork and the copy-on-write faults of memory it now shares with the writer (~1500 faults,
~5-8 ms), packing (~15 µs a cycle), the sends (~30 of them, ~3 ms), and the last batch written
after the run; on a machine whose two cores are both busy, the writer's CPU too.

Choices: a pipe rather than a ``multiprocessing.Queue`` (no feeder thread competing for the GIL);
when the writer falls behind, the run waits on the pipe (its buffer holds tens of batches), so
memory stays bounded and the file is complete. The live view stays in the run's process: it paces
the run.
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import signal
import threading
import traceback
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

import numpy as np

_READY, _DONE, _FAILED = "ready", "done", "failed"
# Cycles go to the writer in batches: one send (a system call and a wake-up of the writer, ~70 µs
# of the run's CPU on a 2-core VM) per batch instead of per cycle. Bounded by count and by size
# (a laser cycle is ~13 kB); small enough that the last batch, written after the run, is quick.
BATCH_CYCLES, BATCH_BYTES = 8, 64_000
_PICKLE = pickle.HIGHEST_PROTOCOL


def _start_method() -> str:
    return "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"


# The plan's extras a scene reads (viapath.viz.scene: the plan's times, the cost breakdown, the
# shield's verdict); the rest (which code path ran, the shield's diagnostics) stays in the run's process.
_SCENE_EXTRAS = ("waypoint_times_s", "slow_s", "speed_after_mps", "cost_terms", "shield_intervened")


def static_input(record) -> tuple:
    """What stays the same for a whole run, sent once with the first cycle: the x-y-t view's forecast
    settings and each scanner's name, mount and beam geometry (see module notes)."""
    from viapath.viz.scene import ForecastSettings

    perception = record.perception if record.scans is not None else None
    scanners = tuple(
        (
            str(m.name),
            np.asarray(m.mount_pose(), dtype=float),
            float(m.angle_min_rad),
            float(m.angle_increment_rad),
            float(m.range_min_m),
            float(m.range_max_m),
        )
        for m in (getattr(perception, "scanners", ()) or ())
    )
    return ForecastSettings.from_planner(record.planner), scanners


def cycle_input(record) -> tuple:
    """What one cycle's scene is built from: a few numbers and strings, and every array of the cycle
    (tracks, the true people, the plan's points and costs, scans, detections, blind region) in one
    float array with the row counts (see module notes); :func:`scene_inputs` unpacks it."""
    state, decision = record.state, record.decision
    plan, command = decision.plan, decision.command
    sectors, counts, numbers = _cycle_arrays(record)
    target = np.asarray(plan.target, dtype=float).reshape(2)
    return (
        record.step,
        record.time_s,
        state.x,
        state.y,
        state.heading_rad,
        state.speed_mps,
        state.turn_rate_radps,
        command.speed_mps,
        command.turn_rate_radps,
        record.plan_time_ms,
        plan.status,
        plan.speed_mps,
        float(target[0]),
        float(target[1]),
        plan.subgoal_index,
        plan.candidate_count,
        plan.chosen,
        _scene_extras(plan.extras),
        sectors,
        counts,
        numbers,
    )


def _cycle_arrays(record) -> tuple[Any, tuple, np.ndarray]:
    """The blind sectors, the row counts and the one float array of a cycle (see :func:`cycle_input`)."""
    from viapath.viz.scene import perception_arrays_of

    world, plan = record.world, record.decision.plan
    tracks = record.observation.obstacles  # all rows: the scene keeps the finite ones, as it does in-process
    detections, radii, points, sectors, blind = perception_arrays_of(
        record.perception if record.scans is not None else None
    )
    lines = [np.asarray(line, dtype=float).reshape(-1) for line in plan.candidate_polylines]
    via = np.asarray(plan.via_points, dtype=float).reshape(-1)
    waypoints = np.asarray(plan.waypoints, dtype=float).reshape(-1)
    costs = np.asarray(plan.candidate_costs, dtype=float).reshape(-1)
    scans = [np.asarray(ranges, dtype=float).reshape(-1) for ranges in (record.scans or ())]
    pieces = [
        tracks.positions.reshape(-1),
        tracks.velocities.reshape(-1),
        tracks.radii_m,
        tracks.position_sigma_m,
        tracks.velocity_sigma_mps,
        tracks.ids,
        via,
        waypoints,
        costs,
        *lines,
        *scans,
        detections.reshape(-1),
        radii,
        points.reshape(-1),
        blind.reshape(-1),
    ]
    truth = 0
    if world is not None:
        truth = len(world.obstacle_radii_m)
        pieces += [world.obstacle_positions.reshape(-1), world.obstacle_velocities.reshape(-1), world.obstacle_radii_m]
    static = np.asarray(record.observation.static.segments, dtype=float)
    pieces.append(static.reshape(-1))
    counts = (
        len(tracks),
        truth if world is not None else -1,
        len(via) // 2,
        len(waypoints) // 2,
        len(costs),
        tuple(len(line) // 2 for line in lines),
        tuple(len(ranges) for ranges in scans),
        len(radii),
        len(points),
        len(blind),
        len(static),
    )
    return sectors, counts, np.concatenate(pieces)


def _scene_extras(extras: dict | None) -> dict:
    """The plan's extras a scene reads (of the shield's verdict only whether it intervened)."""
    extras = extras or {}
    kept = {name: extras[name] for name in _SCENE_EXTRAS if name in extras}
    shield = extras.get("shield")
    if isinstance(shield, dict):
        kept["shield"] = {"intervened": bool(shield.get("intervened"))}
    return kept


def scene_inputs(payload: tuple, static: tuple) -> tuple:
    """The arguments of :meth:`viapath.viz.scene.SceneBuilder.build` (step, time, pose, speed, turn
    rate, observation, decision, plan time; then ``true_people`` and ``perception_parts``) from a
    :func:`cycle_input` payload and the run's :func:`static_input`."""
    from viapath.observation import Command, Decision, Plan
    from viapath.viz.scene import ScannerView

    (
        step,
        time_s,
        x,
        y,
        heading,
        speed,
        turn_rate,
        command_speed,
        command_turn_rate,
        plan_time_ms,
        status,
        plan_speed,
        target_x,
        target_y,
        subgoal_index,
        candidate_count,
        chosen,
        extras,
        sectors,
        counts,
        numbers,
    ) = payload
    tracks, via, waypoints, costs, lines, scans, detections, radii, points, blind, truth, static_segments = (
        _unpack_arrays(counts, numbers)
    )
    plan = Plan(
        status,
        plan_speed,
        np.array([target_x, target_y]),
        via,
        waypoints,
        subgoal_index,
        candidate_count,
        costs,
        lines,
        chosen,
        extras,
    )
    _, scanner_statics = static
    scanners = [
        ScannerView(name, mount, angle_min, increment, ranges, range_min, range_max)
        for (name, mount, angle_min, increment, range_min, range_max), ranges in zip(scanner_statics, scans)
    ]
    decision = Decision(Command(command_speed, command_turn_rate), plan)
    return (
        step,
        time_s,
        (x, y, heading),
        speed,
        turn_rate,
        _Tracks(tracks, static_segments),
        decision,
        plan_time_ms,
        truth,
        (scanners, detections, radii, points, sectors, blind),
    )


def _unpack_arrays(counts: tuple, numbers: np.ndarray) -> tuple:
    """The cycle's arrays from its one float array, in the order :func:`_cycle_arrays` packed them:
    tracks, via points, waypoints, costs, candidate lines, scans, detections and their radii, points,
    blind region, the true people (None: no simulator truth) and the static segments."""
    (
        n,
        truth_count,
        via_count,
        waypoint_count,
        cost_count,
        line_counts,
        scan_counts,
        detection_count,
        point_count,
        blind_count,
        static_count,
    ) = counts
    cursor = _Cursor(numbers)
    tracks = _obstacles(
        cursor.rows(n, 2), cursor.rows(n, 2), cursor.rows(n), cursor.rows(n), cursor.rows(n), cursor.rows(n).astype(int)
    )
    via, waypoints, costs = cursor.rows(via_count, 2), cursor.rows(waypoint_count, 2), cursor.rows(cost_count)
    lines = [cursor.rows(count, 2) for count in line_counts]
    scans = [cursor.rows(count) for count in scan_counts]
    detections, radii = cursor.rows(detection_count, 2), cursor.rows(detection_count)
    points, blind = cursor.rows(point_count, 2), cursor.rows(blind_count, 2)
    truth = _true_people(cursor, truth_count) if truth_count >= 0 else None
    static_segments = cursor.rows(static_count, 4).reshape(-1, 2, 2)
    return tracks, via, waypoints, costs, lines, scans, detections, radii, points, blind, truth, static_segments


def _true_people(cursor: _Cursor, truth_count: int):
    """The simulator's people in the scene (those with a finite position; ids their rows)."""
    positions, velocities, truth_radii = (
        cursor.rows(truth_count, 2),
        cursor.rows(truth_count, 2),
        cursor.rows(truth_count),
    )
    present = np.isfinite(positions).all(axis=1)
    if present.all():  # everyone in the scene: no copies
        zeros = np.zeros(truth_count)
        return _obstacles(positions, velocities, truth_radii, zeros, zeros, np.arange(truth_count))
    zeros = np.zeros(int(present.sum()))
    return _obstacles(
        positions[present], velocities[present], truth_radii[present], zeros, zeros, np.flatnonzero(present)
    )


class _Cursor:
    """Reads consecutive blocks of rows from the cycle's float array (views, no copies)."""

    __slots__ = ("numbers", "start")

    def __init__(self, numbers: np.ndarray) -> None:
        self.numbers, self.start = numbers, 0

    def rows(self, count: int, width: int = 0) -> np.ndarray:
        size = count * (width or 1)
        block = self.numbers[self.start : self.start + size]
        self.start += size
        return block.reshape(count, width) if width else block


class _Tracks:
    """An observation as far as a scene reads one: its tracks and its static segments."""

    __slots__ = ("obstacles", "static_segments")

    def __init__(self, obstacles, static_segments) -> None:
        self.obstacles = obstacles
        self.static_segments = static_segments


_OBSTACLE_ROWS = ("positions", "velocities", "radii_m", "position_sigma_m", "velocity_sigma_mps", "ids")


def _obstacles(*rows):
    """An :class:`~viapath.observation.Obstacles` from fields taken from one (they were checked when it
    was made): its shape checks are the writer's largest cost per cycle otherwise. ``rows``: the arrays
    of :data:`_OBSTACLE_ROWS`, in that order."""
    from viapath.observation import Obstacles

    obstacles = object.__new__(Obstacles)
    vars(obstacles).update(zip(_OBSTACLE_ROWS, rows, strict=True))
    return obstacles


def _writer_main(
    connection, publisher_class, file: str, force: bool, waypoints, half_widths_m, robot_radius_m: float, settings
) -> None:
    """The writer process: open the file, then build and log each cycle until told it is done."""
    # Ctrl-C reaches the whole process group: the run's process decides when the file ends (it sends
    # "done" from its clean-up), so the writer does not stop half-way on its own.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    writer = None
    try:
        import foxglove
        from foxglove.mcap import MCAPCompression, MCAPWriteOptions

        from viapath.path import DesignatedPath

        context = foxglove.Context()
        writer = foxglove.open_mcap(
            file,
            allow_overwrite=force,
            context=context,
            writer_options=MCAPWriteOptions(compression=MCAPCompression.Lz4),
        )
        # Ready once the file is open (what can fail for a reason of the user's); the run starts while
        # the rest is set up, and a failure from here on is reported at the next send or the end.
        connection.send((_READY, None))
        path = DesignatedPath(waypoints, half_widths_m=half_widths_m)
        publisher = publisher_class(context, path, robot_radius_m, settings)
        while True:
            # Waiting on the pipe: each batch wakes the writer once. (Polling it every millisecond
            # instead cost the run's process more CPU, ~7 ms per paper-front run on a 2-core VM.)
            message = connection.recv_bytes()
            if message == b"":
                break
            static, payloads = pickle.loads(message)
            if static is not None:
                publisher.start(static)
            for payload in payloads:
                publisher.publish(publisher.build(payload))
        writer.close()
        writer = None
        connection.send((_DONE, publisher.cycles))
    except BaseException as error:  # every failure goes back to the run's process as text
        if writer is not None:
            with suppress(Exception):
                writer.close()
        with suppress(Exception):
            connection.send((_FAILED, f"{type(error).__name__}: {error}\n{traceback.format_exc(limit=4)}"))
    finally:
        connection.close()


class MCAPWriterProcess:
    """The ``on_step`` callback that hands each cycle to a writer process (see module notes).
    ``publisher_class`` logs a scene on a foxglove context (:class:`viapath.viz.foxglove.FoxglovePublisher`,
    passed in so that this module does not import the one that uses it); ``error`` is the
    exception raised when the writer fails."""

    def __init__(
        self,
        file: Path | str,
        force: bool,
        path,
        robot_radius_m: float,
        publisher_class,
        error: type[Exception] = RuntimeError,
        settings=None,
    ):
        self._error = error
        self.file = Path(file)
        self.cycles = 0  # handed to the writer (sent or pending)
        self._static: tuple[Any, ...] | None = None
        self._static_sent = False
        self._pending: list[tuple] = []
        self._pending_bytes = 0
        ctx = multiprocessing.get_context(_start_method())
        self._connection, child = ctx.Pipe(duplex=True)
        self.process = ctx.Process(  # type: ignore[attr-defined]
            target=_writer_main,
            name="viapath-mcap-writer",
            daemon=True,
            args=(
                child,
                publisher_class,
                str(self.file),
                force,
                np.asarray(path.waypoints, dtype=float),
                np.asarray(path.half_widths_m, dtype=float),
                float(robot_radius_m),
                settings,
            ),
        )
        if self.file.exists() and not force:  # the one refusal foreseen: said before the process starts
            raise error(f"--mcap {self.file}: the writer could not start (file exists; add --force to overwrite it)")
        self.process.start()
        child.close()
        self._ready = False  # the writer's "ready" is read when the first batch goes, not waited for

    def _check_ready(self, wait: bool) -> None:
        """Read the writer's report of opening the file once it has come (``wait``: until it comes)."""
        if self._ready or not (wait or self._connection.poll(0)):
            return
        kind, detail = self._receive()
        if kind != _READY:
            self._stop()
            raise self._error(f"--mcap {self.file}: the writer could not start ({detail})")
        self._ready = True

    def _receive(self) -> tuple[str, Any]:
        try:
            return self._connection.recv()
        except (EOFError, OSError):
            return _FAILED, f"the writer process ended with exit code {self.process.exitcode}"

    def __call__(self, record) -> None:
        if self._static is None:
            self._static = static_input(record)
        payload = cycle_input(record)
        self._pending.append(payload)
        self._pending_bytes += payload[-1].nbytes
        self.cycles += 1
        if len(self._pending) >= BATCH_CYCLES or self._pending_bytes >= BATCH_BYTES:
            self._send_pending()

    def _send_pending(self) -> None:
        """Send the cycles kept so far (with the run's static part before the first)."""
        self._check_ready(wait=False)
        static = self._static if not self._static_sent else None
        message = pickle.dumps((static, self._pending), protocol=_PICKLE)
        self._pending, self._pending_bytes, self._static_sent = [], 0, True
        try:
            with _whole_message():
                self._connection.send_bytes(message)
        except (BrokenPipeError, OSError):
            self._check_ready(wait=True)  # a writer that could not open the file says so
            _kind, detail = self._receive()
            self._stop()
            raise self._error(f"--mcap {self.file}: the writer failed ({detail})") from None

    def close(self) -> int:
        """Tell the writer the run is over, wait for it to finish the file; the cycles it wrote."""
        if self.process is None:
            return self.cycles
        if self._pending:
            self._send_pending()
        try:
            with _whole_message():
                self._connection.send_bytes(b"")
        except (BrokenPipeError, OSError):
            pass
        self._check_ready(wait=True)
        kind, detail = self._receive()
        self._stop(reap_later=kind == _DONE)
        if kind != _DONE:
            raise self._error(f"--mcap {self.file}: the writer failed ({detail})")
        if detail != self.cycles:
            raise self._error(f"--mcap {self.file}: the writer wrote {detail} of {self.cycles} cycles")
        return detail

    def _stop(self, reap_later: bool = False) -> None:
        """End the writer process. ``reap_later``: it has closed the file and is exiting (which takes
        a few ms: its copy of the run's memory is released); a thread waits for it instead of the run."""
        process, self.process = self.process, None
        if process is None:
            return
        self._connection.close()
        if reap_later and process.is_alive():
            reaper = threading.Thread(target=_reap, args=(process,), name="viapath-mcap-reaper", daemon=True)
            reaper.start()
            _REAPERS.append(reaper)
            return
        _reap(process)


_REAPERS: list[threading.Thread] = []


@contextmanager
def _whole_message():
    """Hold a Ctrl-C until the message is sent: a batch above 16 kB goes in several writes, and an
    interrupt between two would leave the writer waiting for the rest of it (and the run waiting
    for the writer). The signal is raised again, as it came, once the message is out. Main thread
    only (where Python runs signal handlers); elsewhere the send is as it is."""
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or not callable(previous):
        yield  # not the main thread, or Ctrl-C ignored or handled outside Python
        return
    caught: list[int] = []
    signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if caught:
            os.kill(os.getpid(), signal.SIGINT)


def _reap(process) -> None:
    process.join(timeout=30)
    if process.is_alive():
        process.kill()
        process.join()


def wait_for_writers() -> None:
    """Wait until every writer process that finished its file has exited (benchmarks read the
    writers' CPU time, which counts once they are reaped)."""
    while _REAPERS:
        _REAPERS.pop().join()
