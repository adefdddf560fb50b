"""Per-planner tables (Markdown and JSON) and plots from the per-episode rows of a benchmark run.

Aggregates, per planner, over its episodes (rows with an error are counted apart, not aggregated):

* ``success_rate``: reached the goal without any collision; ``reached_goal_rate``;
  ``collision_rate`` (any contact); ``at_fault_collision_rate`` (contact begun while the robot moved
  towards the person, see :func:`viapath.sim.metrics.at_fault_collision`); ``at_fault_seen_1s_rate``
  (the same, counting only people present for at least 1 s before the contact);
* ``at_fault_avoidable`` / ``at_fault_unavoidable``: at-fault contacts (onsets, not episodes) that
  some command sequence from the person's appearance avoids, or that none does
  (:mod:`viapath.bench.avoidable`; a search over budget and reactive people count as avoidable);
* ``contact_speed_max_mps``: the robot's highest speed at a contact's onset (person or static), over
  all episodes; ``contact_speed_median_mps``: the median over every contact;
* ``time_ratio_median`` / ``time_ratio_mean``: time to goal over the obstacle-free time, episodes
  that reached the goal;
* ``infeasible_rate``: episodes whose goal no robot on this drive could reach without a contact
  (:mod:`viapath.bench.feasibility`), among those it applies to (people who do not react to the robot);
  ``success_feasible_rate`` / ``reach_feasible_rate``: success and reach among the feasible episodes;
  ``time_ratio_hindsight_median``: time to goal over the reachable set's earliest arrival (a lower
  bound for any robot on this drive), episodes that reached the goal;
* ``mean_lateral_deviation_m``: mean of the episodes' mean |lateral deviation|;
  ``mean_max_lateral_deviation_m`` and ``max_lateral_deviation_m``: mean and max of the episodes' max;
* ``time_outside_corridor_s``: mean per episode; ``outside_corridor_rate``: episodes with any;
* ``min_clearance_m``: smallest over all episodes; ``median_min_clearance_m``;
* ``plan_time_p50_ms``: median of the episodes' median plan time; ``plan_time_p99_ms``: 99th
  percentile of the episodes' 99th percentiles (an upper proxy of the pooled p99: the per-cycle
  samples are not kept).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from viapath.io.jsonable import dumps as json_dumps

TABLE_COLUMNS = [
    ("planner", "planner", "{}"),
    ("episodes", "episodes", "{}"),
    ("success_rate", "success", "{:.1%}"),
    ("collision_rate", "collision", "{:.1%}"),
    ("at_fault_collision_rate", "at-fault", "{:.1%}"),
    ("at_fault_seen_1s_rate", "at-fault, seen ≥ 1 s", "{:.1%}"),
    ("at_fault_avoidable", "at-fault avoidable", "{}"),
    ("at_fault_unavoidable", "at-fault unavoidable", "{}"),
    ("static_contact_rate", "static contact", "{:.1%}"),
    ("blocked_rate", "blocked", "{:.1%}"),
    ("blocked_s_per_episode", "blocked [s/ep]", "{:.1f}"),
    ("contact_speed_max_mps", "contact speed max [m/s]", "{:.2f}"),
    ("time_ratio_median", "time ratio (median)", "{:.2f}"),
    ("infeasible_rate", "infeasible", "{:.1%}"),
    ("success_feasible_rate", "success (feasible)", "{:.1%}"),
    ("reach_feasible_rate", "reach (feasible)", "{:.1%}"),
    ("time_ratio_hindsight_median", "time ratio hindsight (median)", "{:.2f}"),
    ("mean_lateral_deviation_m", "mean lat. dev. [m]", "{:.3f}"),
    ("max_lateral_deviation_m", "max lat. dev. [m]", "{:.2f}"),
    ("time_outside_corridor_s", "outside corridor [s/ep]", "{:.2f}"),
    ("min_clearance_m", "min clearance [m]", "{:.2f}"),
    ("plan_time_p50_ms", "plan p50 [ms]", "{:.2f}"),
    ("plan_time_p99_ms", "plan p99 [ms]", "{:.1f}"),
    ("shield_interventions_per_episode", "shield interventions/ep", "{:.1f}"),
    ("errors", "crashed", "{}"),
]


def label(row: dict[str, Any]) -> str:
    """The planner's name, marked when the shield was on (rows of both settings can share a table)."""
    setting = row.get("shield") or "off"
    return row["planner"] if setting == "off" else f"{row['planner']} +{'shield' if setting == 'on' else setting}"


