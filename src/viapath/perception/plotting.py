"""Plots of the laser chain: a recording's tracks and walking speeds, and a simulator overlay.

matplotlib is imported here only, lazily, inside the functions (the perception core never imports it).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def plot_recording(
    result, path, title: str = "", min_travel_m: float = 1.0, point_scans: int = 40, dpi: int = 110
) -> Path:
    """Three panels: tracks in the sensor frame over the scan points, speed over time, speed histogram."""
    plt = _pyplot()
    path = Path(path)
    summary = result.track_summary(min_travel_m)
    walking = [s["track_id"] for s in summary if s["walking"]]
    fig, axes = plt.subplots(1, 3, figsize=(16, 5.2), gridspec_kw=dict(width_ratios=[1.2, 1.3, 0.8]))
    ax = axes[0]
    if result.points:
        pick = np.linspace(0, len(result.points) - 1, min(point_scans, len(result.points))).astype(int)
        pts = np.concatenate([result.points[i] for i in pick]) if len(pick) else np.zeros((0, 2))
        ax.scatter(pts[:, 0], pts[:, 1], s=0.5, color="0.7", label=f"scan points ({len(pick)} scans)")
    colors = plt.get_cmap("tab20")
    for s in summary:
        rows = result.track(s["track_id"])
        if s["walking"]:
            ax.plot(rows[:, 3], rows[:, 4], lw=1.2, color=colors(s["track_id"] % 20))
        else:
            ax.plot(rows[:, 3], rows[:, 4], lw=0.8, color="k", alpha=0.5)
    ax.plot([], [], color="k", alpha=0.5, label="static tracks (clutter)")
    ax.plot([], [], color="tab:blue", label=f"walking tracks (moved ≥ {min_travel_m:g} m, median ≥ 0.2 m/s)")
    ax.plot(0, 0, marker="^", color="r", ms=8, ls="none", label="scanner")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (sensor frame)")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title("tracks")

    ax = axes[1]
    for tid in walking:
        rows = result.track(tid)
        ax.plot(rows[:, 1], np.hypot(rows[:, 5], rows[:, 6]), lw=1, color=colors(tid % 20))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("filtered speed [m/s]")
    ax.set_title(f"speed of the {len(walking)} walking tracks")
    ax.grid(alpha=0.3)

    ax = axes[2]
    speeds = result.walking_speeds(min_travel_m)
    if len(speeds):
        ax.hist(speeds, bins=np.arange(0, max(2.0, speeds.max()) + 0.05, 0.05), color="tab:blue", alpha=0.8)
        q25, q50, q75 = np.percentile(speeds, [25, 50, 75])
        ax.axvline(q50, color="k", lw=1)
        ax.set_title(
            f"walking speed: median {q50:.2f} m/s\n(p25 {q25:.2f}, p75 {q75:.2f}; {len(speeds)} samples)", fontsize=9
        )
    ax.set_xlabel("speed [m/s]")
    ax.set_ylabel("track-scans")
    fig.suptitle(title or "laser tracks")
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
