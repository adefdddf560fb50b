"""One writer per results folder, torn rows, SIGTERM and killed workers: real processes, signalled by pid.

On main a worker killed with SIGKILL ended the run in a TerminatedWorkerError traceback (exit 1), a
last CSV row cut mid-write had the next run glue a new row onto it, SIGTERM left worker processes
running and exited without a word, and two benches into the same --out ran the same episodes twice."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from viapath.bench.runner import COLUMNS, LOCK_FILE, load_suite, read_rows, repair_torn_tail, run_bench
from viapath.bench.suites import generate_suite, write_suite

VIAPATH = str(Path(sys.executable).parent / "viapath")
WAIT_S = 120.0  # generous: two cores shared with other work; only a bound, never a measured speed


def _suite(folder: Path, name: str = "crowd", count: int = 6) -> Path:
    write_suite(generate_suite(name, count, seed=0), folder)
    return folder


def _wait_for(condition, what: str, timeout: float = WAIT_S):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.2)
    raise AssertionError(f"timed out waiting for {what}")


def _rows_written(csv_path: Path) -> int:
    if not csv_path.exists():
        return 0
    return max(0, csv_path.read_bytes().count(b"\n") - 1)


def _children(pid: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                found.append(int(entry.name))
    return found


def _is_worker(pid: int) -> bool:
    try:
        return b"popen_loky_posix" in Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return False


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _bench(suite: Path, out: Path, planners: str = "viapath", workers: int = 2) -> subprocess.Popen:
    return subprocess.Popen(
        [
            VIAPATH,
            "bench",
            str(suite),
            "--planners",
            planners,
            "--out",
            str(out),
            "--workers",
            str(workers),
            "--no-plots",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _valid_rows(csv_path: Path) -> list[dict]:
    with open(csv_path, newline="") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == COLUMNS
    assert all(len(row) == len(COLUMNS) for row in rows[1:]), "a row glued or cut"
    return read_rows(csv_path)


def _hold(out: Path) -> subprocess.Popen:
    """Another process holding the results folder (as a running bench does)."""
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time\nfrom pathlib import Path\n"
            "from viapath.bench.runner import results_lock\n"
            f"with results_lock(Path({str(out)!r})):\n    print('held', flush=True)\n"
            "    time.sleep(600)\n",
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert holder.stdout.readline().strip() == "held"
    return holder


def test_a_second_bench_into_a_busy_folder_is_refused_naming_it(tmp_path):
    suite, out = _suite(tmp_path / "suite", "paper", 1), tmp_path / "out"
    holder = _hold(out)
    try:
        second = subprocess.run(
            [VIAPATH, "bench", str(suite), "--planners", "follow", "--out", str(out), "--workers", "1", "--no-plots"],
            capture_output=True,
            text=True,
            timeout=WAIT_S,
        )
    finally:
        holder.kill()
        holder.wait(timeout=WAIT_S)
    assert second.returncode == 2, second.stderr
    assert f"{out}: another viapath bench (pid {holder.pid})" in second.stderr and "Traceback" not in second.stderr
    assert out.is_dir()  # the folder of the run holding it is left alone


def test_sigterm_ends_like_ctrl_c_keeps_rows_and_stops_the_workers(tmp_path):
    suite, out = _suite(tmp_path / "suite", count=12), tmp_path / "out"
    bench = _bench(suite, out)
    try:
        workers = _wait_for(
            lambda: (
                [pid for pid in _children(bench.pid) if _is_worker(pid)]
                if _rows_written(out / "episodes.csv") >= 1
                else []
            ),
            "a row and the workers",
        )
        bench.send_signal(signal.SIGTERM)
        _, stderr = bench.communicate(timeout=WAIT_S)
    finally:
        if bench.poll() is None:
            bench.kill()
    assert bench.returncode == 130, stderr
    assert "terminated (SIGTERM)" in stderr and "Traceback" not in stderr
    _wait_for(lambda: not any(_alive(pid) for pid in workers), "the workers to end", timeout=30)
    rows = _valid_rows(out / "episodes.csv")
    assert 1 <= len(rows) < 12 and len({r["scenario"] for r in rows}) == len(rows)


def test_a_killed_worker_ends_the_run_with_exit_3_and_keeps_the_rows(tmp_path):
    suite, out = _suite(tmp_path / "suite"), tmp_path / "out"
    bench = _bench(suite, out)
    try:
        workers = _wait_for(
            lambda: (
                [pid for pid in _children(bench.pid) if _is_worker(pid)]
                if _rows_written(out / "episodes.csv") >= 1
                else []
            ),
            "a row and the workers",
        )
        os.kill(workers[0], signal.SIGKILL)
        _, stderr = bench.communicate(timeout=WAIT_S)
    finally:
        if bench.poll() is None:
            bench.kill()
    assert bench.returncode == 3, stderr
    assert "a worker process died" in stderr and "Traceback" not in stderr
    _wait_for(lambda: not any(_alive(pid) for pid in workers), "the other workers to end", timeout=30)
    assert len(_valid_rows(out / "episodes.csv")) >= 1


def test_a_crashed_holder_leaves_no_lock_behind(tmp_path):
    from viapath.bench.runner import FolderBusy

    out = tmp_path / "out"
    scenarios = load_suite(str(_suite(tmp_path / "suite", "paper", 1)))
    holder = _hold(out)
    try:
        with pytest.raises(FolderBusy, match=f"{out}: another viapath bench \\(pid {holder.pid}\\)"):
            run_bench(scenarios, ["follow"], out, progress=False)
        os.kill(holder.pid, signal.SIGKILL)
        holder.wait(timeout=WAIT_S)
    finally:
        if holder.poll() is None:
            holder.kill()
    assert (out / LOCK_FILE).exists()  # the file stays; the kernel's lock went with the process
    assert run_bench(scenarios, ["follow"], out, progress=False)["ran"] == 1


@pytest.mark.parametrize("cut", [1, 17, 60, "whole-row-but-newline"])
def test_a_torn_last_row_is_repaired_and_reported(tmp_path, cut):
    scenarios = load_suite(str(_suite(tmp_path / "suite", "paper", 3)))
    out = tmp_path / "out"
    run_bench(scenarios, ["follow"], out, progress=False)
    csv_path = out / "episodes.csv"
    data = csv_path.read_bytes()
    csv_path.write_bytes(data[:-1] if cut == "whole-row-but-newline" else data[:-cut])
    notes: list[str] = []
    result = run_bench(scenarios, ["follow", "stop"], out, progress=False, note=notes.append)
    assert notes and "cut off mid-write" in notes[0] and str(csv_path) in notes[0]
    assert result["repaired"] == notes[0]
    assert result["ran"] == 4  # the torn episode again, and stop's three
    rows = _valid_rows(csv_path)
    assert len(rows) == 6 and not any(r["error"] for r in rows)
    again = run_bench(scenarios, ["follow", "stop"], out, progress=False, note=notes.append)
    assert again["ran"] == 0 and len(notes) == 1


def test_a_torn_header_is_repaired(tmp_path):
    csv_path = tmp_path / "episodes.csv"
    csv_path.write_text("scenario,fam")
    assert "header" in repair_torn_tail(csv_path)
    assert csv_path.read_bytes() == b""
