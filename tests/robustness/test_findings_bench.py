"""Issue 12, findings 4 and 5: the benchmark never mixes up results, reports crashes, stops on Ctrl-C.

On main, a rerun into a folder of another suite reused its rows ("2 already done"), a crashed
episode counted as done, was hidden from the console table and summary.md and exited 0, and Ctrl-C
exited without a word (sometimes after minutes of loky tracebacks)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from viapath.bench.runner import BenchError, load_suite, read_rows, run_bench
from viapath.bench.suites import generate_suite, write_suite

VIAPATH = str(Path(sys.executable).parent / "viapath")


def _suite(folder: Path, name: str = "paper", count: int = 2, shift: float = 0.0) -> Path:
    scenarios = generate_suite(name, count, seed=0)
    for scenario in scenarios:
        scenario["obstacles"][0]["start"][1] += shift  # same names, other contents when shifted
    write_suite(scenarios, folder)
    return folder


def _app():
    from viapath.cli import app

    return app


def test_finding_4_another_suite_is_refused_not_reused(tmp_path):
    out = tmp_path / "out"
    first = run_bench(load_suite(str(_suite(tmp_path / "a"))), ["follow"], out, progress=False)
    assert first["ran"] == 2
    other = load_suite(str(_suite(tmp_path / "b", shift=0.3)))  # same scenario names, other people
    with pytest.raises(BenchError, match="another suite"):
        run_bench(other, ["follow"], out, progress=False)
    result = CliRunner().invoke(
        _app(),
        ["bench", str(tmp_path / "b"), "--planners", "follow", "--out", str(out), "--workers", "1", "--no-plots"],
    )
    assert result.exit_code == 2 and "another suite" in result.output and "--force" in result.output
    forced = run_bench(other, ["follow"], out, progress=False, force=True)
    assert forced["ran"] == 2 and forced["skipped"] == 0  # nothing of the other suite reused
    assert {r["scenario_hash"] for r in forced["rows"]}.isdisjoint({r["scenario_hash"] for r in first["rows"]})


def test_finding_4_other_perception_or_seed_is_refused(tmp_path):
    suite = load_suite(str(_suite(tmp_path / "a", count=1)))
    run_bench(suite, ["follow"], tmp_path / "out", progress=False, seed=0)
    with pytest.raises(BenchError, match="seed"):
        run_bench(suite, ["follow"], tmp_path / "out", progress=False, seed=1)
    # The same suite with one more planner is the same configuration: only the new rows run.
    more = run_bench(suite, ["follow", "stop"], tmp_path / "out", progress=False, seed=0)
    assert more["ran"] == 1 and more["skipped"] == 1


def test_finding_4_crash_is_reported_rerun_and_exits_non_zero(tmp_path):
    folder = _suite(tmp_path / "suite", count=2)
    broken = sorted(folder.glob("*.yaml"))[0]
    data = yaml.safe_load(broken.read_text())
    good_text = broken.read_text()
    # A replay file that exists but holds no trajectory: the episode fails when it reads it (a bad
    # planner option no longer gets that far: the loader refuses it).
    bad_replay = tmp_path / "not-a-trajectory.txt"
    bad_replay.write_text("frame id x y\nthis is not a number\n")
    data["obstacles"] = [*(data.get("obstacles") or []), {"replay": {"file": str(bad_replay)}}]
    broken.write_text(yaml.safe_dump(data))
    out = tmp_path / "out"
    args = ["bench", str(folder), "--planners", "viapath", "--out", str(out), "--workers", "1", "--no-plots"]
    result = CliRunner().invoke(_app(), args)
    assert result.exit_code == 3, result.output
    assert "crashed" in result.output and data["name"] in result.output
    table_line = next(line for line in result.output.splitlines() if line.startswith("| viapath"))
    assert table_line.rstrip(" |").endswith("1")  # the 'crashed' column of the console table
    summary_md = (out / "summary.md").read_text()
    assert "1 episode(s) crashed" in summary_md and "expected 4 numeric columns" in summary_md
    # Rerun without a fix: the crashed episode runs again (it is not "done").
    again = CliRunner().invoke(_app(), args)
    assert again.exit_code == 3 and "1 episodes run, 1 already done" in again.output
    # Fixing the file changes its content; as every row of it crashed, that is no other suite: it runs.
    broken.write_text(good_text)
    fixed = CliRunner().invoke(_app(), args)
    assert fixed.exit_code == 0, fixed.output
    assert "1 episodes run, 1 already done" in fixed.output
    assert "crashed" not in (out / "summary.md").read_text().split("Per family")[-1]


def test_finding_5_ctrl_c_stops_workers_keeps_rows_and_says_how_to_resume(tmp_path):
    folder = tmp_path / "suite"
    write_suite(generate_suite("crossing", 12, seed=0), folder)
    out = tmp_path / "out"
    command = [
        VIAPATH,
        "bench",
        str(folder),
        "--planners",
        "viapath,dwa",
        "--out",
        str(out),
        "--workers",
        "2",
        "--no-plots",
    ]
    csv_path = out / "episodes.csv"

    def start_and_interrupt(after_rows: int):
        process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        workers: set[int] = set()
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline and process.poll() is None:
            workers |= {
                int(p)
                for p in subprocess.run(
                    ["pgrep", "-P", str(process.pid)], capture_output=True, text=True
                ).stdout.split()
            }
            if csv_path.exists() and len(csv_path.read_text().splitlines()) >= after_rows + 1:  # + header
                break
            time.sleep(0.2)
        assert process.poll() is None, "the run ended before it could be interrupted"
        os.kill(process.pid, signal.SIGINT)
        sent = time.monotonic()
        try:
            _, stderr = process.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            os.kill(process.pid, signal.SIGKILL)
            process.communicate()
            pytest.fail("bench did not stop within 60 s of Ctrl-C")
        return process.returncode, stderr, time.monotonic() - sent, workers

    code, stderr, stopped_after_s, workers = start_and_interrupt(after_rows=1)
    assert code == 130, (code, stderr[-2000:])
    assert stopped_after_s < 10, stopped_after_s
    assert "rerun the same command to resume" in stderr
    assert "Traceback" not in stderr, stderr[-3000:]
    kept = [r for r in read_rows(csv_path) if not r["error"]]
    assert kept, "no finished row was kept"
    assert workers, "no worker process was seen"
    time.sleep(1.0)
    alive = [
        pid
        for pid in workers
        if Path(f"/proc/{pid}").exists() and "Z" not in Path(f"/proc/{pid}/stat").read_text().split()[2]
    ]
    assert alive == [], f"worker processes still alive after Ctrl-C: {alive}"
    # Resume: the kept rows are not run again (no identity twice in the file), new ones are added.
    code, _, _, _ = start_and_interrupt(after_rows=len(kept) + 1)
    rows = read_rows(csv_path)
    keys = [(r["scenario_hash"], r["planner"], r["seed"]) for r in rows if not r["error"]]
    assert len(keys) == len(set(keys)) and len(keys) > len(kept)
