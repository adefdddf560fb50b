"""A first ``viapath run`` with a cold cache of compiled steps runs plain Python and compiles in the background.

What is checked: the run says so in one line naming the background process; it imports no numba; its metrics are
those of a compiled run (timings aside); a second cold run while that process compiles starts no other; the
background process is the low-priority ``viapath.precompile --background`` and holds the cache folder's lock; a
second background compiler leaves at once while one holds it; a ready cache, ``VIAPATH_BACKGROUND_COMPILE=0`` or a
process that already compiled a step runs compiled. The suite switches the background compilation off
(tests/conftest.py); the tests here switch it on for their own commands and end every process they start by PID.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from viapath import jit

SRC = str(Path(__file__).resolve().parents[1] / "src")
NOTE = re.compile(r"^viapath: this run uses plain Python; .* in the background .*\(about \d+ s of CPU, pid (\d+);")

# The CLI in a fresh interpreter, then whether it loaded numba (stderr's last line).
RUN_THEN_SAY_IF_NUMBA = """
import sys
from viapath.cli import app
try:
    app(sys.argv[1:], standalone_mode=False)
finally:
    print("numba loaded:", "numba" in sys.modules, file=sys.stderr)
"""


def _env(cache: Path, background: str = "1") -> dict[str, str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "VIAPATH_BACKGROUND_COMPILE": background}
    env["PYTHONPATH"] = SRC + os.pathsep + os.environ.get("PYTHONPATH", "")
    env.pop("NUMBA_DISABLE_JIT", None)
    return env


def _run(cache: Path, *arguments: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", RUN_THEN_SAY_IF_NUMBA, *arguments],
        env=_env(cache),
        capture_output=True,
        text=True,
        timeout=300,
    )


def _alive(pid: int) -> bool:
    """Running (a zombie, ended but not yet reaped by init, counts as ended)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state != "Z"


def _end(pid: int) -> None:
    if _alive(pid):
        os.kill(pid, signal.SIGKILL)
    deadline = time.monotonic() + 30
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(pid)


def _wait_for(condition, timeout_s: float = 30.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


def _nice(pid: int) -> int:
    return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[16])


@pytest.mark.skipif(not Path("/proc/self/stat").exists() or not jit.numba_installed(), reason="Linux /proc, numba")
def test_a_cold_run_runs_plain_python_says_so_and_compiles_in_the_background(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    started: list[int] = []
    try:
        first = _run(tmp_path, "run", "paper-front", "--json")
        assert first.returncode == 0, first.stderr
        notes = [line for line in first.stderr.splitlines() if line.startswith("viapath:")]
        assert len(notes) == 1 and NOTE.match(notes[0]), first.stderr
        pid = int(NOTE.match(notes[0]).group(1))
        started.append(pid)
        assert first.stderr.splitlines()[-1] == "numba loaded: False"
        assert _wait_for(lambda: not _alive(pid) or _nice(pid) >= 10)
        if _alive(pid):  # compiling (a fast machine may be done already)
            command = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
            assert b"viapath.precompile" in command and b"--background" in command
            from viapath.precompile import compiling_pid

            assert _wait_for(lambda: compiling_pid() == pid or not _alive(pid))
            second = _run(tmp_path, "run", "paper-front", "--json")
            assert second.returncode == 0, second.stderr
            again = [NOTE.match(line) for line in second.stderr.splitlines() if NOTE.match(line)]
            if again:  # still compiling: the same process is named, no other is started
                assert int(again[0].group(1)) == pid
        plain = json.loads(first.stdout.strip().splitlines()[-1])
        from viapath.scenarios import load_scenario
        from viapath.sim.loop import run_episode

        compiled = json.loads(json.dumps(run_episode(load_scenario("paper-front")).metrics))
        for metrics in (plain, compiled):
            for key in [key for key in metrics if "_time_p" in key]:
                del metrics[key]
        assert plain == compiled
        assert plain["reached_goal"] and plain["max_speed_mps"] > 0.2
    finally:
        for pid in started:
            _end(pid)


@pytest.mark.skipif(not jit.numba_installed(), reason="numba")
def test_a_second_background_compiler_leaves_at_once_while_one_holds_the_lock(tmp_path, monkeypatch):
    from viapath.precompile import compiling_lock, compiling_pid

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert compiling_pid() is None
    with compiling_lock(wait=False) as mine:
        assert mine and compiling_pid() == os.getpid()
        with compiling_lock(wait=False) as second:
            assert not second  # another holder (here another open of the lock file) waits or leaves
        done = subprocess.run(
            [sys.executable, "-m", "viapath.precompile", "--background"],
            env=_env(tmp_path),
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert done.returncode == 0, done.stderr
        assert done.stdout == "" and not jit.cache_is_ready()
        assert not any(tmp_path.rglob("*.nbi"))  # it compiled nothing
    assert compiling_pid() is None


@pytest.mark.parametrize(
    ("background", "cache", "expected"),
    [("1", "cold", "True"), ("0", "cold", "False"), ("1", "ready", "False"), ("1", "unwritable", "False")],
)
def test_only_a_cold_writable_cache_with_background_compilation_on_runs_plain(tmp_path, background, cache, expected):
    """In a fresh interpreter (nothing compiled yet): plain only when the cache is not ready, can be written (the
    next runs would not find what a background compiler made) and the background compilation is allowed."""
    folder = tmp_path
    if cache == "unwritable":
        folder = tmp_path / "a-file"
        folder.write_text("not a folder\n")
    script = (
        "from viapath import jit\n"
        + ("jit.ready_file().parent.mkdir(parents=True); jit.ready_file().touch()\n" if cache == "ready" else "")
        + "from viapath.cli.common import compiled_or_plain\n"
        "plain = compiled_or_plain()\n"
        "from viapath.path import corridor_excess_at\n"
        "print(plain, jit.enabled(), hasattr(corridor_excess_at, 'py_func'))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], env=_env(folder, background), capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    plain, enabled, dispatcher = done.stdout.split()
    assert plain == expected
    assert enabled == dispatcher == str(expected == "False")  # a compiled step is numba's, a plain one Python's
    assert not list(tmp_path.rglob("compiling.lock"))  # nothing was started


def test_a_process_that_compiled_a_step_already_stays_compiled(monkeypatch, tmp_path):
    """The test process has compiled steps (this module imports them): a cold cache does not switch it to plain
    Python halfway, and nothing is started in the background."""
    import viapath.static

    if not jit.enabled():
        pytest.skip("compilation is off")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("VIAPATH_BACKGROUND_COMPILE", "1")
    import viapath.precompile

    def no_background():
        raise AssertionError("started a background compiler")

    monkeypatch.setattr(viapath.precompile, "start_in_background", no_background)
    from viapath.cli.common import compiled_or_plain

    assert compiled_or_plain() is False and jit.enabled()


def test_precompile_with_compilation_off_says_there_is_nothing_to_compile(tmp_path):
    from typer.testing import CliRunner

    from viapath.cli import app

    result = CliRunner().invoke(app, ["precompile"], env={"NUMBA_DISABLE_JIT": "1", "NUMBA_CACHE_DIR": str(tmp_path)})
    assert result.exit_code == 0, result.output
    assert "compilation is off" in result.output and "nothing to compile" in result.output
    assert not any(tmp_path.iterdir())  # no lock, no cache folder
