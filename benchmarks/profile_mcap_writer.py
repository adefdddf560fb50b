"""Where the MCAP writer's time goes: a run's cycles replayed through the writer's work in one process.

Usage: python benchmarks/profile_mcap_writer.py [SCENARIO] [--perception laser] [--repeats 5]
                                                [--profile] [--top 40]

Runs SCENARIO once (``zara01``: 20 s among replayed ETH/UCY people, as in ``bench_mcap.py``)
with the viapath planner keeping its candidates, keeps what the run's process hands to the writer
process each cycle (:func:`viapath.viz.mcap_process.cycle_input`, pickled as it is sent), then
does the writer's work on it in this process: unpickle, build the scene, encode and log every
topic into an LZ4 MCAP file. Printed: the run's CPU per cycle, the hand-off's (packing and
pickling) per cycle and the writer's CPU per cycle (best and median of ``repeats`` replays, warm:
the writer process itself also pays its start, its end and colder caches; ``bench_mcap.py``'s
``writer`` column is that figure). ``--profile``: cProfile of one replay, by own time.
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pickle
import pstats
import statistics
import sys
import tempfile
import time
from pathlib import Path

import foxglove
from foxglove.mcap import MCAPCompression, MCAPWriteOptions

from viapath.path import DesignatedPath
from viapath.scenarios import load_scenario
from viapath.sim.loop import run_episode
from viapath.viz.foxglove import FoxglovePublisher, display_overrides
from viapath.viz.mcap_process import cycle_input, static_input


def _scenario(name: str):
    if name == "zara01":
        sys.path.insert(0, str(Path(__file__).parent))
        from bench_mcap import _scenario as bench_scenario

        scenario = bench_scenario("zara01")
        if scenario is None:
            raise SystemExit("zara01: data not found")
        return scenario
    return load_scenario(name)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default="paper-front")
    parser.add_argument("--perception", default="oracle")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--top", type=int, default=40)
    args = parser.parse_args()
    scenario = _scenario(args.scenario)
    messages, static, pack_s = [], [], [0.0]

    def on_step(record):
        if not static:
            static.append(static_input(record))
        started = time.process_time()
        messages.append(pickle.dumps(cycle_input(record), protocol=pickle.HIGHEST_PROTOCOL))
        pack_s[0] += time.process_time() - started

    overrides = display_overrides(scenario, scenario.planner.name)
    run_episode(scenario, perception=args.perception, planner_overrides=overrides)  # warm-up
    started = time.process_time()
    run_episode(scenario, perception=args.perception, planner_overrides=overrides, on_step=on_step)
    run_s = time.process_time() - started - pack_s[0]
    cycles = len(messages)
    path = DesignatedPath(scenario.path.waypoints, half_widths_m=scenario.path.widths())

    def replay(file: str) -> None:
        context = foxglove.Context()
        writer = foxglove.open_mcap(
            file,
            allow_overwrite=True,
            context=context,
            writer_options=MCAPWriteOptions(compression=MCAPCompression.Lz4),
        )
        publisher = FoxglovePublisher(context, path, scenario.robot.radius)
        publisher.start(static[0])
        for message in messages:
            publisher.publish(publisher.build(pickle.loads(message)))
        writer.close()

    with tempfile.TemporaryDirectory() as folder:
        file = os.path.join(folder, "replay.mcap")
        replay(file)  # warm-up
        if args.profile:
            profile = cProfile.Profile()
            profile.enable()
            replay(file)
            profile.disable()
            pstats.Stats(profile).sort_stats("tottime").print_stats(args.top)
        times = []
        for _ in range(args.repeats):
            started = time.process_time()
            replay(file)
            times.append(time.process_time() - started)
    per_cycle = lambda seconds: 1e3 * seconds / cycles
    print(
        f"{args.scenario} ({args.perception}): {cycles} cycles; run {per_cycle(run_s):.3f} ms/cycle CPU, "
        f"hand-off {per_cycle(pack_s[0]):.3f}, payload {statistics.mean(map(len, messages)):.0f} B; writer "
        f"{per_cycle(min(times)):.3f} best / {per_cycle(statistics.median(times)):.3f} median ms/cycle CPU; "
        f"load {os.getloadavg()[0]:.2f}"
    )


if __name__ == "__main__":
    main()
