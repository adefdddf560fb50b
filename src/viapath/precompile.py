"""Compile viapath's compiled steps now (or load them from the on-disk cache) and mark the cache ready.

Who calls it: ``viapath bench`` before its workers start and the ROS 2 node before it makes its planner and
shield (in their own process, so that they run compiled from their first cycle); ``viapath precompile`` (the
same, said on the terminal); and a first ``viapath run`` of a version whose cache is not ready, which runs
plain Python itself and starts ``python -m viapath.precompile --background`` for the next runs
(:func:`start_in_background`; docs/explanation/speed.md).

The steps live with their features (the planner's in :mod:`viapath.planning.viapath`, the shield's in
:mod:`viapath.safety`, the laser chain's in :mod:`viapath.perception`), each decorated with
:func:`viapath.jit.compiled`. Compiling them means calling them with the argument types they are called with:
the shield's and the planner's own warm-up cycles, then, when the cache is not ready, the episodes of a few
built-in scenes (:data:`WARM_UP_EPISODES`: walls and a door seen by the oracle and by the laser chain, a person
on a subgoal, people met one after another, a box before a closed door). Every built-in scenario, oracle or laser, then runs without compiling
anything. It builds planners, shields and episodes and runs them, so it lives outside all of them.

Choices where nothing says: one compiler per cache folder at a time (an exclusive ``flock`` on
``compiling.lock`` there, holding its PID; a second background compiler leaves at once, :func:`precompile`
waits, then loads what the first compiled). The compiler writes each cache file atomically (a temporary file renamed),
but a function's index and its data are two files: two processes adding *different* signatures of one function
at the same moment could pair an index entry with the other's data, hence the lock. Runs that compile without it
(background compilation off, or a signature no warm-up made) are the rare case; two processes compiling the same
steps in the same order keep the cache consistent (tests/perception/test_numba_cache.py). A cache folder that
cannot be written (a read-only home) gets no lock and no background compilation: runs compile in their own
process, as the compiler does without a cache. The background compiler runs at low priority (``nice`` 10) with its output in ``precompile.log`` there, and is
switched off by ``VIAPATH_BACKGROUND_COMPILE=0`` (the test suite sets it): a cold run then compiles in its own
process, as ``viapath bench`` does.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager

BACKGROUND_VARIABLE = "VIAPATH_BACKGROUND_COMPILE"
# CPU seconds to compile every step once, on the two-core development machine (benchmarks/bench_cold_run.py
# prints the figure of a machine): said to the user before the background compilation starts.
COMPILE_CPU_S = 50
LOCK_NAME = "compiling.lock"
LOG_NAME = "precompile.log"


def precompile() -> bool:
    """Compile the shield, the planner and the laser chain (about a minute of CPU once per machine, said on
    stderr; after waiting for a compilation running in the background, only loading them), then mark the cache
    ready (:func:`viapath.jit.cache_is_ready`). True when all are compiled."""
    from viapath import jit

    if not jit.enabled():
        return _compile_all()  # plain Python: the warm-up runs only, nothing to write
    with compiling_lock(wait=True):
        return _compile_all()


def _compile_all() -> bool:
    from viapath import jit

    note = jit.first_compilation_note()
    if note is not None:
        print(note, file=sys.stderr, flush=True)
    from viapath.planning.viapath.planner import precompile as precompile_planner
    from viapath.safety.shield import precompile as precompile_shield

    shield_ready = precompile_shield()  # first: the planner's warm-up cycles are checked by a shield
    planner_ready = precompile_planner()
    if not (shield_ready and planner_ready):
        return False
    if not jit.cache_is_ready():  # compiling: every step; loading (a ready cache): the two above are enough
        _run_warm_up_episodes()
        _mark_ready(time.process_time())
    return True


#: Built-in scenes whose episodes call every compiled step with the argument types a run does: walls and a door
#: (the static layer, the planner's and the guard's static checks), seen by the oracle and by the laser chain;
#: a person standing on a subgoal (the goal legs, the bypass); three people met one after another by laser; a box
#: before a closed door (the flood of the corridor's free space).
WARM_UP_EPISODES = (
    ("doorway", "laser"),
    ("doorway", "oracle"),
    ("blocked-subgoal", "oracle"),
    ("hallway", "laser"),
    ("box-before-door", "oracle"),
)


def _run_warm_up_episodes() -> None:
    from viapath.scenarios import load_scenario
    from viapath.sim.loop import run_episode

    for scene, perception in WARM_UP_EPISODES:
        run_episode(load_scenario(scene), perception=perception)


def _mark_ready(cpu_s: float) -> None:
    from viapath import jit

    ready = jit.ready_file()
    ready.parent.mkdir(parents=True, exist_ok=True)
    partial = ready.with_name(f"{ready.name}.{os.getpid()}.tmp")
    partial.write_text(f"compiled in {cpu_s:.1f} s of CPU\n")
    partial.replace(ready)  # whole or absent, for a run that looks at the same moment


@contextmanager
def compiling_lock(wait: bool) -> Iterator[bool]:
    """Hold the cache folder's compiling lock (True), or yield False at once when another process holds it and
    ``wait`` is False. Without ``fcntl`` (Windows) there is no lock: always True."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        yield True
        return
    from viapath import jit

    try:
        folder = jit.cache_directory()
        folder.mkdir(parents=True, exist_ok=True)
        descriptor = os.open(folder / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:  # a cache that cannot be written: the compiler works without caching, nothing to share
        yield True
        return
    try:
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
        except BlockingIOError:
            yield False
            return
        os.ftruncate(descriptor, 0)
        os.pwrite(descriptor, f"{os.getpid()}\n".encode(), 0)
        yield True
    finally:
        os.close(descriptor)  # releases the lock


def compiling_pid() -> int | None:
    """The PID of the process compiling into this version's cache folder now (None when none is)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        return None
    from viapath import jit

    path = jit.cache_directory() / LOCK_NAME
    try:
        descriptor = os.open(path, os.O_RDONLY)
    except FileNotFoundError:
        return None
    try:
        try:
            fcntl.flock(descriptor, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            text = os.pread(descriptor, 32, 0).decode(errors="replace").strip()
            return int(text) if text.isdigit() else None
        return None
    finally:
        os.close(descriptor)


def background_allowed() -> bool:
    """Whether a cold run may compile in the background: ``VIAPATH_BACKGROUND_COMPILE`` is not ``0`` and the
    cache folder can be written (else the next runs would not find what it compiled)."""
    if os.environ.get(BACKGROUND_VARIABLE, "1").strip() in ("0", "false", "no", "off"):
        return False
    from viapath import jit

    try:
        jit.cache_directory().mkdir(parents=True, exist_ok=True)
    except OSError:
        return False
    return os.access(jit.cache_directory(), os.W_OK)


def start_in_background() -> int:
    """The PID of the process compiling into the cache in the background: the one already doing it, or a new
    detached ``python -m viapath.precompile --background`` (its own session: it outlives this process and a
    Ctrl-C of the terminal; output in ``precompile.log`` of the cache folder)."""
    running = compiling_pid()
    if running is not None:
        return running
    from viapath import jit

    folder = jit.cache_directory()
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / LOG_NAME, "ab") as log:
        child = subprocess.Popen(
            [sys.executable, "-m", "viapath.precompile", "--background"],
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
            close_fds=True,
        )
    return child.pid


def compile_now(announce=print) -> int:
    """``viapath precompile``: wait for a background compiler, then compile what the cache lacks; exit code."""
    from viapath import jit

    if not jit.enabled():
        announce(
            "viapath: compilation is off (NUMBA_DISABLE_JIT set, or the compiler, a dependency, not installed): nothing to compile"
        )
        return 0
    running = compiling_pid()
    if running is not None:
        announce(f"viapath: waiting for the compilation under way (pid {running})")
    started = time.perf_counter()
    precompile()
    if not jit.cache_is_ready():  # pragma: no cover - a step could not be compiled: its error was raised
        announce("viapath: the compiled steps are not all cached")
        return 1
    announce(f"viapath: compiled steps ready in {jit.cache_directory()} ({time.perf_counter() - started:.1f} s)")
    return 0


def _background() -> int:
    """The detached compiler a cold run starts: low priority, one per cache folder, nothing when ready."""
    from viapath import jit

    if hasattr(os, "nice"):
        os.nice(10)
    with compiling_lock(wait=False) as mine:
        if not mine or jit.cache_is_ready():
            return 0
        print(f"{time.strftime('%Y-%m-%d %H:%M:%S')} pid {os.getpid()}: compiling into {jit.cache_directory()}")
        sys.stdout.flush()
        _compile_all()
        print(f"{time.strftime('%Y-%m-%d %H:%M:%S')} pid {os.getpid()}: done, {time.process_time():.1f} s of CPU")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m viapath.precompile", description=__doc__.splitlines()[0])
    parser.add_argument(
        "--background", action="store_true", help="low priority; leave at once when another process compiles"
    )
    arguments = parser.parse_args(argv)
    if arguments.background:
        return _background()
    return compile_now(lambda text: print(text, file=sys.stderr, flush=True))


if __name__ == "__main__":
    sys.exit(main())
