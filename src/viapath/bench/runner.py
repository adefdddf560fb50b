"""Run many (scenario, planner) episodes in parallel with joblib, writing each result as it finishes.

* Executors (:mod:`.executors`): ``loky`` (local processes, the default), ``dask`` (joins ``scheduler`` when
  given, else starts a local cluster of ``workers`` processes; extra ``dask``) and ``ray`` (joins ``scheduler``
  when given, else starts a local one; extra ``ray``). The same task function runs everywhere; a task
  carries its scenario as a plain dict, so remote workers need only viapath and the data files.
* Results: one CSV row per episode appended to ``episodes.csv`` as soon as the episode returns, so a
  run that is stopped keeps what it finished; a rerun skips every (scenario, planner, perception,
  seed) already in the file. ``episodes.parquet`` is rewritten from all rows at the end where
  pyarrow is installed.
* Determinism: the episode seed is derived from the bench seed and the scenario name, so the same
  seed gives the same numbers (except the wall-clock plan times) on any executor and worker count.
* Time to goal is reported relative to the obstacle-free time: the same scenario with its
  obstacles removed, driven by ``follow`` (one common reference for every planner).
"""

from __future__ import annotations

import contextlib
import csv
import math
import os
import time
import zlib
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

from viapath.bench.executors import ExecutorError, executor_parallel, local_processes, stop_workers
from viapath.bench.feasibility import FEASIBILITY_COLUMNS, FEASIBILITY_FLAGS
from viapath.bench.suites import ETH_UCY_FOLDER, data_root, generate_suite, suite_names, write_suite

COLUMNS = [
    "scenario",
    "family",
    "planner",
    "perception",
    "seed",
    "scenario_hash",
    "options_hash",
    "viapath_version",
    "reached_goal",
    "collision",
    "at_fault_collision",
    "at_fault_collision_seen_1s",
    "overlapping_at_appearance",
    "static_contact",
    "min_clearance_m",
    "time_to_goal_s",
    "free_time_s",
    "time_ratio",
    "path_length_m",
    "mean_lateral_deviation_m",
    "max_lateral_deviation_m",
    "time_outside_corridor_s",
    "min_speed_mps",
    "max_speed_mps",
    "plan_time_p50_ms",
    "plan_time_p99_ms",
    "episode_wall_s",
    "error",
    "shield",
    "shield_interventions",
    "command_flips",
    "escape_cycles",
    "blocked_s",
    # viapath.bench.avoidable: the at-fault contacts split by whether any robot could have avoided them
    # (searched on at-fault episodes only), and the robot's speed at every contact's onset.
    "at_fault_avoidable",
    "at_fault_unavoidable",
    "unavoidable_appeared_before_s",
    "contact_speed_max_mps",
    "contact_speeds",
    "at_fault_detail",
    # viapath.bench.feasibility: whether any robot on this drive could reach the goal without a contact
    # (people who do not react to the robot; empty for those who do), and the episode among feasible ones.
    *FEASIBILITY_COLUMNS,
]
_BOOLS = {"reached_goal", "collision", "at_fault_collision", "at_fault_collision_seen_1s", *FEASIBILITY_FLAGS}
_TEXT = {
    "scenario",
    "family",
    "planner",
    "perception",
    "error",
    "shield",
    "scenario_hash",
    "options_hash",
    "viapath_version",
    "unavoidable_appeared_before_s",
    "contact_speeds",
    "at_fault_detail",
}
_INTS = {
    "seed",
    "command_flips",
    "escape_cycles",
    "overlapping_at_appearance",
    "static_contact",
    "at_fault_avoidable",
    "at_fault_unavoidable",
}


class BenchError(ValueError):
    """Bad benchmark input (unknown planner or executor, empty suite, missing extra)."""


class FolderBusy(BenchError):
    """Another run holds the results folder (:func:`results_lock`)."""


@dataclass(frozen=True)
class Task:
    scenario: dict
    planner: str
    perception: str
    seed: int
    scenario_hash: str = ""
    options_hash: str = ""
    viapath_version: str = ""
    shield: str = "off"  # off | on (passive) | friendly (passive-friendly), see viapath.safety
    options: tuple = ()  # (name, value) planner options over the scenario's block (--weights); in options_hash
    time_limit_s: float | None = None  # wall time an episode may take (None: no limit); not in the row's identity

    @property
    def key(self) -> tuple:
        # What a row is (see viapath.bench.identity): never the scenario name alone.
        return (
            self.scenario_hash,
            self.planner,
            self.options_hash,
            self.perception,
            str(self.seed),
            self.viapath_version,
            self.shield,
        )


