"""Perception speed: detection + tracking of two 683-beam scans with 10 obstacles in view, and ray casting.

    python benchmarks/bench_perception.py [--cycles 2000] [--obstacles 10] [--steps 300]

Prints p50 / p99 per cycle of
* processing (fusion, segmentation, circle fits, leg pairing, association, Kalman update) —
  ray casting excluded; target ≤ 2 ms p99 (issue 3);
* ray casting of both scanners, numpy and (when installed) numba;
* the closed loop (``viapath.sim.loop.run_episode`` with laser perception: both scanners, tracking
  and planning) in simulated steps per second, when the simulator is present.
Not a test: numbers depend on the machine. Run it on an idle machine.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from viapath.compiled import numba_available
from viapath.perception.laser import LaserPerception, ray_casters
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


def percentiles(samples_s) -> str:
    ms = np.asarray(samples_s) * 1e3
    return f"p50 {np.percentile(ms, 50):7.3f} ms   p99 {np.percentile(ms, 99):7.3f} ms   (n={len(ms)})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=2000)
    parser.add_argument("--obstacles", type=int, default=10)
    parser.add_argument("--steps", type=int, default=300, help="closed-loop steps per scenario (0: skip)")
    args = parser.parse_args()
    print(
        f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}, numba: {numba_available()}"
    )

    worlds = [scene(args.obstacles, k) for k in range(args.cycles)]
    fits = ["numpy"] + (["numba"] if numba_available() else [])
    print(
        f"\nprocessing (fusion, segmentation, circle fits, association, Kalman), 2 x 683 beams, {args.obstacles} obstacles:"
    )
    for fit in fits:
        perception = LaserPerception(detector={"keep_segments": False, "fit_compute": fit})
        perception.reset(np.random.default_rng(1))
        scans = [perception.scan(w) for w in worlds]
        for k in range(20):  # warm-up (and numba compilation)
            perception.process(worlds[k].time_s, worlds[k].robot_pose, scans[k])
        perception.reset(np.random.default_rng(1))
        process_s, counts = [], []
        for world, scan in zip(worlds, scans, strict=True):
            started = time.perf_counter()
            obstacles = perception.process(world.time_s, world.robot_pose, scan)
            process_s.append(time.perf_counter() - started)
            counts.append(len(obstacles))
        print(
            f"  circle fit {fit:6s}          {percentiles(process_s)}   "
            f"(median {np.median(counts[50:]):.0f} confirmed tracks)   target p99 <= 2 ms"
        )

    print(f"\nray casting, both scanners, {args.obstacles} discs + 2 walls:")
    backends = ["numpy"] + (["numba"] if numba_available() else [])
    for backend in backends:
        rng = np.random.default_rng(2)
        caster = ray_casters(backend)[0]
        perception = LaserPerception()
        for w in worlds[:5]:
            for s in perception.scanners:
                simulate_scan(s, w.robot_pose, w.obstacle_positions, w.obstacle_radii_m, w.walls, rng, caster)
        cast_s = []
        for w in worlds[: min(len(worlds), 1000)]:
            started = time.perf_counter()
            for s in perception.scanners:
                simulate_scan(s, w.robot_pose, w.obstacle_positions, w.obstacle_radii_m, w.walls, rng, caster)
            cast_s.append(time.perf_counter() - started)
        print(f"  {backend:6s}                     {percentiles(cast_s)}")
    if not numba_available():
        print("  numba: not installed (pip install 'viapath[fast]')")

    if args.steps > 0:
        closed_loop(args.steps, backends)


def closed_loop(steps: int, backends) -> None:
    try:
        from viapath.scenarios import scenario_from_dict
        from viapath.sim.loop import run_episode
    except ImportError:
        print("\nclosed loop: simulator not available")
        return
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
    print(f"\nclosed loop, 10 obstacles, both scanners + tracking + planning, {steps} steps:")
    for mode, options in [("oracle", {})] + [
        ("laser", {"ray_compute": b, "detector": {"fit_compute": b, "keep_segments": False}}) for b in backends
    ]:
        scenario = scenario_from_dict({**base, "perception": {"mode": mode, "options": options}})
        run_episode(scenario, seed=0)  # warm-up (numba compile, caches)
        started = time.perf_counter()
        episode = run_episode(scenario, seed=0)
        elapsed = time.perf_counter() - started
        n = len(episode.trace.times_s)
        label = mode if mode == "oracle" else f"laser/{options['ray_compute']}"
        extra = ""
        if mode == "laser":
            m = episode.metrics
            extra = (
                f"   track RMSE {m['track_position_rmse_m']:.3f} m, {m['track_velocity_rmse_mps']:.3f} m/s;"
                f" perception p99 {m['perception_time_p99_ms']:.2f} ms"
            )
        print(f"  {label:12s} {n / elapsed:8.0f} steps/s  ({n} steps, collision {episode.metrics['collision']}){extra}")
    print("  target: >= 300 steps/s with numpy alone")


if __name__ == "__main__":
    main()
