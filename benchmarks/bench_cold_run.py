"""The README's run command on a machine that has never compiled viapath's steps, and after.

    python benchmarks/bench_cold_run.py [--runs 3] [--install] [--python python3] [--json]

Each run takes a fresh, empty ``NUMBA_CACHE_DIR`` and times, wall clock:

* ``cold_s``: ``viapath run paper-front --plot front.png`` (the README's run command without its install), the
  first run with that cache: it runs plain Python and starts the compilation in the background;
* ``background_s`` and ``background_cpu_s``: from the end of that run until the background compilation has
  marked the cache ready, and the CPU seconds it took (what it wrote into the ready file);
* ``warm_s``: the same command again, loading the compiled steps from the cache.

``--install`` times the README's whole command instead (``python3 -m venv .venv && .venv/bin/pip install -e .
&& .venv/bin/viapath run paper-front --plot front.png``) in a fresh clone of this checkout's HEAD, pip from its
cache; the warm run then is the same command in the same clone (the venv and the install are made again). The
load average is printed with each run (the machine may be shared). Not a test: numbers depend on the machine.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = str(ROOT / "src")


def readme_command() -> str:
    text = (ROOT / "README.md").read_text()
    block = re.search(r"<!-- run-command -->\s*```bash\n(.*?)\n```", text, re.S)
    if block is None:
        raise SystemExit("README.md: no run-command block")
    return block.group(1).strip()


def _timed(command: list[str] | str, cwd: Path, env: dict[str, str]) -> tuple[float, str]:
    started = time.perf_counter()
    done = subprocess.run(command, cwd=cwd, env=env, shell=isinstance(command, str), capture_output=True, text=True)
    wall = time.perf_counter() - started
    if done.returncode != 0:
        raise SystemExit(f"{command!r} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    return wall, done.stderr


def _background_pid(stderr: str) -> int | None:
    found = re.search(r"in the background .*pid (\d+)", stderr)
    return int(found.group(1)) if found else None


def _wait_ready(cache: Path, pid: int | None, timeout_s: float) -> tuple[float, float | None]:
    """Seconds until the ready file appears (and the compiler ended), and the CPU seconds it wrote there."""
    started = time.perf_counter()
    while time.perf_counter() - started < timeout_s:
        ready = list(cache.glob("*/ready-*"))
        if ready and (pid is None or not _running(pid)):
            found = re.search(r"([\d.]+) s of CPU", ready[0].read_text())
            return time.perf_counter() - started, float(found.group(1)) if found else None
        time.sleep(0.2)
    raise SystemExit(f"the background compilation did not finish within {timeout_s:.0f} s")


def _running(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return False
    return state != "Z"


def one(install: bool, python: str, timeout_s: float) -> dict:
    with tempfile.TemporaryDirectory(prefix="viapath-cold-") as folder:
        work, cache = Path(folder), Path(folder, "numba-cache")
        env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
        for name in ("NUMBA_DISABLE_JIT", "VIAPATH_BACKGROUND_COMPILE", "PYTHONPATH"):
            env.pop(name, None)
        if install:
            clone = work / "clone"
            subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
            command: list[str] | str = readme_command().replace("python3 ", f"{python} ", 1)
            cwd = clone
        else:
            env["PYTHONPATH"] = SRC
            command = [sys.executable, "-m", "viapath.cli", "run", "paper-front", "--plot", "front.png"]
            cwd = work
        load_before = os.getloadavg()[0]
        cold, stderr = _timed(command, cwd, env)
        background, cpu = _wait_ready(cache, _background_pid(stderr), timeout_s)
        if install:
            shutil.rmtree(cwd / ".venv")
        warm, _ = _timed(command, cwd, env)
        return {
            "cold_s": round(cold, 2),
            "background_s": round(background, 2),
            "background_cpu_s": cpu,
            "warm_s": round(warm, 2),
            "note": next((line for line in stderr.splitlines() if line.startswith("viapath:")), None),
            "load_before": load_before,
            "load_after": os.getloadavg()[0],
        }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--install", action="store_true", help="time the README's whole command (venv, pip, run)")
    parser.add_argument("--python", default="python3", help="with --install: the Python that makes the venv")
    parser.add_argument("--timeout", type=float, default=900.0, help="seconds to wait for the background compile")
    parser.add_argument("--json", action="store_true")
    arguments = parser.parse_args()
    runs = [one(arguments.install, arguments.python, arguments.timeout) for _ in range(arguments.runs)]
    result = {
        "command": readme_command() if arguments.install else "viapath run paper-front --plot front.png",
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "runs": runs,
    }
    if arguments.json:
        print(json.dumps(result, indent=2))
        return
    print(f"{result['command']}  ({result['cpus']} CPUs)")
    for k, run in enumerate(runs, 1):
        print(
            f"run {k}: cold {run['cold_s']:.1f} s, background compile {run['background_s']:.1f} s "
            f"({run['background_cpu_s']} s CPU), warm {run['warm_s']:.1f} s; load {run['load_before']:.1f} -> "
            f"{run['load_after']:.1f}"
        )


if __name__ == "__main__":
    main()
