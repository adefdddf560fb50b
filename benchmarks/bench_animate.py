"""Time ``viapath run SCENARIO --animate FILE``'s animation step (the episode itself excluded).

Usage: python benchmarks/bench_animate.py [SCENARIO ...] [--format gif|mp4] [--stride N] [--old FILE]

Runs each scenario once (default: paper-front, a 24 s episode: 240 frames), then writes its
animation and prints the wall time of that step, the frames and the file size. ``--old FILE`` times
another animate.py (e.g. ``git show REV:src/viapath/viz/animate.py > old.py``) on the same episode,
for a before/after comparison.
"""

from __future__ import annotations

import argparse
import importlib.util
import tempfile
import time
from pathlib import Path

from viapath.scenarios import load_scenario
from viapath.sim.loop import run_episode
from viapath.viz import animate


def _module(file: str | None):
    if file is None:
        return animate
    spec = importlib.util.spec_from_file_location("animate_under_test", file)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="*", default=["paper-front"])
    parser.add_argument("--format", choices=("gif", "mp4"), default="gif")
    parser.add_argument("--stride", type=int, default=None)
    parser.add_argument("--old", default=None, help="another animate.py to time on the same episodes")
    args = parser.parse_args()
    versions = [("this", animate)] + ([("old", _module(args.old))] if args.old else [])
    with tempfile.TemporaryDirectory() as folder:
        for name in args.scenarios:
            episode = run_episode(load_scenario(name), record_perceived=True)
            steps = len(episode.trace.times_s)
            for label, module in versions:
                file = Path(folder) / f"{name}-{label}.{args.format}"
                kwargs = {"stride": args.stride} if args.stride and label == "this" else {}
                started = time.perf_counter()
                module.animate_episode(episode, file, **kwargs)
                wall = time.perf_counter() - started
                print(
                    f"{name} ({steps} steps, {episode.trace.times_s[-1]:.1f} s) {label}: {wall:.1f} s wall, "
                    f"{file.stat().st_size / 1e6:.2f} MB"
                )


if __name__ == "__main__":
    main()
