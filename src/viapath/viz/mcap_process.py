"""Write a run's MCAP in a process of its own, so the run is not slowed by building its messages.

Source: issue 14 (writing the MCAP may cost at most 20 % of the run's wall time) and DESIGN §9.
Building Foxglove messages in Python costs about as much per cycle as planning (1.5-3 ms), so in
the run's own process an MCAP doubles the run. A recorder beside the robot is how ROS does it
(``ros2 bag record`` is its own process); we do the same:

* The run's process keeps, per cycle, only what the scene is built from (step, time, robot state,
  the tracks, the command and plan, plan time, the perception's scans/detections/blind region, the
  simulator's truth), packed into a few flat arrays (tracks as one (N, 8) array, every point of the
  plan as one (R, 2) array with row counts), pickles it and sends it down a pipe. Pickled as the
  dataclasses they come in, the same content cost three times as much (about 5 µs per small array).
* The writer process builds the :class:`~viapath.viz.scene.CycleScene` with the same
  :class:`~viapath.viz.scene.SceneBuilder` and logs it with the same
  :class:`~viapath.viz.foxglove.FoxglovePublisher` as an in-process view, so the file is the same.
* It is started by ``fork`` where the platform has it (it then inherits the imports: starts in a few
  ms) and ``spawn`` elsewhere. It opens the file and reports ready (or its error) before the run
  starts; at the end the run's process sends "done" and waits for the count of cycles written.
  If the writer fails mid-run, the next send or the end raises the given error (the views pass
  :class:`~viapath.viz.foxglove.ViewError`) with its reason.

Choices: a pipe rather than a ``multiprocessing.Queue`` (no feeder thread competing for the GIL);
when the writer falls behind, the run waits on the pipe (its buffer holds tens of cycles), so memory
stays bounded and the file is complete. The live view stays in the run's process: it paces the run.
"""

from __future__ import annotations

import multiprocessing
import pickle
import signal
import traceback
from pathlib import Path
from typing import Any

import numpy as np

_READY, _DONE, _FAILED = "ready", "done", "failed"
_PICKLE = pickle.HIGHEST_PROTOCOL


def _start_method() -> str:
    return "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"


def cycle_input(record) -> tuple:
    """What one cycle's scene is built from, packed into a few flat arrays and numbers (see module
    notes); :func:`scene_inputs` unpacks it into the arguments of :meth:`SceneBuilder.build`."""
    from viapath.viz.scene import perception_parts_of

    state, world, decision = record.state, record.world, record.decision
    truth = None
    if world is not None:
        present = np.isfinite(world.obstacle_positions).all(axis=1)
        truth = np.column_stack([world.obstacle_positions[present], world.obstacle_velocities[present],
                                 world.obstacle_radii_m[present], np.flatnonzero(present)])
    parts = perception_parts_of(record.perception if record.scans is not None else None)
    command = decision.command
    return (record.step, record.time_s, (state.x, state.y, state.heading_rad), state.speed_mps,
            state.turn_rate_radps, _pack_obstacles(record.observation.obstacles.finite()),
            (command.speed_mps, command.turn_rate_radps), _pack_plan(decision.plan), record.plan_time_ms,
            _pack_parts(parts), truth)


def scene_inputs(payload: tuple) -> tuple:
    """The arguments of :meth:`viapath.viz.scene.SceneBuilder.build` (step, time, pose, speed, turn
    rate, observation, decision, plan time; then ``true_people`` and ``perception_parts``) from a
    :func:`cycle_input` payload. The observation carries only the finite tracks, all a scene reads."""
    from viapath.observation import Command, Decision

    step, time_s, pose, speed, turn_rate, tracks, command, plan, plan_time_ms, parts, truth = payload
    if truth is not None:
        zeros = np.zeros(len(truth))
        truth = _obstacles(truth[:, 0:2], truth[:, 2:4], truth[:, 4], zeros, zeros, truth[:, 5].astype(int))
    decision = Decision(Command(*command), _unpack_plan(plan))
    return (step, time_s, pose, speed, turn_rate, _Tracks(_unpack_obstacles(tracks)), decision, plan_time_ms,
            truth, _unpack_parts(parts))