def _values(rows, column) -> np.ndarray:
    return np.array([r[column] for r in rows if r.get(column) is not None], dtype=float)


def _stat(function, values):
    return float(function(values)) if len(values) else None


def _share(rows, column) -> float | None:
    """The share of true values among the rows where ``column`` is filled (None where none is)."""
    values = [bool(r[column]) for r in rows if r.get(column) is not None]
    return sum(values) / len(values) if values else None


def _count(rows, column) -> int | None:
    values = [r.get(column) for r in rows if r.get(column) is not None]
    return int(sum(values)) if values else None


def _contact_speeds(rows) -> np.ndarray:
    """Every contact's onset speed of the rows (the ``contact_speeds`` column: ``time:who:speed`` items)."""
    return np.array(
        [float(item.rsplit(":", 1)[1]) for r in rows for item in (r.get("contact_speeds") or "").split()],
        dtype=float,
    )


def at_fault_lines(rows: list[dict[str, Any]]) -> list[str]:
    """One Markdown line per episode with an at-fault contact: the avoidable / unavoidable verdicts."""
    return [
        f"* {label(r)} {r['scenario']}: {r.get('at_fault_avoidable') or 0} avoidable, "
        f"{r.get('at_fault_unavoidable') or 0} unavoidable; {r.get('at_fault_detail') or '(not searched)'}"
        for r in rows
        if not r.get("error") and r.get("at_fault_collision")
    ]


def summarize(rows: list[dict[str, Any]], by: str = "planner", order: list[str] | None = None) -> list[dict[str, Any]]:
    """One dict of aggregates per value of ``by`` (planner by default), in ``order`` then first-seen order."""
    keyed = label if by == "planner" else (lambda row: row[by])
    groups: dict[str, list[dict]] = {
        f"{key}{mark}": [] for key in order or [] for mark in ("", " +shield", " +friendly")
    }
    for row in rows:
        groups.setdefault(keyed(row), []).append(row)
    summary = []
    for key, group in groups.items():
        if not group:
            continue
        ok = [r for r in group if not r.get("error")]
        n = len(ok)
        rate = (lambda flag, ok=ok, n=n: sum(bool(r[flag]) for r in ok) / n) if n else (lambda flag: None)
        success = sum(bool(r["reached_goal"]) and not r["collision"] for r in ok) / n if n else None
        ratios = _values(ok, "time_ratio")
        outside = _values(ok, "time_outside_corridor_s")
        summary.append(
            {
                by: key,
                "episodes": n,
                "errors": len(group) - n,
                "success_rate": success,
                "reached_goal_rate": rate("reached_goal"),
                "collision_rate": rate("collision"),
                "at_fault_collision_rate": rate("at_fault_collision"),
                "at_fault_seen_1s_rate": rate("at_fault_collision_seen_1s"),
                "at_fault_avoidable": _count(ok, "at_fault_avoidable"),
                "at_fault_unavoidable": _count(ok, "at_fault_unavoidable"),
                "contact_speed_max_mps": _stat(np.max, _contact_speeds(ok)),
                "contact_speed_median_mps": _stat(np.median, _contact_speeds(ok)),
                "static_contact_rate": (sum(bool(r.get("static_contact")) for r in ok) / n) if n else None,
                "blocked_rate": (sum(bool(r.get("blocked_s")) for r in ok) / n) if n else None,
                "blocked_s_per_episode": _stat(np.mean, _values(ok, "blocked_s")),
                "time_ratio_median": _stat(np.median, ratios),
                "time_ratio_mean": _stat(np.mean, ratios),
                "feasibility_judged": sum(r.get("feasible") is not None for r in ok),
                "infeasible_rate": (lambda share: None if share is None else 1.0 - share)(_share(ok, "feasible")),
                "success_feasible_rate": _share(ok, "success_feasible"),
                "reach_feasible_rate": _share(ok, "reach_feasible"),
                "time_ratio_hindsight_median": _stat(np.median, _values(ok, "time_ratio_hindsight")),
                "mean_lateral_deviation_m": _stat(np.mean, _values(ok, "mean_lateral_deviation_m")),
                "mean_max_lateral_deviation_m": _stat(np.mean, _values(ok, "max_lateral_deviation_m")),
                "max_lateral_deviation_m": _stat(np.max, _values(ok, "max_lateral_deviation_m")),
                "time_outside_corridor_s": _stat(np.mean, outside),
                "outside_corridor_rate": float(np.mean(outside > 0)) if len(outside) else None,
                "min_clearance_m": _stat(np.min, _values(ok, "min_clearance_m")),
                "median_min_clearance_m": _stat(np.median, _values(ok, "min_clearance_m")),
                "plan_time_p50_ms": _stat(np.median, _values(ok, "plan_time_p50_ms")),
                "plan_time_p99_ms": _stat(lambda v: np.percentile(v, 99), _values(ok, "plan_time_p99_ms")),
                "shield": group[0].get("shield") or "off",
                "shield_interventions_per_episode": _stat(np.mean, _values(ok, "shield_interventions")),
            }
        )
    return summary


