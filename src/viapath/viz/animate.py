"""Animation of an episode: robot, obstacles, corridor, current via point and plan (GIF or MP4).

What does not move (corridor, path, goal, walls, axes, layout) is drawn once; each frame restores that
picture and draws only the moving artists on it (blitting, on matplotlib's Agg canvas), then hands the
pixels to Pillow (GIF, no ffmpeg needed) or to ffmpeg through a pipe (MP4). Redrawing the whole
figure for every frame, with the layout recomputed each time, took minutes for a 24 s run.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np

from viapath.viz.plot import _fit_view, _matplotlib, corridor_polygons

MAX_FRAMES = 400


def frame_indices(steps: int, max_frames: int = MAX_FRAMES, stride: int | None = None) -> list[int]:
    """The trace steps shown: every ``stride``-th (default: as few as keep at most ``max_frames``),
    and the last step always, so the animation ends where the episode ends."""
    if steps <= 0:
        return []
    stride = max(1, int(stride)) if stride else max(1, int(np.ceil(steps / max_frames)))
    frames = list(range(0, steps, stride))
    if frames[-1] != steps - 1:
        frames.append(steps - 1)
    return frames


def animate_episode(
    episode,
    file: str | Path,
    fps: int = 10,
    max_frames: int = MAX_FRAMES,
    progress=None,
    stride: int | None = None,
    dpi: int = 100,
) -> Path:
    """Write the animation; ``progress(frame, total)`` is called as each frame is written."""
    file = Path(file)
    suffix = file.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"{file}: animation must end in .gif or .mp4")
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise RuntimeError("writing .mp4 needs ffmpeg on the PATH (e.g. apt-get install ffmpeg); use .gif otherwise")
    plt = _matplotlib()
    fig, draw = _scene(plt, episode.trace, dpi)
    try:
        frames = frame_indices(len(episode.trace.times_s), max_frames, stride)
        images = (draw(k) for k in frames)
        if suffix == ".gif":
            _write_gif(images, file, fps, len(frames), progress)
        else:
            _write_mp4(images, file, fps, len(frames), progress, fig)
    finally:
        plt.close(fig)
    return file


def _scene(plt, trace, dpi: int):
    """The figure with its still parts drawn once, and ``draw(k)``: the RGBA pixels of step k."""
    from matplotlib.patches import Circle, Polygon

    fig, ax = plt.subplots(figsize=(8, 5), dpi=dpi, constrained_layout=True)
    for outline in corridor_polygons(trace.path):
        ax.add_patch(Polygon(outline, closed=True, facecolor="#dfe9f5", edgecolor="none", zorder=0))
    ax.plot(*trace.path.waypoints.T, ls=(0, (4, 3)), color="#2f6eb5", lw=1.2)
    ax.plot(*trace.path.goal, marker="*", color="#2f6eb5", ms=14, mec="k")
    doors = []  # edges that go during the run: drawn in the frames where they still stand
    for wall, until_s in zip(trace.walls, _until(trace)):
        (line,) = ax.plot(*wall.T, color="k", lw=2.5)
        if np.isfinite(until_s):
            doors.append((line, until_s))
    _fit_view(ax, trace)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    (trail,) = ax.plot([], [], color="0.4", lw=0.8)
    (scan,) = ax.plot([], [], ".", color="0.2", ms=2, zorder=2)
    (plan_line,) = ax.plot([], [], color="#8e44ad", lw=1.0, ls="--", zorder=4)
    obstacles = [Circle((np.nan, np.nan), r, fc="#e6a19a", ec="#c0392b", zorder=4) for r in trace.obstacle_radii_m]
    for patch in obstacles:
        ax.add_patch(patch)
    robot = Circle((0, 0), trace.robot_radius_m, fc="#1f9e89", ec="k", zorder=5)
    ax.add_patch(robot)
    (heading,) = ax.plot([], [], color="k", lw=1.5, zorder=6)
    (via_marker,) = ax.plot([], [], "x", color="#8e44ad", ms=9, mew=2, zorder=6)
    label = ax.text(0.01, 0.99, "", transform=ax.transAxes, va="top", fontsize=9, family="monospace")
    moving = [*(line for line, _ in doors), trail, scan, plan_line, *obstacles, robot, heading, via_marker, label]
    for artist in moving:
        artist.set_animated(True)
    canvas = fig.canvas
    canvas.draw()  # the layout is worked out here, once
    fig.set_layout_engine("none")
    background = canvas.copy_from_bbox(fig.bbox)
    poses, radius = trace.robot_poses, trace.robot_radius_m

    def draw(k: int) -> np.ndarray:
        x, y, h = poses[k]
        robot.center = (x, y)
        heading.set_data([x, x + radius * np.cos(h)], [y, y + radius * np.sin(h)])
        trail.set_data(poses[: k + 1, 0], poses[: k + 1, 1])
        via = trace.via_points[k]
        target = trace.plan_targets[k]
        plan_line.set_data([x, target[0]], [y, target[1]])
        via_marker.set_data(via[:, 0], via[:, 1]) if len(via) else via_marker.set_data([], [])
        for j, patch in enumerate(obstacles):
            patch.center = tuple(trace.obstacle_positions[k, j])
        if trace.scan_points and k < len(trace.scan_points) and len(trace.scan_points[k]):
            scan.set_data(*np.asarray(trace.scan_points[k]).T)
        for line, until_s in doors:
            line.set_visible(bool(trace.times_s[k] < until_s))
        label.set_text(
            f"t = {trace.times_s[k]:5.1f} s  v = {trace.robot_speeds_mps[k]:.2f} m/s  {trace.plan_status[k]}"
        )
        canvas.restore_region(background)
        for artist in moving:
            ax.draw_artist(artist)
        return np.asarray(canvas.buffer_rgba())

    return fig, draw


def _until(trace) -> np.ndarray:
    """(W,) the time each static edge goes (inf: it stays)."""
    until = getattr(trace, "wall_until_s", None)
    return np.full(len(trace.walls), np.inf) if until is None else np.asarray(until, dtype=float)


def _write_gif(images, file: Path, fps: int, total: int, progress) -> None:
    """Pillow's GIF encoder, one shared palette (taken from the first frame, which shows every colour
    but the moving ones' overlaps), no dithering: flat colours stay flat and the frames small. Each
    frame is written as it is drawn (Pillow's own multi-frame save keeps every frame until the end: 5 GB
    for a 600 s run at one frame per step), so memory does not grow with the number of frames."""
    from PIL import GifImagePlugin, Image

    palette = None
    duration = round(1000 / fps)
    with open(file, "wb") as handle:
        for i, rgba in enumerate(images):
            image = Image.fromarray(rgba[..., :3])
            if palette is None:
                palette = image.quantize(colors=64, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
            frame = image.quantize(palette=palette, dither=Image.Dither.NONE)
            if i == 0:
                header, _ = GifImagePlugin.getheader(frame, info={"loop": 0, "duration": duration})
                for chunk in header:
                    handle.write(chunk)
            for chunk in GifImagePlugin.getdata(frame, duration=duration, disposal=1):
                handle.write(chunk)
            handle.flush()  # on disk as drawn: a run stopped midway leaves the frames so far
            if progress is not None:
                progress(i, total)
        handle.write(b";")  # the GIF trailer


def _write_mp4(images, file: Path, fps: int, total: int, progress, fig) -> None:
    width, height = fig.canvas.get_width_height()
    command = [
        "ffmpeg",
        "-y",
        "-loglevel",
        "error",
        "-f",
        "rawvideo",
        "-pix_fmt",
        "rgba",
        "-s",
        f"{width}x{height}",
        "-r",
        str(fps),
        "-i",
        "-",
        "-pix_fmt",
        "yuv420p",
        "-vf",
        "pad=ceil(iw/2)*2:ceil(ih/2)*2",
        "-vcodec",
        "libx264",
        str(file),
    ]
    with subprocess.Popen(command, stdin=subprocess.PIPE, stderr=subprocess.PIPE) as ffmpeg:
        try:
            for i, rgba in enumerate(images):
                ffmpeg.stdin.write(np.ascontiguousarray(rgba).tobytes())  # type: ignore[union-attr]  # stdin=PIPE
                if progress is not None:
                    progress(i, total)
        finally:
            ffmpeg.stdin.close()  # type: ignore[union-attr]
            error = ffmpeg.stderr.read().decode(errors="replace")  # type: ignore[union-attr]
        if ffmpeg.wait() != 0:
            raise RuntimeError(f"ffmpeg could not write {file}: {error.strip()[-500:]}")