class _Tracks:
    """An observation as far as a scene reads one: its tracks."""

    __slots__ = ("obstacles",)

    def __init__(self, obstacles) -> None:
        self.obstacles = obstacles


def _pack_obstacles(obstacles) -> np.ndarray:
    return np.column_stack([obstacles.positions, obstacles.velocities, obstacles.radii_m, obstacles.position_sigma_m,
                            obstacles.velocity_sigma_mps, obstacles.ids])


def _unpack_obstacles(rows: np.ndarray):
    return _obstacles(rows[:, 0:2], rows[:, 2:4], rows[:, 4], rows[:, 5], rows[:, 6], rows[:, 7].astype(int))


def _obstacles(positions, velocities, radii_m, position_sigma_m, velocity_sigma_mps, ids):
    """An :class:`~viapath.observation.Obstacles` from fields taken from one (they were checked when it
    was made): its shape checks are the writer's largest cost per cycle otherwise."""
    from viapath.observation import Obstacles

    obstacles = object.__new__(Obstacles)
    for name, value in (("positions", positions), ("velocities", velocities), ("radii_m", radii_m),
                        ("position_sigma_m", position_sigma_m), ("velocity_sigma_mps", velocity_sigma_mps),
                        ("ids", ids)):
        object.__setattr__(obstacles, name, value)
    return obstacles


def _pack_plan(plan) -> tuple:
    """A plan's points (target, via points, waypoints, every candidate polyline) as one (R, 2) array
    and the row counts; the rest as plain values."""
    lines = [np.asarray(line, dtype=float).reshape(-1, 2) for line in plan.candidate_polylines]
    via = np.asarray(plan.via_points, dtype=float).reshape(-1, 2)
    waypoints = np.asarray(plan.waypoints, dtype=float).reshape(-1, 2)
    points = np.concatenate([np.asarray(plan.target, dtype=float).reshape(1, 2), via, waypoints, *lines])
    counts = [len(via), len(waypoints)] + [len(line) for line in lines]
    return (plan.status, plan.speed_mps, points, counts, plan.subgoal_index, plan.candidate_count,
            np.asarray(plan.candidate_costs, dtype=float).reshape(-1).tolist(), plan.chosen, plan.extras)


def _unpack_plan(packed: tuple):
    from viapath.observation import Plan

    status, speed, points, counts, subgoal_index, candidate_count, costs, chosen, extras = packed
    pieces, start = [], 1
    for count in counts:
        pieces.append(points[start:start + count])
        start += count
    return Plan(status, speed, points[0], pieces[0], pieces[1], subgoal_index, candidate_count,
                np.array(costs, dtype=float), pieces[2:], chosen, extras)


def _pack_parts(parts: tuple) -> tuple:
    scanners, detections, radii, points, sectors, blind = parts
    flat = [(s.name, s.mount_pose, s.angle_min_rad, s.angle_increment_rad, s.ranges_m, s.range_min_m, s.range_max_m)
            for s in scanners]
    return flat, detections, radii, points, sectors, blind


def _unpack_parts(packed: tuple) -> tuple:
    from viapath.viz.scene import ScannerView

    flat, detections, radii, points, sectors, blind = packed
    return ([ScannerView(*fields) for fields in flat], detections, radii, points, sectors, blind)


def _writer_main(connection, publisher_class, file: str, force: bool, waypoints, half_widths_m,
                 robot_radius_m: float, settings) -> None:
    """The writer process: open the file, then build and log each cycle until told it is done."""
    # Ctrl-C reaches the whole process group: the run's process decides when the file ends (it sends
    # "done" from its clean-up), so the writer does not stop half-way on its own.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    writer = None
    try:
        import foxglove
        from foxglove.mcap import MCAPCompression, MCAPWriteOptions

        from viapath.path import DesignatedPath
        from viapath.viz.scene import SceneBuilder

        context = foxglove.Context()
        writer = foxglove.open_mcap(file, allow_overwrite=force, context=context,
                                    writer_options=MCAPWriteOptions(compression=MCAPCompression.Lz4))
        path = DesignatedPath(waypoints, half_widths_m=half_widths_m)
        publisher = publisher_class(context, path, robot_radius_m, settings)
        connection.send((_READY, None))
        while True:
            message = connection.recv_bytes()
            if message == b"":
                break
            payload = pickle.loads(message)
            if publisher.builder is None:
                first_settings, payload = payload
                publisher.builder = SceneBuilder(path, robot_radius_m, settings or first_settings)
            publisher.publish(publisher.build(payload))
        writer.close()
        writer = None
        connection.send((_DONE, publisher.cycles))
    except BaseException as error:  # every failure goes back to the run's process as text
        if writer is not None:
            try:
                writer.close()
            except Exception:
                pass
        try:
            connection.send((_FAILED, f"{type(error).__name__}: {error}\n{traceback.format_exc(limit=4)}"))
        except Exception:
            pass
    finally:
        connection.close()


