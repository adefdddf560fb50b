"""The static layer's own time from real scans (about 1 500 returns): marking, thinning, memory, merging.

    python benchmarks/bench_static_layer.py [--cycles 300] [--tracks 0] [--first-scan 50] [--clock wall|cpu] [--json]

Two consecutive real scans of ``leg_tracker_laser/positive_2.bag`` (../shared/data, or $VIAPATH_DATA), the
first as a forward scanner and the second turned round as a backward one (as ``bench_static.py`` makes its
layer). One cycle is ``StaticObstacleLayer.update`` with the layer of the cycle before in memory (the robot
standing still, 0.1 s later): the marking of every return, the thinning of the runs into segments, the
memory's check of last cycle's segments against the scans and the merging into shapes. ``--tracks N`` puts N
person tracks (r = 0.25 m) on returns, so that the marking also sets aside the returns tracks explain.
Prints p50, p99 and max over ``--cycles`` cycles and the machine's load average (run it three times). Wall
clock by default; ``--clock cpu`` takes the thread's CPU time. Not a test: numbers depend on the machine.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from viapath.bench.suites import data_root
from viapath.io.rosbag import read_laser_scans
from viapath.perception.static_layer import StaticObstacleLayer


def real_scans(first_scan: int):
    """The two scanners and their ranges: scans ``first_scan`` and the next of positive_2.bag."""
    bag = Path(data_root()) / "leg_tracker_laser" / "positive_2.bag"
    scans = []
    for index, message in enumerate(read_laser_scans(bag)):
        if index >= first_scan:
            scans.append(message)
        if len(scans) == 2:
            break
    front = scans[0].scanner_model("front")
    rear = replace(scans[1].scanner_model("rear"), mount_yaw_rad=scans[1].scanner_model().mount_yaw_rad + np.pi)
    return (front, rear), [scans[0].ranges_m, scans[1].ranges_m]


def tracks_on_returns(layer: StaticObstacleLayer, ranges, count: int, rng) -> np.ndarray:
    """``count`` track positions on returns of the first scanner (robot at the origin)."""
    scanner = layer.scanners[0]
    valid = np.flatnonzero(np.isfinite(ranges[0]) & (ranges[0] > scanner.range_min_m))
    beams = rng.choice(valid, size=min(count, len(valid)), replace=False)
    x, y, yaw = scanner.world_pose(np.zeros(3))
    angles = scanner.beam_angles_rad()[beams] + yaw
    return np.stack([x + ranges[0][beams] * np.cos(angles), y + ranges[0][beams] * np.sin(angles)], 1)


def measure(cycles: int, tracks: int, first_scan: int, clock) -> dict:
    scanners, ranges = real_scans(first_scan)
    layer = StaticObstacleLayer(scanners)
    positions = tracks_on_returns(layer, ranges, tracks, np.random.default_rng(0))
    radii = np.full(len(positions), 0.25)
    layer.update(0.0, np.zeros(3), ranges, positions, radii)  # warm-up (and numba's cache load)
    samples = []
    for k in range(cycles):
        layer.reset()
        layer.update(0.0, np.zeros(3), ranges, positions, radii)
        started = clock()
        static = layer.update(0.1 * (k + 1), np.zeros(3), ranges, positions, radii)
        samples.append((clock() - started) * 1e3)
    samples_ms = np.array(samples)
    return {
        "returns": int(sum(np.isfinite(r).sum() for r in ranges)),
        "segments": len(static),
        "tracks": len(positions),
        "p50_ms": float(np.percentile(samples_ms, 50)),
        "p99_ms": float(np.percentile(samples_ms, 99)),
        "max_ms": float(samples_ms.max()),
        "cycles": cycles,
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=300)
    parser.add_argument("--tracks", type=int, default=0)
    parser.add_argument("--first-scan", type=int, default=50)
    parser.add_argument("--clock", choices=("wall", "cpu"), default="wall")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    clock = time.perf_counter if args.clock == "wall" else time.thread_time
    figures = measure(args.cycles, args.tracks, args.first_scan, clock)
    figures["load_average"] = os.getloadavg()
    figures["clock"] = args.clock
    if args.json:
        print(json.dumps(figures, indent=2))
        return
    print(
        f"{figures['returns']} returns, {figures['tracks']} tracks -> {figures['segments']} segments: layer "
        f"p50 {figures['p50_ms']:.3f} ms  p99 {figures['p99_ms']:.3f} ms  max {figures['max_ms']:.3f} ms "
        f"({args.cycles} cycles, {args.clock} clock); load {' '.join(f'{v:.2f}' for v in figures['load_average'])}"
    )


if __name__ == "__main__":
    main()
