"""The laser chain's compiled steps are compiled once per machine: a second process loads them from the cache.

Compiled functions that were closures had cache entries that never matched, so every process compiled
again (~10 s). Two fresh interpreters share one empty ``NUMBA_CACHE_DIR``; the first must compile (cache
misses), the second must load every step from disk (hits, no misses).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("numba")

SRC = str(Path(__file__).resolve().parents[2] / "src")

SCRIPT = r"""
import json
import numpy as np
from viapath.perception import circle_fit, raycast
from viapath.perception.circle_fit import fit_circles
from viapath.perception.raycast import cast_rays

angles = np.linspace(-2.0, 2.0, 50)
ranges = cast_rays((0.0, 0.0), angles, [[2.0, 0.0]], [0.3], [[[-1.0, 3.0], [5.0, 3.0]]])
pts = np.stack([2.0 - 0.3 * np.cos(np.linspace(-1, 1, 9)), 0.3 * np.sin(np.linspace(-1, 1, 9))], -1)
fit_circles(pts, [0], [9], radius_prior_m=0.25)
fit_circles(pts, [0], [9])
out = {}
for name, function in (("cast_beams", raycast.cast_beams), ("fit_clusters", circle_fit.fit_clusters)):
    stats = function.stats
    out[name] = {"hits": sum(stats.cache_hits.values()), "misses": sum(stats.cache_misses.values())}
out["finite_ranges"] = int(np.isfinite(ranges).sum())
print(json.dumps(out))
"""


def _start(cache_dir: Path) -> subprocess.Popen:
    env = {
        **os.environ,
        "NUMBA_CACHE_DIR": str(cache_dir),
        "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", ""),
    }
    env.pop("NUMBA_DISABLE_JIT", None)
    return subprocess.Popen(
        [sys.executable, "-c", SCRIPT], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )


def _result(process: subprocess.Popen) -> dict:
    try:
        out, err = process.communicate(timeout=300)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 0, err
    return json.loads(out.strip().splitlines()[-1])


def _run(cache_dir: Path) -> dict:
    return _result(_start(cache_dir))


def test_second_process_loads_every_kernel_from_the_cache(tmp_path):
    """The first fill is two processes compiling into the empty cache at once (numba writes each file atomically;
    the two add the same signatures in the same order): the third loads everything, the same answers."""
    both = [_start(tmp_path), _start(tmp_path)]
    first, other = (_result(process) for process in both)
    assert other["finite_ranges"] == first["finite_ranges"]
    files_after_first = sorted(p.name for p in tmp_path.rglob("*.nb[ci]"))
    second = _run(tmp_path)
    assert first["finite_ranges"] == second["finite_ranges"] > 0
    # The cast and the fit are called from Python; what they call is compiled into them.
    for name in ("cast_beams", "fit_clusters"):
        assert first[name]["misses"] + other[name]["misses"] >= 1, (name, first, other)  # the empty cache was filled
        assert second[name]["misses"] == 0, (name, second)  # nothing compiled the second time
        assert second[name]["hits"] >= 1, (name, second)
    assert any(name.endswith(".nbi") for name in files_after_first), "no cache index written"
    # The second process added no cache entry (closures would add one per process start).
    assert sorted(p.name for p in tmp_path.rglob("*.nb[ci]")) == files_after_first
