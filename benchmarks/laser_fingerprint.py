"""Fingerprint of the laser chain's output, to show that a change leaves it bit for bit the same.

    PYTHONPATH=src python benchmarks/laser_fingerprint.py [--steps 600]

Runs ``LaserPerception(detector={"keep_segments": False})`` (the default chain) over the scene of
``bench_perception.py`` (``scene(10, k)`` for k < steps, generator ``default_rng(1)``) and prints a SHA-256 of
every step's Obstacles (positions, velocities, radii, position and velocity sigmas, ids: exact bytes) and one
of every step's static layer (segments, radii). Run it on two versions of the code (another checkout on
``PYTHONPATH``): equal digests mean the planner was handed the same obstacles and the same static geometry.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_perception import scene

from viapath.perception.laser import LaserPerception


def fingerprint(steps: int) -> tuple[str, str, int]:
    """The digests of the reported obstacles and of the static layers of ``steps`` steps, and the obstacles
    reported."""
    perception = LaserPerception(detector={"keep_segments": False})
    perception.reset(np.random.default_rng(1))
    tracks, static, reported = hashlib.sha256(), hashlib.sha256(), 0
    for k in range(steps):
        world = scene(10, k)
        obstacles = perception.observe(world)
        reported += len(obstacles)
        for array in (
            obstacles.positions,
            obstacles.velocities,
            obstacles.radii_m,
            obstacles.position_sigma_m,
            obstacles.velocity_sigma_mps,
            obstacles.ids,
        ):
            tracks.update(np.ascontiguousarray(array).tobytes())
        layer = perception.static_layer(world)
        for array in (layer.segments, layer.radii_m):
            static.update(np.ascontiguousarray(array).tobytes())
    return tracks.hexdigest(), static.hexdigest(), reported


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=600)
    args = parser.parse_args(argv)
    tracks, static, reported = fingerprint(args.steps)
    print(f"obstacles {tracks} ({reported} reported)")
    print(f"static layer {static}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