def markdown_table(summary: list[dict[str, Any]], columns=TABLE_COLUMNS, key: str = "planner") -> str:
    columns = [(key, key, "{}")] + [c for c in columns if c[0] != "planner"] if key != "planner" else columns
    header = "| " + " | ".join(title for _, title, _ in columns) + " |"
    rule = "|" + "|".join("---" for _ in columns) + "|"
    lines = [header, rule]
    for entry in summary:
        cells = []
        for name, _, fmt in columns:
            value = entry.get(name)
            cells.append("–" if value is None else fmt.format(value))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def family_table(rows: list[dict[str, Any]]) -> str:
    """Success / collision / at-fault per family (rows) and planner (columns), as Markdown."""
    planners = list(dict.fromkeys(label(r) for r in rows))
    families = sorted({r["family"] for r in rows})
    lines = ["| family | " + " | ".join(planners) + " |", "|---|" + "|".join("---" for _ in planners) + "|"]
    for family in families:
        cells = []
        for planner in planners:
            group = [r for r in rows if r["family"] == family and label(r) == planner and not r.get("error")]
            if not group:
                cells.append("–")
                continue
            n = len(group)
            success = sum(bool(r["reached_goal"]) and not r["collision"] for r in group) / n
            collision = sum(bool(r["collision"]) for r in group) / n
            fault = sum(bool(r["at_fault_collision"]) for r in group) / n
            cells.append(f"{success:.0%} / {collision:.0%} / {fault:.0%}")
        scenarios = len({r["scenario"] for r in rows if r["family"] == family})
        lines.append(f"| {family} (n={scenarios}) | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def write_report(
    rows: list[dict[str, Any]], out_dir: Path, plots: bool = True, order: list[str] | None = None
) -> list[dict[str, Any]]:
    """Write ``summary.json``, ``summary.md`` and (optionally) the plots; returns the summary."""
    out_dir = Path(out_dir)
    summary = summarize(rows, order=order)
    if order:
        rows = sorted(rows, key=lambda r: order.index(r["planner"]) if r["planner"] in order else len(order))
    (out_dir / "summary.json").write_text(json_dumps(summary, indent=2))
    text = [
        "# Benchmark summary",
        "",
        markdown_table(summary),
        "",
        "Per family: success / collision / at-fault collision rate.",
        "",
        family_table(rows),
        "",
    ]
    faults = at_fault_lines(rows)
    if faults:
        text += [
            "## At-fault contacts",
            "",
            "Each searched from the person's first appearance with the recorded future "
            "(viapath.bench.avoidable): unavoidable when no command sequence of the drive avoids an "
            "at-fault onset; a search over budget and reactive people count as avoidable.",
            "",
            *faults,
            "",
        ]
    from viapath.bench.identity import crash_lines

    crashed = crash_lines(rows)
    if crashed:
        count = sum(1 for r in rows if r.get("error"))
        text += [
            f"## {count} episode(s) crashed",
            "",
            "Not in the rates above; rerunning the same command runs them again.",
            "",
            *crashed,
            "",
        ]
    (out_dir / "summary.md").write_text("\n".join(text))
    if plots and rows:
        plot_rates(summary, out_dir / "rates.png")
        plot_deviation_vs_time(rows, out_dir / "deviation_vs_time.png")
    return summary