def row_key(row: dict) -> tuple:
    return (
        row["scenario_hash"],
        row["planner"],
        row["options_hash"],
        row["perception"],
        str(row["seed"]),
        row["viapath_version"],
        row["shield"],
    )


def episode_seed(bench_seed: int, scenario_name: str) -> int:
    return zlib.crc32(f"{bench_seed}:{scenario_name}".encode()) & 0x7FFFFFFF


def family_of(name: str) -> str:
    head, _, tail = name.rpartition("-")
    return head if tail.isdigit() and head else name


# -- loading suites ---------------------------------------------------------------------------------


def load_suite(
    suite: str, out_dir: Path | None = None, count: int = 200, seed: int = 0, workers: int = 1
) -> list[dict]:
    """Scenario dicts of SUITE: a folder of scenario YAML files, or a suite name (generated with
    ``count`` and ``seed`` and written to ``out_dir/suite`` so it can be inspected and rerun)."""
    folder = Path(suite)
    if folder.is_dir():
        files = sorted(folder.glob("*.yaml")) + sorted(folder.glob("*.yml"))
        if not files:
            raise BenchError(f"{suite}: no scenario files (*.yaml) in this folder")
    elif suite in suite_names():
        scenarios = generate_suite(suite, count, seed, workers=workers)
        if out_dir is None:
            return [_resolve_replays(s) for s in scenarios]
        folder = Path(out_dir) / "suite"
        if workers > 1 and len(scenarios) > 1:
            # Writing the YAML files and reading them back is PyYAML's Python representer and constructor,
            # a few seconds per thousand scenarios: done in the workers, chunk by chunk, in order.
            import joblib

            chunks = [scenarios[start : start + 50] for start in range(0, len(scenarios), 50)]
            parts = local_processes(workers)(joblib.delayed(_write_and_read)(chunk, folder) for chunk in chunks)
            loaded = [scenario for part in parts for scenario in part]
        else:
            loaded = _write_and_read(scenarios, folder)
        return _unique_names(loaded, suite)
    else:
        raise BenchError(f"{suite}: not a folder of scenario files nor a suite name ({', '.join(suite_names())})")
    return _unique_names(_read(files), suite)


def _write_and_read(scenarios: list[dict], folder: Path) -> list[dict]:
    """Write scenario files into ``folder`` and read them back as a rerun from the folder would."""
    return _read(write_suite(scenarios, folder))


def _read(files: list[Path]) -> list[dict]:
    from viapath.scenarios import ScenarioError, load_scenario

    loaded = []
    for file in files:
        try:
            scenario = load_scenario(file)
        except ScenarioError as error:
            raise BenchError(str(error).splitlines()[0]) from None
        loaded.append(_resolve_replays(scenario.model_dump(mode="json")))
    return loaded


def _unique_names(loaded: list[dict], suite: str) -> list[dict]:
    names = [s["name"] for s in loaded]
    if len(set(names)) != len(names):
        duplicate = next(n for n in names if names.count(n) > 1)
        raise BenchError(f"{suite}: two scenarios are named {duplicate!r}; names key the results, make them unique")
    return loaded


def _resolve_replays(scenario: dict) -> dict:
    """Replay files that do not exist where written are looked up under the data root by file name."""
    for item in scenario.get("obstacles", []):
        replay = item.get("replay") if isinstance(item, dict) else None
        if replay is None:
            continue
        path = Path(replay["file"])
        if not path.exists():
            candidate = data_root() / ETH_UCY_FOLDER / path.name
            if not candidate.exists():
                raise BenchError(
                    f"{scenario['name']}: replay file {replay['file']} not found (nor {candidate}); "
                    "set VIAPATH_DATA to the data folder"
                )
            replay["file"] = str(candidate)
        else:
            replay["file"] = str(path.resolve())
    return scenario


# -- one episode (runs in the workers) ---------------------------------------------------------------


def _free_time_s(scenario: dict) -> float | None:
    """How long the robot takes to the goal with nobody about (path following at the nominal speed): the
    denominator of the time ratio. Scenarios that differ only in their people, name or description share it
    (a suite's families repeat paths and robots), so it is run once per worker for each of them."""
    import json

    empty = {key: value for key, value in scenario.items() if key not in ("obstacles", "name", "description")}
    return _free_run_time_s(json.dumps(empty, sort_keys=True))


