"""What numba's compilation costs on the first run after install, and what loading it from the cache costs later.

    python benchmarks/bench_numba_cache.py [--runs 3] [--json]

Each run starts two fresh interpreters on one empty ``NUMBA_CACHE_DIR`` (the first compiles the
laser chain's compiled ray casting and circle fit, the second loads them) and times the
first call of each, wall clock and process CPU time (the machine is shared: CPU time is the
steadier figure). Not a test: numbers depend on the machine.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

SRC = str(Path(__file__).resolve().parents[1] / "src")

SCRIPT = r"""
import json, time
import numpy as np
t0, c0 = time.perf_counter(), time.process_time()
from viapath.perception.circle_fit import fit_circles
from viapath.perception.raycast import simulate_scans
from viapath.perception.scanner import paper_scanners
simulate_scans(paper_scanners(), np.zeros(3), [[2.0, 0.0]], [0.3], [[[-1.0, 3.0], [5.0, 3.0]]])
pts = np.stack([2.0 - 0.3 * np.cos(np.linspace(-1, 1, 9)), 0.3 * np.sin(np.linspace(-1, 1, 9))], -1)
fit_circles(pts, [0], [9], radius_prior_m=0.25)
print(json.dumps({"wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}))
"""


def one(cache: str) -> dict:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}
    done = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    runs = []
    for run in range(args.runs):
        with tempfile.TemporaryDirectory() as cache:
            load = os.getloadavg()
            cold, warm = one(cache), one(cache)
        runs.append({"run": run + 1, "load_average": load, "first_process": cold, "second_process": warm})
        if not args.json:
            print(
                f"run {run + 1} (load {' '.join(f'{v:.2f}' for v in load)}): first process (compiles) "
                f"{cold['wall_s']:.2f} s wall / {cold['cpu_s']:.2f} s CPU; second (cache) "
                f"{warm['wall_s']:.2f} s wall / {warm['cpu_s']:.2f} s CPU"
            )
    if args.json:
        print(json.dumps({"runs": runs}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
