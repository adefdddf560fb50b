"""Fingerprint of the laser chain's output, to show that a change leaves it bit for bit the same.

    PYTHONPATH=src python benchmarks/laser_fingerprint.py [--steps 600]

Runs ``LaserPerception(ray_compute=B, detector={"keep_segments": False, "fit_compute": B})`` over the
scene of ``bench_perception.py`` (``scene(10, k)`` for k < steps, generator ``default_rng(1)``) for
B = numpy and numba, and prints per back end a SHA-256 of every step's Obstacles (positions,
velocities, radii, position and velocity sigmas, ids: exact bytes). Run it on two versions of the code
(another checkout on ``PYTHONPATH``): equal digests mean the planner was handed the same obstacles.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_perception import scene

from viapath.compiled import numba_available
from viapath.perception.laser import LaserPerception


def fingerprint(backend: str, steps: int) -> tuple[str, int]:
    perception = LaserPerception(ray_compute=backend, detector={"keep_segments": False, "fit_compute": backend})
    perception.reset(np.random.default_rng(1))
    digest, reported = hashlib.sha256(), 0
    for k in range(steps):
        obstacles = perception.observe(scene(10, k))
        reported += len(obstacles)
        for array in (
            obstacles.positions,
            obstacles.velocities,
            obstacles.radii_m,
            obstacles.position_sigma_m,
            obstacles.velocity_sigma_mps,
            obstacles.ids,
        ):
            digest.update(np.ascontiguousarray(array).tobytes())
    return digest.hexdigest(), reported


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=600)
    args = parser.parse_args(argv)
    for backend in ["numpy"] + (["numba"] if numba_available() else []):
        digest, reported = fingerprint(backend, args.steps)
        print(backend, digest, f"({reported} obstacles reported)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
