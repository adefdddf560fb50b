"""Perception speed: detection + tracking of two 683-beam scans with 10 obstacles in view, and ray casting.

    python benchmarks/bench_perception.py [--cycles 2000] [--obstacles 10] [--steps 300] [--json]

Prints p50 / p99 per cycle of
* processing (fusion, segmentation, circle fits, leg pairing, association, Kalman update, static layer) —
  ray casting excluded; target ≤ 2 ms p99;
* ray casting of both scanners;
* the closed loop (``viapath.sim.loop.run_episode`` with laser perception: both scanners, tracking
  and planning) in simulated steps per second, when the simulator is present.
The laser chain is compiled where numba is installed (``viapath.jit.enabled()``, printed), plain Python
with ``NUMBA_DISABLE_JIT=1``. Not a test: numbers depend on the machine. Run it on an idle machine.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

import numpy as np

from viapath.jit import enabled
from viapath.perception.laser import LaserPerception
from viapath.perception.raycast import simulate_scan
from viapath.sim.perception import WorldSnapshot


def scene(n_obstacles: int, k: int, dt: float = 0.1):
    """n obstacles circling a robot that drives at 0.3 m/s between walls at ±4 m.

    Obstacle i keeps its distance ρ_i (1.2–3.5 m) from the robot and circles it at 0.2–0.8 m/s
    (alternate directions), so all n stay in view for the whole run (some occlude others at times).
    """
    rng = np.random.default_rng(0)
    rho = rng.uniform(1.2, 3.5, n_obstacles)
    phase = np.linspace(-np.pi, np.pi, n_obstacles, endpoint=False)
    omega = rng.uniform(0.2, 0.8, n_obstacles) / rho * np.where(np.arange(n_obstacles) % 2, 1.0, -1.0)
    t = k * dt
    pose = np.array([0.3 * t, 0.0, 0.0])
    angle = phase + omega * t
    positions = pose[:2] + rho[:, None] * np.stack([np.cos(angle), np.sin(angle)], -1)
    velocities = np.array([0.3, 0.0]) + (rho * omega)[:, None] * np.stack([-np.sin(angle), np.cos(angle)], -1)
    walls = np.array([[[-20, -4.0], [400, -4.0]], [[-20, 4.0], [400, 4.0]]])
    return WorldSnapshot(t, pose, 0.25, positions, velocities, np.full(n_obstacles, 0.25), walls)


def percentiles(samples_s) -> dict:
    ms = np.asarray(samples_s) * 1e3
    return {"p50_ms": float(np.percentile(ms, 50)), "p99_ms": float(np.percentile(ms, 99)), "n": len(ms)}


def shown(figures: dict) -> str:
    return f"p50 {figures['p50_ms']:7.3f} ms   p99 {figures['p99_ms']:7.3f} ms   (n={figures['n']})"


def processing(worlds) -> tuple[dict, float]:
    """Per-cycle time of ``LaserPerception.process`` on pre-cast scans, and the median of confirmed tracks."""
    perception = LaserPerception(detector={"keep_segments": False})
    perception.reset(np.random.default_rng(1))
    scans = [perception.scan(w) for w in worlds]
    for k in range(20):  # warm-up (and numba's cache load)
        perception.process(worlds[k].time_s, worlds[k].robot_pose, scans[k])
    perception.reset(np.random.default_rng(1))
    process_s, counts = [], []
    for world, scan in zip(worlds, scans, strict=True):
        started = time.perf_counter()
        obstacles = perception.process(world.time_s, world.robot_pose, scan)
        process_s.append(time.perf_counter() - started)
        counts.append(len(obstacles))
    return percentiles(process_s), float(np.median(counts[50:]))


def ray_casting(worlds) -> dict:
    """Per-cycle time of casting both scanners (``simulate_scan`` each, with range noise)."""
    rng = np.random.default_rng(2)
    perception = LaserPerception()
    for w in worlds[:5]:
        for s in perception.scanners:
            simulate_scan(s, w.robot_pose, w.obstacle_positions, w.obstacle_radii_m, w.walls, rng)
    cast_s = []
    for w in worlds[: min(len(worlds), 1000)]:
        started = time.perf_counter()
        for s in perception.scanners:
            simulate_scan(s, w.robot_pose, w.obstacle_positions, w.obstacle_radii_m, w.walls, rng)
        cast_s.append(time.perf_counter() - started)
    return percentiles(cast_s)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=2000)
    parser.add_argument("--obstacles", type=int, default=10)
    parser.add_argument("--steps", type=int, default=300, help="closed-loop steps per scenario (0: skip)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    worlds = [scene(args.obstacles, k) for k in range(args.cycles)]
    results: dict = {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "machine": platform.machine(),
        "compiled": enabled(),
        "load_average": os.getloadavg(),
        "obstacles": args.obstacles,
    }
    results["processing"], tracks = processing(worlds)
    results["confirmed_tracks_median"] = tracks
    results["ray_casting"] = ray_casting(worlds)
    if args.steps > 0:
        results["closed_loop"] = closed_loop(args.steps)
    if args.json:
        print(json.dumps(results, indent=2))
        return
    print(f"python {results['python']}, numpy {results['numpy']}, {results['machine']}, compiled: {enabled()}")
    print(f"load average {' '.join(f'{v:.2f}' for v in results['load_average'])}")
    print("\nprocessing (fusion, segmentation, circle fits, association, Kalman, static layer), 2 x 683 beams:")
    print(f"  {shown(results['processing'])}   (median {tracks:.0f} confirmed tracks)   target p99 <= 2 ms")
    print(f"\nray casting, both scanners, {args.obstacles} discs + 2 walls:\n  {shown(results['ray_casting'])}")
    if args.steps > 0:
        print(f"\nclosed loop, 10 obstacles, both scanners + tracking + planning, {args.steps} steps:")
        for label, row in results["closed_loop"].items():
            extra = ""
            if label == "laser":
                extra = (
                    f"   track RMSE {row['track_position_rmse_m']:.3f} m, {row['track_velocity_rmse_mps']:.3f} m/s;"
                    f" perception p99 {row['perception_time_p99_ms']:.2f} ms"
                )
            steps, collision = row["steps"], row["collision"]
            print(f"  {label:8s} {row['steps_per_s']:8.0f} steps/s  ({steps} steps, collision {collision}){extra}")


def closed_loop(steps: int) -> dict:
    """Simulated steps per second of ``run_episode`` with oracle and with laser perception (10 obstacles)."""
    from viapath.scenarios import scenario_from_dict
    from viapath.sim.loop import run_episode

    rng = np.random.default_rng(3)
    obstacles = []
    for _i in range(10):
        y = rng.uniform(-3.0, 3.0)
        x = rng.uniform(2.0, 14.0)
        obstacles.append(
            {
                "start": [float(x), float(y)],
                "velocity": [float(rng.uniform(-0.4, 0.4)), float(-np.sign(y) * 0.1)],
                "radius": 0.25,
            }
        )
    base = {
        "name": "bench-10",
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.2, "radius": 0.25},
        "path": {"waypoints": [[0.0, 0.0], [15.0, 0.0]], "half_width": 1.5},
        "obstacles": obstacles,
        "walls": [[[-2.0, -4.0], [20.0, -4.0]], [[-2.0, 4.0], [20.0, 4.0]]],
        "duration_s": steps * 0.1,
    }
    out = {}
    for mode, options in (("oracle", {}), ("laser", {"detector": {"keep_segments": False}})):
        scenario = scenario_from_dict({**base, "perception": {"mode": mode, "options": options}})
        run_episode(scenario, seed=0)  # warm-up (numba's cache load, caches)
        started = time.perf_counter()
        episode = run_episode(scenario, seed=0)
        elapsed = time.perf_counter() - started
        n = len(episode.trace.times_s)
        m = episode.metrics
        out[mode] = {"steps_per_s": n / elapsed, "steps": n, "collision": m["collision"]}
        if mode == "laser":
            for key in ("track_position_rmse_m", "track_velocity_rmse_mps", "perception_time_p99_ms"):
                out[mode][key] = m[key]
    return out


if __name__ == "__main__":
    main()
