"""What writing the MCAP costs: a run's wall time with and without ``--mcap`` (target: at most +20 %).

Usage: python benchmarks/bench_mcap.py [--repeats 3] [--scenarios paper-front paper-side:laser zara01] [--loop-only]
                                       [--json]

Each scenario runs once to warm up (imports, numba), then ``repeats`` times each way, interleaved:
``plain`` is ``run_episode`` as ``viapath run`` does it; ``mcap`` is the same run with the MCAP view
as ``viapath run --mcap`` writes it (the messages built and written by a process of its own,
:mod:`viapath.viz.mcap_process`; the viapath planner also keeps every candidate's polyline for
display, part of the cost); ``here`` writes the same file from the run's own process (how the live
view works, and the cost before the writer process); ``cand.`` is the plain run with the
candidates option alone, to show which part of the cost is the planner's.
A scenario ``NAME:laser`` runs with laser perception; ``zara01`` is 20 s among replayed ETH/UCY
people (crowds_zara01.txt; skipped when the data folder is absent). Printed: median wall time of
each; the MCAP run's wall-time overhead over the plain one (the stricter figure), the same for ``here``;
CPU overhead of the run's process alone and of run + writer together (``resource`` children
time, taken after the writer is reaped), the writer process's CPU per cycle (its whole life, start
and end included: less sensitive to the machine's load than wall time), the extra wall milliseconds
per cycle, the file size and the 1-minute load average. The writer process only pays off when a
core is free: on a loaded machine the two processes share one core and the wall overhead
approaches ``here``'s.

Then (unless ``--loop-only``) it times the whole ``viapath run SCENARIO --json`` command in a fresh
process, as a user types it (imports, the run, the file closed), without and with ``--mcap``: what
writing the view costs the user's run, issue 14's target (at most +20 %). The episode loop alone
(above) is the stricter figure: a short run such as paper-front's loop (about 40 ms here) still pays
the writer process's fixed cost (fork, first batch, end of file: about 20 ms).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

from viapath.bench.suites import data_root
from viapath.scenarios import load_scenario, scenario_from_dict
from viapath.sim.loop import run_episode
from viapath.viz.foxglove import display_overrides, record_episode

try:
    from viapath.viz.mcap_process import wait_for_writers
except ImportError:  # an older viapath (measured for comparison) waits for its writer itself

    def wait_for_writers() -> None:
        return None


DEFAULT = ("paper-front", "paper-side:laser", "zara01")


def _zara01() -> dict | None:
    file = data_root() / "eth_ucy_trajectron" / "crowds_zara01.txt"
    if not file.exists():
        return None
    return {
        "name": "zara01-bench",
        "dt_s": 0.1,
        "duration_s": 20.0,
        "robot": {"start": [3.0, 5.0], "heading": 0.0, "speed": 0.3, "radius": 0.25},
        "path": {"waypoints": [[3.0, 5.0], [12.0, 5.0]], "half_width": 1.5},
        "obstacles": [{"replay": {"file": str(file), "dt_s": 0.4, "start_s": 120, "offset": [0, 0], "radius": 0.25}}],
    }


def _scenario(name: str):
    if name == "zara01":
        data = _zara01()
        return None if data is None else scenario_from_dict(data)
    return load_scenario(name)


def measure(name: str, repeats: int, folder: Path) -> dict | None:
    base, _, mode = name.partition(":")
    scenario = _scenario(base)
    if scenario is None:
        return None
    perception = mode or "oracle"
    run_episode(scenario, perception=perception)  # warm-up
    kinds = ("plain", "candidates", "mcap", "here")
    wall = {kind: [] for kind in kinds}
    cpu = {kind: [] for kind in kinds}  # the run's process
    cpu_all = {kind: [] for kind in kinds}  # the run's process and its (reaped) writer process
    overrides = display_overrides(scenario, scenario.planner.name)
    cycles, size = 0, 0

    def children_cpu() -> float:
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        return usage.ru_utime + usage.ru_stime

    def timed(kind, run):
        wall_start, cpu_start, child_start = time.perf_counter(), time.process_time(), children_cpu()
        result = run()
        wall[kind].append(time.perf_counter() - wall_start)
        wait_for_writers()  # the writer's exit is not waited for by the run; its CPU counts once reaped
        cpu[kind].append(time.process_time() - cpu_start)
        cpu_all[kind].append(cpu[kind][-1] + children_cpu() - child_start)
        return result

    for k in range(repeats):
        episode = timed("plain", lambda: run_episode(scenario, perception=perception))
        timed("candidates", lambda: run_episode(scenario, perception=perception, planner_overrides=overrides))
        file = folder / f"{base}-{k}.mcap"
        recorded = timed("mcap", lambda file=file: record_episode(scenario, file, perception=perception, force=True))
        cycles, size = len(recorded.trace.times_s) - 1, file.stat().st_size
        timed(
            "here",
            lambda: record_episode(scenario, folder / "here.mcap", perception=perception, force=True, in_process=True),
        )
        assert len(episode.trace.times_s) == len(recorded.trace.times_s)
    med = {kind: statistics.median(values) for kind, values in wall.items()}
    med_cpu = {kind: statistics.median(values) for kind, values in cpu.items()}
    med_cpu_all = {kind: statistics.median(values) for kind, values in cpu_all.items()}
    p, m, c, h = med["plain"], med["mcap"], med["candidates"], med["here"]
    percent = lambda a, b: 100.0 * (a - b) / b
    return {
        "scenario": name,
        "perception": perception,
        "cycles": cycles,
        "wall_s": wall,
        "cpu_s": cpu,
        "cpu_with_writer_s": cpu_all,
        "plain_median_s": p,
        "mcap_median_s": m,
        "candidates_median_s": c,
        "here_median_s": h,
        "overhead_percent": percent(m, p),
        "here_overhead_percent": percent(h, p),
        "candidates_overhead_percent": percent(c, p),
        "cpu_overhead_percent": percent(med_cpu["mcap"], med_cpu["plain"]),
        "cpu_with_writer_overhead_percent": percent(med_cpu_all["mcap"], med_cpu_all["plain"]),
        "mcap_ms_per_cycle": 1e3 * (m - p) / max(cycles, 1),
        "file_bytes": size,
        "writer_cpu_ms_per_cycle": 1e3
        * statistics.median(a - b for a, b in zip(cpu_all["mcap"], cpu["mcap"]))
        / max(cycles, 1),
        "load_average_1min": os.getloadavg()[0],
    }


def measure_command(name: str, repeats: int, folder: Path) -> dict | None:
    """The whole ``viapath run`` command as a user types it (a fresh process: imports, the run, the
    file closed), without and with ``--mcap``, interleaved; medians of the wall times."""
    base, _, mode = name.partition(":")
    target = base
    if base == "zara01":
        data = _zara01()
        if data is None:
            return None
        target = str(folder / "zara01.yaml")
        Path(target).write_text(yaml.safe_dump(data))
    command = [sys.executable, "-m", "viapath.cli", "run", target, "--json"] + (["--perception", mode] if mode else [])
    mcap = ["--mcap", str(folder / f"{base}-command.mcap"), "--force"]
    subprocess.run(command + mcap, check=True, capture_output=True)  # warm-up (numba's cache, page cache)
    wall = {"plain": [], "mcap": []}
    for _ in range(repeats):
        for kind, extra in (("plain", []), ("mcap", mcap)):
            started = time.perf_counter()
            subprocess.run(command + extra, check=True, capture_output=True)
            wall[kind].append(time.perf_counter() - started)
    p, m = statistics.median(wall["plain"]), statistics.median(wall["mcap"])
    return {
        "scenario": name,
        "command_wall_s": wall,
        "command_plain_median_s": p,
        "command_mcap_median_s": m,
        "command_overhead_percent": 100.0 * (m - p) / p,
        "load_average_1min": os.getloadavg()[0],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scenarios", nargs="+", default=list(DEFAULT))
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--loop-only",
        action="store_true",
        help="skip timing the whole `viapath run` command (a fresh process) without and with --mcap",
    )
    args = parser.parse_args()
    results = []
    with tempfile.TemporaryDirectory() as folder:
        for name in args.scenarios:
            result = measure(name, args.repeats, Path(folder))
            if result is None:
                print(f"{name}: skipped (data not found under {data_root()})") if not args.json else None
                continue
            results.append(result)
        commands = (
            [c for c in (measure_command(name, args.repeats, Path(folder)) for name in args.scenarios) if c is not None]
            if not args.loop_only
            else []
        )
    if args.json:
        print(
            json.dumps(
                {"python": platform.python_version(), "repeats": args.repeats, "results": results, "commands": commands}
            )
        )
        return
    print(f"python {platform.python_version()}, {platform.machine()}, {args.repeats} repeats each (medians)")
    print(
        f"{'scenario':18s} {'cycles':>6s} {'plain s':>8s} {'mcap s':>8s} {'wall +':>8s} {'here +':>8s} "
        f"{'cand. +':>8s} {'CPU run +':>10s} {'CPU all +':>10s} {'writer':>7s} {'ms/cycle':>9s} {'file':>8s} "
        f"{'load':>5s}"
    )
    for r in results:
        print(
            f"{r['scenario']:18s} {r['cycles']:6d} {r['plain_median_s']:8.2f} {r['mcap_median_s']:8.2f} "
            f"{r['overhead_percent']:7.1f}% {r['here_overhead_percent']:7.1f}% "
            f"{r['candidates_overhead_percent']:7.1f}% {r['cpu_overhead_percent']:9.1f}% "
            f"{r['cpu_with_writer_overhead_percent']:9.1f}% {r['writer_cpu_ms_per_cycle']:7.2f} "
            f"{r['mcap_ms_per_cycle']:9.2f} "
            f"{r['file_bytes'] / 1e6:6.2f}MB {r['load_average_1min']:5.1f}"
        )
    for c in commands:
        print(
            f"{c['scenario']:18s} whole command: {c['command_plain_median_s']:.2f} s -> "
            f"{c['command_mcap_median_s']:.2f} s with --mcap ({c['command_overhead_percent']:+.1f} %), "
            f"load {c['load_average_1min']:.1f}"
        )


if __name__ == "__main__":
    main()