def plot_rates(summary: list[dict[str, Any]], file: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [s["planner"] for s in summary]
    metrics = [
        ("success_rate", "success", "tab:green"),
        ("collision_rate", "collision", "tab:orange"),
        ("at_fault_collision_rate", "at-fault collision", "tab:red"),
    ]
    x = np.arange(len(names))
    width = 0.8 / len(metrics)
    fig, ax = plt.subplots(figsize=(max(6, 0.9 * len(names) + 2), 4))
    for i, (key, label, color) in enumerate(metrics):
        values = [s[key] or 0.0 for s in summary]
        ax.bar(x + (i - 1) * width, values, width, label=label, color=color)
    ax.set_xticks(x, names, rotation=30, ha="right")
    ax.set_ylim(0, 1)
    ax.set_ylabel("fraction of episodes")
    ax.set_title(f"Rates per planner ({summary[0]['episodes']} episodes each)" if summary else "Rates per planner")
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(file, dpi=120)
    plt.close(fig)


def plot_deviation_vs_time(rows: list[dict[str, Any]], file: Path) -> None:
    """One panel per planner (shared axes): each episode that reached the goal as a point; the other
    planners' episodes in light grey behind, for comparison."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    planners = list(dict.fromkeys(label(r) for r in rows))
    done = [r for r in rows if r.get("time_ratio") is not None and r.get("max_lateral_deviation_m") is not None]
    columns = min(3, len(planners))
    lines = int(np.ceil(len(planners) / columns))
    fig, axes = plt.subplots(
        lines, columns, figsize=(3.6 * columns, 2.8 * lines), sharex=True, sharey=True, squeeze=False
    )
    all_ratio = np.array([r["time_ratio"] for r in done])
    all_deviation = np.array([r["max_lateral_deviation_m"] for r in done])
    for ax, planner in zip(axes.flat, planners):
        mine = [r for r in done if label(r) == planner]
        ax.scatter(all_ratio, all_deviation, s=4, color="0.85", zorder=1, label="every planner's episodes")
        if mine:
            ratio = np.array([r["time_ratio"] for r in mine])
            deviation = np.array([r["max_lateral_deviation_m"] for r in mine])
            ax.scatter(ratio, deviation, s=8, alpha=0.6, color="tab:blue", zorder=2, label="this planner's episodes")
            ax.scatter(
                [np.median(ratio)], [np.median(deviation)], s=60, marker="x", color="tab:red", zorder=3, label="median"
            )
        ax.set_title(f"{planner} ({len(mine)} reached)", fontsize=9)
        ax.grid(alpha=0.3)
    if len(done):
        axes.flat[0].legend(fontsize=7, loc="upper right", markerscale=1.5, framealpha=0.8)
    for ax in axes.flat[len(planners) :]:
        ax.set_visible(False)
    beyond = ""
    if len(all_ratio):
        # The axes end at the 99.5th percentiles so that a few outliers do not squash the rest.
        ratio_top = min(np.percentile(all_ratio, 99.5) + 0.1, 4.0)
        deviation_top = min(np.percentile(all_deviation, 99.5) + 0.1, 5.0)
        axes[0, 0].set_xlim(max(0.0, all_ratio.min() - 0.05), ratio_top)
        axes[0, 0].set_ylim(-0.05, deviation_top)
        clipped = int(np.sum((all_ratio > ratio_top) | (all_deviation > deviation_top)))
        beyond = f"; {clipped} of {len(all_ratio)} beyond the axes" if clipped else ""
    fig.supxlabel(f"time to goal / obstacle-free time (episodes that reached the goal; x = median{beyond})", fontsize=9)
    fig.supylabel("max lateral deviation [m]", fontsize=9)
    fig.tight_layout()
    fig.savefig(file, dpi=110)
    plt.close(fig)
