"""One-at-a-time sweeps of the weights k1..k4 of Eq. 1 around the paper's values (issue 15, docs/howto/tune-weights.md).

Usage: python benchmarks/sweep_weights.py [--factors 0.1,0.3,1,3,10,30] [--suite-count 9] [--suite-seed 303]
       [--suite-factors 0.1,10] [--workers 1] [--img docs/img] [--json] [--no-suite]

Part 1, the paper's three experiments (built-in paper-behind, paper-front, paper-side; oracle
perception, no noise, shield on as shipped): each k is multiplied by each factor while the other three
keep the paper's values; every episode is classified from its trace:
* behind: "speed up" (top speed >= 0.29 m/s and |lateral deviation| < 0.05 m, the paper's Fig. 8a),
  "step aside" (|deviation| >= 0.05 m), else "trail";
* front: "pass left" (deviation > 0.2 m, never right of the path), "pass right", else "other";
* side: at the moment the person crosses the path line, "slow down" (the robot is still short of the
  person's line x and slowed to <= 0.11 m/s before), "pass in front" (the robot is past the line),
  "swerve" (|deviation| >= 0.05 m), else "other".
Part 2, a generated suite (``mixed``, ``--suite-count`` scenarios, one per family for 9): each k times
each ``--suite-factors`` value through the benchmark runner; mean lateral deviation, median time
ratio, goal misses and contacts (the objectives and constraints of ``viapath tune``).
Plots: weights_paper_sweep.png and weights_suite_sweep.png in ``--img``. Prints a table, or JSON.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from viapath.bench.tune import PAPER_WEIGHTS, evaluate
from viapath.scenarios import load_scenario
from viapath.sim.loop import run_episode

CASES = ("paper-behind", "paper-front", "paper-side")


def classify(name: str, episode) -> dict:
    trace = episode.trace
    deviation = trace.path.lateral_deviation(trace.robot_poses[:, :2])
    speeds = trace.robot_speeds_mps
    out = {
        "reached_goal": bool(episode.metrics["reached_goal"]),
        "collision": bool(episode.metrics["collision"]),
        "time_to_goal_s": episode.metrics["time_to_goal_s"],
        "max_speed_mps": float(speeds.max()),
        "max_abs_deviation_m": float(np.abs(deviation).max()),
        "max_deviation_m": float(deviation.max()),
        "min_deviation_m": float(deviation.min()),
    }
    if name == "paper-behind":
        if out["max_abs_deviation_m"] >= 0.05:
            label = "step aside"
        elif out["max_speed_mps"] >= 0.29:
            label = "speed up"
        else:
            label = "trail"
    elif name == "paper-front":
        if deviation.max() > 0.2 and deviation.min() > -0.05:
            label = "pass left"
        elif deviation.min() < -0.2 and deviation.max() < 0.05:
            label = "pass right"
        else:
            label = "other"
    else:
        obstacle_y = trace.obstacle_positions[:, 0, 1]
        crossing = int(np.argmax(obstacle_y >= 0)) if (obstacle_y >= 0).any() else len(obstacle_y) - 1
        lead = float(trace.robot_poses[crossing, 0] - trace.obstacle_positions[crossing, 0, 0])
        out["lead_at_crossing_m"] = lead  # > 0: the robot is past the person's line when it crosses the path
        out["min_speed_before_crossing_mps"] = float(speeds[: max(crossing, 1)].min())
        if lead > 0:
            label = "pass in front"
        elif out["max_abs_deviation_m"] >= 0.05:
            label = "swerve"
        elif out["min_speed_before_crossing_mps"] <= 0.11:
            label = "slow down"
        else:
            label = "other"
    out["behaviour"] = label
    if not out["reached_goal"] or out["collision"]:
        out["behaviour"] = label + (" (contact)" if out["collision"] else " (missed goal)")
    return out


def sweep_paper(factors: list[float]) -> list[dict]:
    rows, seen = [], {}
    scenarios = {name: load_scenario(name) for name in CASES}
    for weight in ("k1", "k2", "k3", "k4"):
        for factor in factors:
            values = {**PAPER_WEIGHTS, weight: PAPER_WEIGHTS[weight] * factor}
            for name in CASES:
                key = (name, tuple(sorted(values.items())))
                if key not in seen:  # the paper's point (factor 1) is run once, not once per weight
                    episode = run_episode(
                        scenarios[name],
                        perception="oracle",
                        seed=0,
                        position_noise_m=0.0,
                        velocity_noise_mps=0.0,
                        planner_overrides=values,
                    )
                    seen[key] = classify(name, episode)
                rows.append({"weight": weight, "factor": factor, "value": values[weight], "case": name, **seen[key]})
    return rows


def sweep_suite(count: int, seed: int, factors: list[float], workers: int) -> list[dict]:
    from viapath.bench.runner import load_suite

    scenarios = load_suite("mixed", None, count=count, seed=seed)
    rows = [{"weight": "paper", "factor": 1.0, **evaluate(scenarios, PAPER_WEIGHTS, workers, seed)}]
    for weight in ("k1", "k2", "k3", "k4"):
        for factor in (f for f in factors if f != 1.0):
            values = {**PAPER_WEIGHTS, weight: PAPER_WEIGHTS[weight] * factor}
            rows.append(
                {
                    "weight": weight,
                    "factor": factor,
                    "value": values[weight],
                    **evaluate(scenarios, values, workers, seed),
                }
            )
    return rows


def plot_paper(rows: list[dict], factors: list[float], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {
        "speed up": "tab:green",
        "step aside": "tab:orange",
        "trail": "tab:gray",
        "pass left": "tab:green",
        "pass right": "tab:orange",
        "slow down": "tab:green",
        "pass in front": "tab:red",
        "swerve": "tab:orange",
        "other": "tab:gray",
    }
    fig, axes = plt.subplots(3, 4, figsize=(15, 9.5), sharex=True)
    quantities = {
        "paper-behind": [("max_speed_mps", "top speed [m/s]"), ("max_abs_deviation_m", "max |deviation| [m]")],
        "paper-front": [("max_deviation_m", "max deviation, left + [m]"), ("time_to_goal_s", "time to goal / 100 [s]")],
        "paper-side": [
            ("min_speed_before_crossing_mps", "min speed before the crossing [m/s]"),
            ("lead_at_crossing_m", "robot ahead of the person's line at the crossing [m]"),
        ],
    }
    for row_index, case in enumerate(CASES):
        for column, weight in enumerate(("k1", "k2", "k3", "k4")):
            ax = axes[row_index][column]
            items = sorted((r for r in rows if r["case"] == case and r["weight"] == weight), key=lambda r: r["factor"])
            x = [r["factor"] for r in items]
            for (key, label), style in zip(quantities[case], ("-o", "--s")):
                scale = 0.01 if key == "time_to_goal_s" else 1.0
                y = [np.nan if r.get(key) is None else r[key] * scale for r in items]
                ax.plot(x, y, style, ms=4, label=label)
            for r in items:
                base = r["behaviour"].split(" (")[0]
                ax.axvspan(
                    r["factor"] / 1.25, r["factor"] * 1.25, color=colours.get(base, "tab:gray"), alpha=0.18, lw=0
                )
                if "(" in r["behaviour"]:
                    ax.plot([r["factor"]], [0], "kx", ms=8)
            ax.axvline(1.0, color="k", lw=0.8, ls=":")
            ax.set_xscale("log")
            ax.grid(alpha=0.3)
            if row_index == 0:
                ax.set_title(f"{weight} × factor (paper {weight} = {PAPER_WEIGHTS[weight]:g})")
            if column == 0:
                ax.set_ylabel(case)
            if row_index == 2:
                ax.set_xlabel("factor on the paper's value")
            if column == 3:
                ax.legend(fontsize=7, loc="best")
    handles = [
        plt.Rectangle((0, 0), 1, 1, color=c, alpha=0.3) for c in ("tab:green", "tab:orange", "tab:red", "tab:gray")
    ]
    fig.legend(
        handles,
        [
            "paper's behaviour (speed up / pass left / slow down)",
            "step aside / pass right / swerve",
            "pass in front",
            "trail / other",
        ],
        loc="lower center",
        ncol=4,
        fontsize=9,
    )
    fig.suptitle(
        "One-at-a-time sweeps on the paper's three experiments (shading: behaviour; x: contact or missed goal)"
    )
    fig.tight_layout(rect=(0, 0.04, 1, 0.97))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_suite(rows: list[dict], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paper = next(r for r in rows if r["weight"] == "paper")
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.3))
    for weight, marker in zip(("k1", "k2", "k3", "k4"), "osD^"):
        items = sorted(
            [r for r in rows if r["weight"] == weight] + [{**paper, "factor": 1.0}], key=lambda r: r["factor"]
        )
        x = [r["factor"] for r in items]
        for ax, key in zip(axes, ("mean_lateral_deviation_m", "median_time_ratio")):
            ax.plot(x, [r[key] for r in items], "-" + marker, label=weight)
            for r in items:
                if r["misses"] or r["at_fault"]:
                    ax.annotate(
                        f"{r['misses']}m/{r['at_fault']}f",
                        (r["factor"], r[key]),
                        fontsize=7,
                        textcoords="offset points",
                        xytext=(3, 3),
                    )
    for ax, label in zip(axes, ("mean lateral deviation [m]", "median time ratio")):
        ax.set_xscale("log")
        ax.set_xlabel("factor on the paper's value (others at the paper's)")
        ax.set_ylabel(label)
        ax.axvline(1.0, color="k", lw=0.8, ls=":")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title + " (labels: goal misses m / at-fault contacts f)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--factors", default="0.1,0.3,1,3,10,30")
    parser.add_argument("--suite-factors", default="0.1,10")
    parser.add_argument("--suite-count", type=int, default=9)
    parser.add_argument("--suite-seed", type=int, default=303)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--img", type=Path, default=Path("docs/img"))
    parser.add_argument("--no-suite", action="store_true")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    factors = [float(f) for f in args.factors.split(",")]
    started = time.perf_counter()
    paper_rows = sweep_paper(factors)
    paper_wall = time.perf_counter() - started
    args.img.mkdir(parents=True, exist_ok=True)
    plot_paper(paper_rows, factors, args.img / "weights_paper_sweep.png")
    suite_rows, suite_wall = [], 0.0
    if not args.no_suite:
        started = time.perf_counter()
        suite_rows = sweep_suite(
            args.suite_count, args.suite_seed, [float(f) for f in args.suite_factors.split(",")], args.workers
        )
        suite_wall = time.perf_counter() - started
        plot_suite(
            suite_rows,
            args.img / "weights_suite_sweep.png",
            f"mixed suite, {args.suite_count} scenarios, seed {args.suite_seed}",
        )
    if args.json:
        print(
            json.dumps(
                {
                    "paper": paper_rows,
                    "suite": suite_rows,
                    "paper_wall_s": round(paper_wall, 1),
                    "suite_wall_s": round(suite_wall, 1),
                },
                indent=1,
                default=float,
            )
        )
        return
    print(f"paper's three experiments ({paper_wall:.0f} s):")
    print(f"{'weight':6} {'factor':>7} {'value':>9}  " + "  ".join(f"{c:>26}" for c in CASES))
    for weight in ("k1", "k2", "k3", "k4"):
        for factor in factors:
            items = {r["case"]: r for r in paper_rows if r["weight"] == weight and r["factor"] == factor}
            value = PAPER_WEIGHTS[weight] * factor
            print(f"{weight:6} {factor:7g} {value:9.4g}  " + "  ".join(f"{items[c]['behaviour']:>26}" for c in CASES))
    if suite_rows:
        print(f"\nmixed suite ({suite_wall:.0f} s):")
        print(
            f"{'weight':6} {'factor':>7} {'dev [m]':>8} {'time ratio':>10} {'misses':>6} {'contacts':>8} {'at-fault':>8}"
        )
        for r in suite_rows:
            print(
                f"{r['weight']:6} {r['factor']:7g} {r['mean_lateral_deviation_m']:8.4f} {r['median_time_ratio']:10.4f} "
                f"{r['misses']:6d} {r['contacts']:8d} {r['at_fault']:8d}"
            )


if __name__ == "__main__":
    main()
