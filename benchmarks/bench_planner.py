"""Planning time per cycle of viapath (numpy and compiled) and its peers on the same scenes: p50/p99.

Usage: python benchmarks/bench_planner.py [--cycles 300] [--seed 0] [--obstacles 1,10,50,100,200]
           [--planners viapath,dwa,vo,nav-hl,nav-orca,nav-hrvo] [--plot FILE.png] [--json]
           [--clock wall|cpu]

Scenes: the robot at the start of a 10 m designated path (corridor ±1.5 m), obstacles placed
uniformly within 8 m, walking at 0.3-1.5 m/s in random directions, none overlapping the robot;
only scenes where viapath's straight leg at nominal speed is blocked are kept, so every viapath
cycle runs the full search (6 speeds: the paper's five plus the current one). Every planner is
timed on the same scenes (40 per obstacle count, cycled), one cycle = ``planner.plan(observation)``
after ``reset()`` (the guard, subgoal tracking and inflation included), single thread, wall clock
(``--clock cpu``: the thread's CPU time, which leaves out the waits for a core on a loaded machine).

* ``viapath`` (also read as ``viapath-fast``, its name when it had a numpy twin): the viapath planner, its steps
  compiled (``NUMBA_DISABLE_JIT=1``: the same steps as plain Python).
* ``dwa``, ``vo``: the baselines of :mod:`viapath.planning.baselines` (numpy).
* ``nav-hl``, ``nav-orca``, ``nav-hrvo``: navground's C++ behaviours (extra ``navground``) behind our
  planner protocol. Our harness around them (guard, Python ``Neighbor`` objects) costs far more than
  the behaviours themselves, so only their ``compute_cmd`` call is timed (the mean of 20 calls on
  the same state: one call is a few microseconds, at the clocks' noise), and the cost of that call
  itself (Python → C++ and back) is measured with navground's own ``Dummy`` behaviour (heads for the
  target, looks at nobody) on the same scenes and subtracted (p50 from p50, p99 from p99): what is
  left is the behaviour's own time, the figure the others are compared with (``ratio_to_hrvo`` =
  p50 / HRVO's net p50, None where that is under 2 µs, within the noise; ``ratio_p99_to_hrvo`` the
  same for p99; ``ratio_to_hrvo_call``: to HRVO's whole call, always resolved). The whole harness cycle of the
  Dummy (``harness_ms``) is printed too: it is what any navground behaviour costs behind our protocol.

For viapath the cycle's own part, ``decide(situation)`` after the harness every planner gets alike (guard,
subgoal tracking, inflation), is timed too (``decide_p50_ms``, ``decide_p99_ms``, ``ratio_decide_to_hrvo_call``):
the figure like for like with navground's ``compute_cmd``.

The machine's load average is printed with the figures: on a shared machine, run it three times.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from viapath import DesignatedPath, Observation, Obstacles, RobotState
from viapath.planning import make_planner

DEFAULT_PLANNERS = "viapath,dwa,vo,nav-hl,nav-orca,nav-hrvo"
NAVGROUND = ("nav-hl", "nav-orca", "nav-hrvo")
CLOCKS = {"wall": time.perf_counter, "cpu": time.thread_time}
CLOCK = [time.perf_counter]  # the clock every sample is taken with (--clock)
REPEATS = 20  # navground's compute_cmd per timed sample
RESOLVED_MS = 0.002  # a net navground time below this is noise


def random_scene(rng, n_obstacles, path, planner):
    while True:
        distance = rng.uniform(0.8, 8.0, n_obstacles)
        bearing = rng.uniform(-np.pi, np.pi, n_obstacles)
        positions = np.stack([distance * np.cos(bearing), distance * np.sin(bearing)], 1)
        speed = rng.uniform(0.3, 1.5, n_obstacles)
        direction = rng.uniform(-np.pi, np.pi, n_obstacles)
        velocities = np.stack([speed * np.cos(direction), speed * np.sin(direction)], 1)
        obstacles = Obstacles(positions, velocities, np.full(n_obstacles, 0.25))
        observation = Observation(0.0, RobotState(np.zeros(2), 0.0, 0.23), obstacles)
        planner.reset()
        if planner.plan(observation).plan.status != "straight" or n_obstacles == 0:
            return observation


def build(name: str, path):
    """The planner timed under ``name``."""
    if name == "viapath-numpy":
        raise SystemExit(
            "viapath-numpy: the planner has no numpy twin any more; time 'viapath' with NUMBA_DISABLE_JIT=1 for its "
            "steps as plain Python"
        )
    if name in ("viapath", "viapath-fast"):
        planner = make_planner("viapath", path, nominal_speed_mps=0.2)
        planner.decide = _TimedDecide(planner.decide)  # the instance's, ahead of the class's
        return planner
    if name == "nav-dummy":
        from viapath.planning.navground_peers import _NavgroundPeer

        class _Dummy(_NavgroundPeer):  # not registered: only the benchmark's harness measure
            behavior_type = "Dummy"

        dummy = _Dummy(path, nominal_speed_mps=0.2)
        dummy.behavior = _Timed(dummy.behavior, dummy._core.GeometricState())
        return dummy
    planner = make_planner(name, path, nominal_speed_mps=0.2)
    if name in NAVGROUND:
        planner.behavior = _Timed(planner.behavior)
    return planner


class _Timed:
    """A navground behaviour whose ``compute_cmd`` calls are timed (and, for Dummy, which has no geometric
    state of its own, with one the harness can fill all the same)."""

    def __init__(self, behavior, state=None):
        object.__setattr__(self, "_behavior", behavior)
        object.__setattr__(self, "_state", state)
        object.__setattr__(self, "last_ms", float("nan"))

    @property
    def environment_state(self):
        return self._state if self._state is not None else self._behavior.environment_state

    def compute_cmd(self, *args):
        # A few microseconds are below the clocks' noise: the call is repeated on the same state and
        # the mean taken (the behaviours keep no state between calls that changes their work).
        start = CLOCK[0]()
        for _ in range(REPEATS - 1):
            self._behavior.compute_cmd(*args)
        twist = self._behavior.compute_cmd(*args)
        object.__setattr__(self, "last_ms", (CLOCK[0]() - start) * 1e3 / REPEATS)
        return twist

    def __getattr__(self, name):
        return getattr(self._behavior, name)

    def __setattr__(self, name, value):
        setattr(self._behavior, name, value)


class _TimedDecide:
    """A planner's own part of the cycle, ``decide(situation)``, timed: what follows the harness every planner
    gets alike (the guard's inspection and command check, subgoal tracking, the inflation), as navground's
    ``compute_cmd`` follows it for the peers."""

    def __init__(self, decide):
        self.decide, self.last_ms = decide, float("nan")

    def __call__(self, situation):
        start = CLOCK[0]()
        decision = self.decide(situation)
        self.last_ms = (CLOCK[0]() - start) * 1e3
        return decision


def time_planner(planner, scenes, cycles: int, whole: bool = False) -> np.ndarray:
    """Per cycle: the whole ``plan`` call; for navground, only its ``compute_cmd`` (see the module docstring)
    unless ``whole``."""
    timed = isinstance(getattr(planner, "behavior", None), _Timed) and not whole
    for scene in scenes[:5]:  # warm-up (and numba's first call)
        planner.reset()
        planner.plan(scene)
    decide = planner.__dict__.get("decide")
    own = decide if isinstance(decide, _TimedDecide) else None
    samples, own_samples = np.empty(cycles), np.full(cycles, np.nan)
    for i in range(cycles):
        scene = scenes[i % len(scenes)]
        planner.reset()
        if own is not None:
            own.last_ms = float("nan")  # a cycle that never reaches decide (at the goal, guard stop) has no own part
        start = CLOCK[0]()
        planner.plan(scene)
        samples[i] = planner.behavior.last_ms if timed else (CLOCK[0]() - start) * 1e3
        if own is not None:
            own_samples[i] = own.last_ms
    planner.own_samples = own_samples  # decide alone (viapath), NaN for the others
    return samples


def run(planners: list[str], counts: list[int], cycles: int, seed: int) -> dict:
    path = DesignatedPath([[0.0, 0.0], [10.0, 0.0]], half_width_m=1.5)
    chooser = build("viapath", path)
    wanted = list(planners)
    if any(name in NAVGROUND for name in wanted):
        wanted.append("nav-dummy")
    built = {name: build(name, path) for name in wanted}
    rng = np.random.default_rng(seed)
    results: dict[str, dict[str, dict]] = {name: {} for name in planners}
    harness: dict[str, dict] = {}
    for n in counts:
        scenes = [random_scene(rng, n, path, chooser) for _ in range(40)]
        quantiles, decide_quantiles = {}, {}
        for name in wanted:
            samples = time_planner(built[name], scenes, cycles)
            quantiles[name] = np.percentile(samples, [50, 99])
            own_samples = built[name].own_samples
            if np.isfinite(own_samples).any():  # viapath: the cycles that reached decide
                decide_quantiles[name] = np.percentile(own_samples[np.isfinite(own_samples)], [50, 99])
        if "nav-dummy" in quantiles:
            whole = np.percentile(time_planner(built["nav-dummy"], scenes, cycles, whole=True), [50, 99])
            harness[str(n)] = {
                "p50_ms": float(whole[0]),
                "p99_ms": float(whole[1]),
                "call_p50_ms": float(quantiles["nav-dummy"][0]),
                "call_p99_ms": float(quantiles["nav-dummy"][1]),
            }
            gross = {name: quantiles[name].copy() for name in NAVGROUND if name in quantiles}
            for name in gross:
                quantiles[name] = np.maximum(quantiles[name] - quantiles["nav-dummy"], 0.0)
        hrvo = quantiles.get("nav-hrvo")
        for name in planners:
            p50, p99 = (float(q) for q in quantiles[name])
            row = {"p50_ms": p50, "p99_ms": p99}
            if hrvo is not None:
                # Below RESOLVED_MS the net time is within the noise of the subtraction: no ratio to it.
                row["ratio_to_hrvo"] = p50 / float(hrvo[0]) if hrvo[0] >= RESOLVED_MS else None
                row["ratio_p99_to_hrvo"] = p99 / float(hrvo[1]) if hrvo[1] >= RESOLVED_MS else None
                # ... and to HRVO's whole call (the Python → C++ call included): always resolved, kinder.
                own = gross[name][0] if name in NAVGROUND else p50
                row["ratio_to_hrvo_call"] = float(own) / float(gross["nav-hrvo"][0])
            if name in NAVGROUND:
                row["call_p50_ms"], row["call_p99_ms"] = (float(q) for q in gross[name])
            if name in decide_quantiles:  # the planner's own part, like for like with the peers' compute_cmd
                row["decide_p50_ms"], row["decide_p99_ms"] = (float(q) for q in decide_quantiles[name])
                if hrvo is not None:
                    row["ratio_decide_to_hrvo_call"] = row["decide_p50_ms"] / float(gross["nav-hrvo"][0])
            results[name][str(n)] = row
    clock = "wall (perf_counter)" if CLOCK[0] is time.perf_counter else "thread CPU time (thread_time)"
    return {
        "cycles": cycles,
        "seed": seed,
        "obstacles": counts,
        "clock": f"{clock}, single thread",
        "navground_net_of_harness": bool(harness),
        "harness_ms": harness,
        "results": results,
    }


def print_table(report: dict, load_before, load_after) -> None:
    print(
        f"planning time per cycle, {report['cycles']} cycles per cell, pid {os.getpid()}, {report['clock']}; "
        f"load average {load_before[0]:.2f} {load_before[1]:.2f} {load_before[2]:.2f} before, "
        f"{load_after[0]:.2f} {load_after[1]:.2f} {load_after[2]:.2f} after"
    )
    if report["harness_ms"]:
        print(
            "navground: compute_cmd only, net of the call as navground's Dummy measures it (p50/p99 ms per "
            "obstacle count: "
            + ", ".join(f"{n}: {h['call_p50_ms']:.4f}/{h['call_p99_ms']:.4f}" for n, h in report["harness_ms"].items())
            + ")"
        )
        print(
            "  the whole harness cycle around a navground behaviour (Dummy, p50/p99 ms): "
            + ", ".join(f"{n}: {h['p50_ms']:.3f}/{h['p99_ms']:.3f}" for n, h in report["harness_ms"].items())
        )
    header = (
        f"{'planner':>14} {'obstacles':>9} {'p50 ms':>9} {'p99 ms':>9} {'p50/HRVO':>9} {'p99/HRVO':>9} "
        f"{'p50/HRVO call':>13}"
    )
    print(header)
    show = lambda value, width: f"{'n/a':>{width}}" if value is None else f"{value:>{width}.1f}"
    for name, rows in report["results"].items():
        for n, row in rows.items():
            ratio = (
                (
                    f"{show(row['ratio_to_hrvo'], 9)} {show(row['ratio_p99_to_hrvo'], 9)} "
                    f"{show(row['ratio_to_hrvo_call'], 13)}"
                )
                if "ratio_to_hrvo" in row
                else ""
            )
            own = (
                (
                    f"   decide alone: {row['decide_p50_ms']:.4f} / {row['decide_p99_ms']:.4f}"
                    + (
                        f", p50 {row['ratio_decide_to_hrvo_call']:.1f}× HRVO's call"
                        if "ratio_decide_to_hrvo_call" in row
                        else ""
                    )
                )
                if "decide_p50_ms" in row
                else ""
            )
            print(f"{name:>14} {n:>9} {row['p50_ms']:>9.4f} {row['p99_ms']:>9.4f} {ratio}{own}")
    print(
        f"n/a: HRVO's net time is under {RESOLVED_MS} ms, within the noise of the subtraction; "
        "'HRVO call': the ratio to HRVO's whole compute_cmd call (the Python → C++ call included); "
        "'decide alone': viapath's own part of the cycle, after the guard, subgoal tracking and inflation "
        "that every planner gets (navground's peers included)"
    )


def plot(report: dict, file: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axis = plt.subplots(figsize=(7.5, 4.8))
    counts = report["obstacles"]
    for index, (name, rows) in enumerate(report["results"].items()):
        color = f"C{index}"
        floor = 1e-4  # a net navground time of 0 (within the noise) is drawn at the floor of the log axis
        p50 = [max(rows[str(n)]["p50_ms"], floor) for n in counts]
        p99 = [max(rows[str(n)]["p99_ms"], floor) for n in counts]
        axis.plot(counts, p50, "o-", color=color, label=f"{name} p50")
        axis.plot(counts, p99, "s--", color=color, alpha=0.6, label=f"{name} p99")
    axis.set_xscale("log")
    axis.set_yscale("log")
    axis.set_xticks(counts, [str(n) for n in counts])
    axis.set_xlabel("obstacles in the scene")
    axis.set_ylabel("planning time per cycle [ms]")
    net = " (navground: net of harness)" if report["navground_net_of_harness"] else ""
    load = report.get("load_average")
    axis.set_title(
        f"p50 (solid) and p99 (dashed) per cycle{net}\n{report['clock']}"
        + (f", load average {load[0]:.2f}" if load else ""),
        fontsize=10,
    )
    axis.grid(True, which="both", alpha=0.3)
    axis.legend(fontsize=7, ncol=2, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    figure.tight_layout()
    figure.savefig(file, dpi=120)
    plt.close(figure)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--obstacles", default="1,10,50,100,200", help="comma-separated obstacle counts")
    parser.add_argument("--planners", default=DEFAULT_PLANNERS, help="comma-separated; navground ones need the extra")
    parser.add_argument("--plot", metavar="FILE.png", help="plot p50/p99 against the number of obstacles")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON instead of a table")
    parser.add_argument(
        "--clock",
        choices=sorted(CLOCKS),
        default="wall",
        help="wall: perf_counter; cpu: the thread's CPU time (on a loaded machine it leaves out the "
        "time the process waits for a core)",
    )
    args = parser.parse_args()
    CLOCK[0] = CLOCKS[args.clock]
    planners = [name.strip() for name in args.planners.split(",") if name.strip()]
    try:
        counts = [int(value) for value in args.obstacles.split(",")]
    except ValueError:
        parser.error(f"--obstacles: expected comma-separated integers, found {args.obstacles!r}")
    load_before = os.getloadavg()
    report = run(planners, counts, args.cycles, args.seed)
    load_after = os.getloadavg()
    report["load_average"] = list(load_before)
    report["load_average_after"] = list(load_after)
    if args.plot:
        plot(report, args.plot)
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print_table(report, load_before, load_after)


if __name__ == "__main__":
    main()
