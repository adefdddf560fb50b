"""Animation of an episode: robot, obstacles, corridor, current via point and plan (GIF or MP4)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from viapath.viz.plot import _fit_view, _matplotlib, corridor_polygons


def animate_episode(episode, file: str | Path, fps: int = 10, max_frames: int = 400, progress=None) -> Path:
    """Write the animation; ``progress(frame, total)`` is called as each frame is written."""
    plt = _matplotlib()
    from matplotlib import animation
    from matplotlib.patches import Circle, Polygon

    trace = episode.trace
    file = Path(file)
    n = len(trace.times_s)
    stride = max(1, int(np.ceil(n / max_frames)))
    frames = list(range(0, n, stride))
    fig, ax = plt.subplots(figsize=(8, 5), constrained_layout=True)
    for outline in corridor_polygons(trace.path):
        ax.add_patch(Polygon(outline, closed=True, facecolor="#dfe9f5", edgecolor="none", zorder=0))
    ax.plot(*trace.path.waypoints.T, ls=(0, (4, 3)), color="#2f6eb5", lw=1.2)
    ax.plot(*trace.path.goal, marker="*", color="#2f6eb5", ms=14, mec="k")
    for wall in trace.walls:
        ax.plot(*wall.T, color="k", lw=2.5)
    _fit_view(ax, trace)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    robot = Circle((0, 0), trace.robot_radius_m, fc="#1f9e89", ec="k", zorder=5)
    ax.add_patch(robot)
    heading, = ax.plot([], [], color="k", lw=1.5, zorder=6)
    trail, = ax.plot([], [], color="0.4", lw=0.8)
    plan_line, = ax.plot([], [], color="#8e44ad", lw=1.0, ls="--", zorder=4)
    via_marker, = ax.plot([], [], "x", color="#8e44ad", ms=9, mew=2, zorder=6)
    scan, = ax.plot([], [], ".", color="0.2", ms=2, zorder=2)
    obstacles = [Circle((np.nan, np.nan), r, fc="#e6a19a", ec="#c0392b", zorder=4) for r in trace.obstacle_radii_m]
    for patch in obstacles:
        ax.add_patch(patch)
    label = ax.text(0.01, 0.99, "", transform=ax.transAxes, va="top", fontsize=9, family="monospace")

    def update(k):
        x, y, h = trace.robot_poses[k]
        robot.center = (x, y)
        heading.set_data([x, x + trace.robot_radius_m * np.cos(h)], [y, y + trace.robot_radius_m * np.sin(h)])
        trail.set_data(*trace.robot_poses[: k + 1, :2].T)
        via = trace.via_points[k]
        target = trace.plan_targets[k]
        plan_line.set_data([x, target[0]], [y, target[1]])
        via_marker.set_data(via[:, 0], via[:, 1]) if len(via) else via_marker.set_data([], [])
        for j, patch in enumerate(obstacles):
            patch.center = tuple(trace.obstacle_positions[k, j])
        if trace.scan_points and k < len(trace.scan_points) and len(trace.scan_points[k]):
            scan.set_data(*np.asarray(trace.scan_points[k]).T)
        status = trace.plan_status[k]
        label.set_text(f"t = {trace.times_s[k]:5.1f} s  v = {trace.robot_speeds_mps[k]:.2f} m/s  {status}")
        return [robot, heading, trail, plan_line, via_marker, scan, label, *obstacles]

    movie = animation.FuncAnimation(fig, update, frames=frames, blit=False)
    if file.suffix.lower() == ".gif":
        movie.save(file, writer=animation.PillowWriter(fps=fps), progress_callback=progress)
    elif file.suffix.lower() == ".mp4":
        if not animation.writers.is_available("ffmpeg"):
            plt.close(fig)
            raise RuntimeError("writing .mp4 needs ffmpeg on the PATH (e.g. apt-get install ffmpeg); use .gif otherwise")
        movie.save(file, writer=animation.FFMpegWriter(fps=fps), progress_callback=progress)
    else:
        plt.close(fig)
        raise ValueError(f"{file}: animation must end in .gif or .mp4")
    plt.close(fig)
    return file