@lru_cache(maxsize=4096)
def _free_run_time_s(empty_scenario_json: str) -> float | None:
    import json

    from viapath.scenarios import scenario_from_dict
    from viapath.sim.loop import run_episode

    data = json.loads(empty_scenario_json)
    episode = run_episode(
        scenario_from_dict({**data, "name": "free run", "obstacles": []}), planner="follow", perception="oracle"
    )
    return episode.metrics["time_to_goal_s"]


EPISODE_TIME_LIMIT_S = 600.0  # wall time; the longest suite episodes take seconds (a hung one is a failure)


class EpisodeTimeLimit(RuntimeError):
    """An episode ran longer than its wall-time limit (checked at each planning cycle)."""


def _time_limit(limit_s: float | None, started: float):
    if limit_s is None or not limit_s > 0:
        return None

    def check(_record) -> None:
        if time.perf_counter() - started > limit_s:
            raise EpisodeTimeLimit(f"the episode took more than {limit_s:g} s of wall time (--episode-time-limit)")

    return check


def run_task(task: Task) -> dict[str, Any]:
    """Run one episode; never raises (an error is recorded in the row so the run goes on; an episode
    over its time limit is such an error: a recorded failure, rerun on resume)."""
    from viapath.scenarios import scenario_from_dict
    from viapath.sim.loop import run_episode

    started = time.perf_counter()
    row: dict[str, Any] = dict.fromkeys(COLUMNS)
    name = task.scenario["name"]
    row.update(
        scenario=name,
        family=family_of(name),
        planner=task.planner,
        perception=task.perception,
        seed=task.seed,
        scenario_hash=task.scenario_hash,
        options_hash=task.options_hash,
        viapath_version=task.viapath_version,
        error="",
        shield=task.shield,
    )
    _ignore_sigint_in_workers()
    try:
        scenario = scenario_from_dict(task.scenario, name)
        episode = run_episode(
            scenario,
            planner=task.planner,
            perception=task.perception,
            seed=task.seed,
            shield=task.shield != "off",
            planner_overrides=dict(task.options),
            shield_options={"mode": "passive-friendly" if task.shield == "friendly" else "passive"},
            on_step=_time_limit(task.time_limit_s, started),
        )
        for column in COLUMNS:
            if column in episode.metrics and column != "shield":
                row[column] = episode.metrics[column]
        from viapath.bench.avoidable import episode_columns

        row.update(episode_columns(episode.trace, scenario, bool(row["at_fault_collision"])))
        from viapath.bench.feasibility import episode_columns as feasibility_columns

        row.update(
            feasibility_columns(scenario, bool(row["reached_goal"]), bool(row["collision"]), row["time_to_goal_s"])
        )
        free = _free_time_s(task.scenario)
        row["free_time_s"] = free
        if row["time_to_goal_s"] is not None and free:
            row["time_ratio"] = row["time_to_goal_s"] / free
    except Exception as error:
        row["error"] = f"{type(error).__name__}: {error}".replace("\n", " ")[:300]
    row["episode_wall_s"] = time.perf_counter() - started
    return row


def _ignore_sigint_in_workers() -> None:
    """Ctrl-C is the parent's to handle (it stops the workers and keeps the finished rows): a worker
    that got it too would only print a traceback."""
    import os
    import signal

    parent = os.environ.get("VIAPATH_BENCH_PARENT_PID")
    if parent and parent != str(os.getpid()):
        signal.signal(signal.SIGINT, signal.SIG_IGN)


# -- results file ----------------------------------------------------------------------------------

LOCK_FILE = ".viapath-bench.lock"
_HELD_LOCKS: dict[str, int] = {}  # resolved folder -> the descriptor holding its lock (this process)


