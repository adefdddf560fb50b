"""Episode plots in the style of the paper's Fig. 9, plus the corridor and a speed panel.

Markers as in the paper: '*' where the robot heads for a via point, squares where it heads for the
(sub)goal, marker size growing with speed; 'x' at the via points planned; circles for the obstacle.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from viapath.viz.scene import path_view


def _matplotlib():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def corridor_polygons(path, resolution: int = 24) -> list[np.ndarray]:
    """Outline of each segment's capsule, for drawing: the outlines the scene views draw
    (:func:`viapath.viz.scene.path_view`, closed)."""
    return path_view(path, resolution).corridor_outlines


def draw_scene(
    ax, trace, upto: int | None = None, obstacle_every_s: float = 1.0, show_via: bool = True, robot_every_s: float = 0.5
):
    """Path, corridor, walls, robot and obstacle history on ``ax`` (up to step ``upto``).

    The robot is drawn every ``robot_every_s`` (its track as a line in between): at every 0.1 s step
    the markers pile up into a band and hide the via points."""
    n = len(trace.times_s) if upto is None else upto + 1
    _draw_path(ax, trace, float(trace.times_s[n - 1]) if n else 0.0)
    _draw_obstacles(ax, trace, n, obstacle_every_s)
    _draw_robot(ax, trace, n, robot_every_s, show_via)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, lw=0.3, alpha=0.6)


def wall_open(trace, time_s: float) -> np.ndarray:
    """(W,) bool: each static edge is gone at ``time_s`` (a door that opened: ``until_s`` <= ``time_s``)."""
    until = getattr(trace, "wall_until_s", None)
    if until is None:
        return np.zeros(len(trace.walls), dtype=bool)
    return np.asarray(until, dtype=float) <= time_s


def _draw_path(ax, trace, time_s: float) -> None:
    """The corridor, the designated path with its subgoals and goal, and the walls standing at
    ``time_s``; a door that had opened by then is a thin dotted line."""
    from matplotlib.patches import Polygon

    path = trace.path
    for k, outline in enumerate(corridor_polygons(path)):
        ax.add_patch(
            Polygon(
                outline,
                closed=True,
                facecolor="#dfe9f5",
                edgecolor="none",
                zorder=0,
                label="corridor (path boundary)" if k == 0 else None,
            )
        )
    ax.plot(*path.waypoints.T, linestyle=(0, (4, 3)), color="#2f6eb5", lw=1.3, zorder=1, label="designated path")
    ax.plot(
        *path.waypoints[1:-1].T,
        "D",
        color="#2f6eb5",
        ms=5,
        zorder=2,
        label="subgoals" if len(path.waypoints) > 2 else None,
    )
    ax.plot(*path.goal, marker="*", color="#2f6eb5", ms=14, mec="k", zorder=5, ls="none", label="goal")
    gone = wall_open(trace, time_s)
    standing_labelled = opened_labelled = False
    for wall, opened in zip(trace.walls, gone):
        if opened:
            ax.plot(*wall.T, color="0.45", lw=1.0, ls=":", zorder=2, label=None if opened_labelled else "door (opened)")
            opened_labelled = True
        else:
            ax.plot(*wall.T, color="k", lw=2.5, zorder=2, label=None if standing_labelled else "wall")
            standing_labelled = True


def _draw_obstacles(ax, trace, n: int, obstacle_every_s: float) -> None:
    """Each obstacle every ``obstacle_every_s`` (darker later) and its track, up to ``n`` steps."""
    from matplotlib.patches import Circle

    every = max(1, int(round(obstacle_every_s / trace.dt_s)))
    obstacle_steps = list(range(0, n, every))
    cmap = _matplotlib().get_cmap("Reds")
    for j, radius in enumerate(trace.obstacle_radii_m):
        for i, k in enumerate(obstacle_steps):
            centre = trace.obstacle_positions[k, j]
            if not np.isfinite(centre).all():
                continue
            shade = cmap(0.3 + 0.6 * i / max(len(obstacle_steps) - 1, 1))
            ax.add_patch(Circle(centre, radius, fill=False, ec=shade, lw=1.0, zorder=3))
        track = trace.obstacle_positions[:n, j]
        ax.plot(*track.T, color="#c0392b", lw=0.6, alpha=0.5, zorder=3)
    if len(trace.obstacle_radii_m):
        ax.plot([], [], "o", mfc="none", mec="#c0392b", ms=9, label=f"obstacle (every {obstacle_every_s:.0f} s)")


def _draw_robot(ax, trace, n: int, robot_every_s: float, show_via: bool) -> None:
    """The robot's track, its markers every ``robot_every_s`` (square: heading for the goal, star: for
    a via point; size by speed), the first via point of each plan, and the robot at step ``n - 1``."""
    from matplotlib.patches import Circle

    ax.plot(*trace.robot_poses[:n, :2].T, color="0.35", lw=0.8, zorder=4)
    shown = np.arange(0, n, max(1, int(round(robot_every_s / trace.dt_s))))
    poses = trace.robot_poses[shown]
    speeds = trace.robot_speeds_mps[shown]
    sizes = 6 + 140 * speeds / max(float(trace.robot_speeds_mps.max()), 1e-6)
    heading_via = np.array([len(trace.via_points[k]) > 0 for k in shown])
    ax.scatter(
        *poses[~heading_via, :2].T,
        s=sizes[~heading_via],
        marker="s",
        facecolor="#1f9e89",
        edgecolor="k",
        lw=0.3,
        zorder=6,
        label="robot → goal (size ∝ speed)",
    )
    if heading_via.any():
        ax.scatter(
            *poses[heading_via, :2].T,
            s=2 * sizes[heading_via],
            marker="*",
            facecolor="#f39c12",
            edgecolor="k",
            lw=0.3,
            zorder=6,
            label="robot → via point",
        )
    if show_via:
        vias = [v for v in trace.via_points[:n] if len(v)]
        if vias:
            first_vias = np.array([v[0] for v in vias])
            ax.scatter(*first_vias.T, marker="x", color="#8e44ad", s=24, lw=1.0, zorder=8, label="via points planned")
    ax.add_patch(Circle(trace.robot_poses[n - 1, :2], trace.robot_radius_m, fill=False, ec="k", lw=1.2, zorder=7))


def plot_episode(episode, file: str | Path, title: str | None = None) -> Path:
    """Write the trajectory figure with a speed-over-time panel to ``file`` (PNG, PDF or SVG)."""
    plt = _matplotlib()
    trace, metrics = episode.trace, episode.metrics
    fig = plt.figure(figsize=(9.0, 6.0), constrained_layout=True)
    grid = fig.add_gridspec(2, 1, height_ratios=[3.2, 1.0])
    ax = fig.add_subplot(grid[0])
    draw_scene(ax, trace)
    _draw_perception(ax, trace)
    _fit_view(ax, trace)
    status = "reached goal" if metrics["reached_goal"] else "did not reach goal"
    collision = "COLLISION" if metrics["collision"] else "no collision"
    clearance = metrics["min_clearance_m"]
    clearance_text = f"min clearance {clearance:.2f} m" if clearance is not None else "no obstacles"
    ax.set_title(
        title
        or f"{trace.scenario_name} — {trace.planner_name} ({trace.perception_mode}): {status}, "
        f"{collision}, {clearance_text}",
        fontsize=10,
    )
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)

    speed_ax = fig.add_subplot(grid[1])
    speed_ax.plot(trace.times_s, trace.robot_speeds_mps, color="#1f9e89", lw=1.5, label="robot speed")
    nominal = trace.extras.get("nominal_speed_mps")
    if nominal is not None:
        speed_ax.axhline(nominal, color="0.5", ls="--", lw=0.8, label="nominal speed")
    speed_ax.set_xlabel("time [s]")
    speed_ax.set_ylabel("speed [m/s]")
    speed_ax.set_ylim(bottom=0)
    speed_ax.grid(True, lw=0.3, alpha=0.6)
    speed_ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    file = Path(file)
    fig.savefig(file, dpi=130)
    plt.close(fig)
    return file


def _draw_perception(ax, trace) -> None:
    """What the planner saw: the perceived obstacle centres every step, and (laser) the scan at the
    robot's closest approach to an obstacle."""
    perceived = [p for p in getattr(trace, "perceived", []) if p is not None and len(p)]
    noisy = trace.perception_mode != "oracle" or any(np.any(p.position_sigma_m > 0) for p in perceived)
    if perceived and noisy:
        centres = np.vstack([p.positions for p in perceived])
        ax.scatter(*centres.T, s=3, color="#2471a3", alpha=0.5, zorder=3, label="perceived obstacle centres")
    scans = getattr(trace, "scan_points", None)
    if scans:
        from viapath.sim.metrics import clearance_per_step

        clearance = clearance_per_step(trace)
        k = int(np.argmin(clearance)) if len(clearance) and np.isfinite(clearance).any() else len(scans) - 1
        k = min(k, len(scans) - 1)
        points = np.asarray(scans[k])
        if len(points):
            ax.scatter(
                *points.T, s=3, color="0.15", zorder=2, label=f"scan at closest approach ({trace.times_s[k]:.1f} s)"
            )
            from matplotlib.patches import Circle

            ax.add_patch(
                Circle(trace.robot_poses[k, :2], trace.robot_radius_m, fill=False, ec="0.15", ls="--", lw=0.8, zorder=7)
            )


def _fit_view(ax, trace, margin_m: float = 0.6) -> None:
    poses = trace.robot_poses[:, :2]
    corridor = np.vstack(corridor_polygons(trace.path))
    points = np.vstack([poses, corridor])
    low, high = points.min(axis=0) - margin_m, points.max(axis=0) + margin_m
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