def _hold_interrupts():
    """Block SIGINT for this thread where the platform can (POSIX); what was blocked before, or None."""
    if not hasattr(signal, "pthread_sigmask"):
        return None
    return signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})


def _release_interrupts(held) -> None:
    """Restore the mask: a SIGINT that came meanwhile is delivered now (KeyboardInterrupt here)."""
    if held is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


class MCAPWriterProcess:
    """The ``on_step`` callback that hands each cycle to a writer process (see module notes).
    ``publisher_class`` logs a scene on a foxglove context (:class:`viapath.viz.foxglove.FoxglovePublisher`,
    passed in so that this module does not import the one that uses it); ``error`` is the
    exception raised when the writer fails."""

    def __init__(self, file: Path | str, force: bool, path, robot_radius_m: float, publisher_class,
                 error: type[Exception] = RuntimeError, settings=None):
        self._error = error
        self.file = Path(file)
        self.cycles = 0
        self._first = True
        ctx = multiprocessing.get_context(_start_method())
        self._connection, child = ctx.Pipe(duplex=True)
        self.process = ctx.Process(
            target=_writer_main, name="viapath-mcap-writer", daemon=True,
            args=(child, publisher_class, str(self.file), force, np.asarray(path.waypoints, dtype=float),
                  np.asarray(path.half_widths_m, dtype=float), float(robot_radius_m), settings))
        self.process.start()
        child.close()
        kind, detail = self._receive()
        if kind != _READY:
            self._stop()
            raise error(f"--mcap {self.file}: the writer could not start ({detail})")

    def _receive(self) -> tuple[str, Any]:
        try:
            return self._connection.recv()
        except (EOFError, OSError):
            return _FAILED, f"the writer process ended with exit code {self.process.exitcode}"

    def __call__(self, record) -> None:
        payload = cycle_input(record)
        if self._first:
            from viapath.viz.scene import ForecastSettings

            payload = (ForecastSettings.from_planner(record.planner), payload)
            self._first = False
        data = pickle.dumps(payload, protocol=_PICKLE)
        # A cycle is counted if and only if the writer gets all of it: Ctrl-C is held back while it is
        # sent (the run often waits here on a full pipe now that planning is fast, and an interrupt
        # there could leave a cycle sent but not counted; close() compares the counts).
        held = _hold_interrupts()
        try:
            try:
                self._connection.send_bytes(data)
            except (BrokenPipeError, OSError):
                kind, detail = self._receive()
                self._stop()
                raise self._error(f"--mcap {self.file}: the writer failed ({detail})") from None
            self.cycles += 1
        finally:
            _release_interrupts(held)

    def close(self) -> int:
        """Tell the writer the run is over, wait for it to finish the file; the cycles it wrote."""
        if self.process is None:
            return self.cycles
        try:
            self._connection.send_bytes(b"")
        except (BrokenPipeError, OSError):
            pass
        kind, detail = self._receive()
        self._stop()
        if kind != _DONE:
            raise self._error(f"--mcap {self.file}: the writer failed ({detail})")
        if detail != self.cycles:
            raise self._error(f"--mcap {self.file}: the writer wrote {detail} of {self.cycles} cycles")
        return detail

    def _stop(self) -> None:
        process, self.process = self.process, None
        if process is None:
            return
        process.join(timeout=30)
        if process.is_alive():
            process.kill()
            process.join()
        self._connection.close()