@contextlib.contextmanager
def results_lock(out_dir: Path) -> Iterator[None]:
    """Hold the results folder for this run: one writer at a time. Another run into the same folder is
    refused (:class:`BenchError`) while this one holds it. The lock is the operating system's (``flock`` on a file in
    the folder), so a run that crashes or is killed leaves no lock behind. Re-entrant in one process."""
    import fcntl

    out_dir = Path(out_dir)
    key = str(out_dir.resolve())
    if key in _HELD_LOCKS:
        yield
        return
    out_dir.mkdir(parents=True, exist_ok=True)
    fd = os.open(out_dir / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        holder = os.read(fd, 32).decode(errors="replace").strip() or "?"
        os.close(fd)
        raise FolderBusy(
            f"{out_dir}: another viapath bench (pid {holder}) is writing into this folder; "
            "wait for it to end or use another --out"
        ) from None
    os.ftruncate(fd, 0)
    os.write(fd, f"{os.getpid()}\n".encode())
    _HELD_LOCKS[key] = fd
    try:
        yield
    finally:
        del _HELD_LOCKS[key]
        os.close(fd)  # releases the lock


def repair_torn_tail(csv_path: Path) -> str | None:
    """Cut a last row that was cut off mid-write (a run killed while writing it: no newline at the end),
    so that the next row is not glued onto it; returns what was done, or None when the file is whole."""
    csv_path = Path(csv_path)
    if not csv_path.exists() or csv_path.stat().st_size == 0:
        return None
    with open(csv_path, "rb+") as handle:
        size = handle.seek(0, os.SEEK_END)
        handle.seek(size - 1)
        if handle.read(1) == b"\n":
            return None
        end = size
        while end > 0:
            start = max(0, end - 65536)
            handle.seek(start)
            found = handle.read(end - start).rfind(b"\n")
            if found >= 0:
                end = start + found + 1
                break
            end = start
        handle.truncate(end)
    what = "its header" if end == 0 else "its last row"
    return (
        f"{csv_path}: {what} was cut off mid-write ({size - end} bytes; a run stopped while writing it); "
        "removed, that episode runs again"
    )


def read_rows(csv_path: Path) -> list[dict[str, Any]]:
    if not Path(csv_path).exists():
        return []
    with open(csv_path, newline="") as handle:
        reader = csv.DictReader(handle)
        if reader.fieldnames is not None and list(reader.fieldnames) != COLUMNS:
            raise BenchError(
                f"{csv_path}: written by another version of viapath (columns differ); use a new --out folder"
            )
        rows = []
        for row in reader:
            try:
                if None in row or any(row[column] is None for column in COLUMNS):
                    raise ValueError(f"{len(row) - (None in row)} fields, expected {len(COLUMNS)}")
                rows.append(_parse(row))
            except ValueError as error:
                raise BenchError(
                    f"{csv_path}: line {reader.line_num}: not a row of this file ({error}); remove "
                    "that line or use a new --out folder"
                ) from None
        return rows


def _parse(row: dict[str, str]) -> dict[str, Any]:
    parsed: dict[str, Any] = {}
    for column in COLUMNS:
        value = row.get(column, "")
        if column in _TEXT:
            parsed[column] = value or ""
        elif value == "" or value is None:
            parsed[column] = None
        elif column in _BOOLS:
            parsed[column] = value == "True"
        elif column in _INTS:
            parsed[column] = int(value)
        else:
            parsed[column] = float(value)
    return parsed


def _format(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ""
    return str(value)


def write_parquet(rows: list[dict], path: Path) -> bool:
    """Write the rows as Parquet where pyarrow is installed; returns whether it did."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return False
    table = pa.Table.from_pylist([{c: row.get(c) for c in COLUMNS} for row in rows])
    pq.write_table(table, path)
    return True


# -- the run ---------------------------------------------------------------------------------------


def make_tasks(
    scenarios: list[dict],
    planners: list[str],
    perception: str = "oracle",
    seed: int = 0,
    shield: str | None = None,
    planner_options: dict[str, dict] | None = None,
    time_limit_s: float | None = EPISODE_TIME_LIMIT_S,
) -> list[Task]:
    """``shield``: on | off | friendly for every planner, None for each planner's default (viapath.safety).
    ``planner_options``: planner name → option values set over every scenario's block (``--weights``).
    ``time_limit_s``: wall time per episode (None or 0: none)."""
    from viapath.planning import available_planners
    from viapath.safety import shield_default

    known = available_planners()
    unknown = [p for p in planners if p not in known]
    if unknown:
        raise BenchError(f"unknown planner {unknown[0]!r}; available: {', '.join(known)}")
    from viapath.perception.modes import PERCEPTION_MODES

    if perception not in PERCEPTION_MODES:
        raise BenchError(f"unknown perception {perception!r}; use {' or '.join(PERCEPTION_MODES.ordered())}")
    from viapath.bench.identity import options_hash, scenario_hash, viapath_version

    if shield not in (None, "on", "off", "friendly"):
        raise BenchError(f"unknown shield setting {shield!r}; use on, off or friendly")
    setting = {p: shield or ("on" if shield_default(p) else "off") for p in planners}
    version = viapath_version()
    hashes = [scenario_hash(s) for s in scenarios]
    extra = {p: tuple(sorted((planner_options or {}).get(p, {}).items())) for p in planners}
    return [
        Task(
            s,
            p,
            perception,
            episode_seed(seed, s["name"]),
            h,
            options_hash(s, p, dict(extra[p])),
            version,
            setting[p],
            extra[p],
            time_limit_s,
        )
        for s, h in zip(scenarios, hashes)
        for p in planners
    ]


def run_bench(
    scenarios: list[dict],
    planners: list[str],
    out_dir: Path,
    workers: int = 1,
    executor: str = "loky",
    scheduler: str | None = None,
    perception: str = "oracle",
    seed: int = 0,
    progress: bool | Callable[[int, int], None] = True,
    shield: str | None = None,
    force: bool = False,
    planner_options: dict[str, dict] | None = None,
    note: Callable[[str], None] | None = None,
    episode_time_limit_s: float | None = EPISODE_TIME_LIMIT_S,
) -> dict[str, Any]:
    """Run every episode not already done in ``out_dir/episodes.csv`` (a row is identified by the
    scenario's content hash, planner, options, perception, seed and viapath version; an episode that
    crashed is not done). ``progress``: a bar on stderr (True), nothing (False), or a function told
    (episodes done, episodes to run) after each episode. A folder written by another suite or configuration is refused
    (:class:`BenchError`) unless ``force``; see :mod:`viapath.bench.identity`.

    Returns ``{"rows": this run's rows, "ran": episodes run now, "skipped": already done,
    "errors": crashed episodes among the rows, "wall_s": ...}``. Ctrl-C stops the workers, keeps the
    finished rows and raises :class:`BenchInterrupted` saying how many are done; a worker process that
    dies (killed, out of memory) does the same with :class:`BenchWorkerLost`. The folder is held for the
    whole run (:func:`results_lock`); a last row cut off mid-write is removed first (``note`` is told,
    and the result's ``"repaired"`` says so).
    """
    with results_lock(Path(out_dir)):
        return _run_bench(
            scenarios,
            planners,
            Path(out_dir),
            workers,
            executor,
            scheduler,
            perception,
            seed,
            progress,
            shield,
            force,
            planner_options,
            note or (lambda text: None),
            episode_time_limit_s,
        )


def _run_bench(
    scenarios,
    planners,
    out_dir: Path,
    workers,
    executor,
    scheduler,
    perception,
    seed,
    progress,
    shield,
    force,
    planner_options,
    note,
    episode_time_limit_s=EPISODE_TIME_LIMIT_S,
) -> dict[str, Any]:
    from viapath.bench.identity import check_folder, manifest

    csv_path = out_dir / "episodes.csv"
    tasks = make_tasks(scenarios, planners, perception, seed, shield, planner_options, episode_time_limit_s)
    repaired = repair_torn_tail(csv_path)
    if repaired:
        note(repaired)
    latest = _latest(read_rows(csv_path))
    ok_names = {row["scenario"] for row in latest.values() if not row.get("error")}
    crashed_only = {row["scenario"] for row in latest.values()} - ok_names
    refused = check_folder(
        out_dir, manifest({t.scenario["name"]: t.scenario_hash for t in tasks}, perception, seed), force, crashed_only
    )
    if refused:
        raise BenchError(refused)
    done = {key for key, row in latest.items() if not row.get("error")}
    todo = [t for t in tasks if t.key not in done]
    started = time.perf_counter()
    if todo:
        from viapath.precompile import precompile

        precompile()  # once per machine (then cached), so that the workers' shields and planners run compiled
        os.environ["VIAPATH_BENCH_PARENT_PID"] = str(os.getpid())
        try:
            parallel, close = executor_parallel(executor, workers, scheduler)
        except ExecutorError as error:
            raise BenchError(str(error)) from None
        try:
            _run_and_write(parallel, todo, csv_path, progress)
        except KeyboardInterrupt as interrupt:
            stop_workers(parallel)
            finished = _finished(tasks, csv_path)
            raise BenchInterrupted(finished, len(tasks), csv_path, getattr(interrupt, "reason", "")) from None
        except Exception as error:
            if not _worker_lost(error):
                raise
            stop_workers(parallel)
            raise BenchWorkerLost(_finished(tasks, csv_path), len(tasks), csv_path, error) from None
        finally:
            close()
    wall = time.perf_counter() - started
    latest = _latest(read_rows(csv_path))
    rows = [latest[t.key] for t in tasks if t.key in latest]
    write_parquet(rows, out_dir / "episodes.parquet")
    return {
        "rows": rows,
        "ran": len(todo),
        "skipped": len(tasks) - len(todo),
        "errors": sum(1 for r in rows if r.get("error")),
        "wall_s": wall,
        "repaired": repaired,
    }


def _finished(tasks: list[Task], csv_path: Path) -> int:
    latest = _latest(read_rows(csv_path))
    return sum(1 for t in tasks if t.key in latest and not latest[t.key].get("error"))


def _worker_lost(error: BaseException) -> bool:
    """Whether ``error`` says a worker process died under the run (loky's TerminatedWorkerError, a broken
    process pool, dask's or ray's lost worker), rather than a bug of the run itself."""
    names = {cls.__name__ for cls in type(error).__mro__}
    return bool(
        names
        & {
            "TerminatedWorkerError",
            "BrokenProcessPool",
            "BrokenExecutor",
            "KilledWorker",
            "WorkerCrashedError",
            "RayActorError",
        }
    )


class BenchInterrupted(Exception):
    """Ctrl-C (or SIGTERM) during a run: the finished rows are kept in the CSV; rerunning resumes."""

    def __init__(self, finished: int, total: int, csv_path: Path, reason: str = ""):
        super().__init__(f"{reason or 'interrupted'}: {finished} of {total} episodes done and kept in {csv_path}")
        self.finished, self.total, self.csv_path = finished, total, csv_path


class BenchWorkerLost(Exception):
    """A worker process died during the run (killed, out of memory): the others are stopped, the finished
    rows are kept; rerunning the command runs the rest."""

    def __init__(self, finished: int, total: int, csv_path: Path, error: BaseException):
        cause = str(error).splitlines()[0][:200] if str(error) else type(error).__name__
        super().__init__(
            f"a worker process died during the run ({type(error).__name__}: {cause}); the other "
            f"workers were stopped; {finished} of {total} episodes done and kept in {csv_path}"
        )
        self.finished, self.total, self.csv_path = finished, total, csv_path


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so a run ends as on Ctrl-C (see :func:`terminate_as_interrupt`)."""

    reason = "terminated (SIGTERM)"


@contextlib.contextmanager
def terminate_as_interrupt() -> Iterator[None]:
    """While inside: SIGTERM raises :class:`Terminated` (a KeyboardInterrupt) in the main thread, so the
    workers are stopped and the finished rows kept, as on Ctrl-C."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def _raise(signum, frame):
        raise Terminated()

    previous = signal.signal(signal.SIGTERM, _raise)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _latest(rows: list[dict]) -> dict[tuple, dict]:
    """The last row of each identity (a crashed episode rerun later appends its new row)."""
    return {row_key(row): row for row in rows}


def _run_and_write(parallel, tasks: list[Task], csv_path: Path, progress) -> None:
    import joblib

    new_file = not csv_path.exists() or csv_path.stat().st_size == 0
    with open(csv_path, "a", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        if new_file:
            writer.writeheader()
            handle.flush()
        if parallel.return_as == "list":
            chunk = max(8, 4 * max(1, parallel.n_jobs))
            results: Iterable[dict] = (
                row
                for start in range(0, len(tasks), chunk)
                for row in parallel(joblib.delayed(run_task)(t) for t in tasks[start : start + chunk])
            )
        else:
            results = parallel(joblib.delayed(run_task)(task) for task in tasks)
        for row in _with_progress(results, len(tasks), progress):
            writer.writerow({c: _format(row.get(c)) for c in COLUMNS})
            handle.flush()


def _with_progress(results: Iterable[dict], total: int, enabled) -> Iterator[dict]:
    if callable(enabled):
        for done, row in enumerate(results, 1):
            enabled(done, total)
            yield row
        return
    if not enabled:
        yield from results
        return
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    class _Rate(TextColumn):
        def __init__(self):
            super().__init__("")

        def render(self, task):
            elapsed = task.elapsed or 0.0
            rate = task.completed / elapsed if elapsed > 0 else 0.0
            return f"{rate:5.1f} ep/s"

    columns = [
        TextColumn("episodes"),
        BarColumn(),
        MofNCompleteColumn(),
        _Rate(),
        TextColumn("elapsed"),
        TimeElapsedColumn(),
        TextColumn("/"),
        TimeRemainingColumn(),
        TextColumn("left"),
    ]
    from rich.console import Console

    with Progress(*columns, console=Console(stderr=True), transient=False) as bar:
        job = bar.add_task("episodes", total=total)
        for row in results:
            bar.advance(job)
            yield row
