"""One planning cycle drawn with matplotlib: the world from above and the paper's Fig. 4 in x-y-t.

Source: Yamada, Sa, Ohya Fig. 4 (obstacles as oblique cylinders in x-y-t, the robot's plan as a
polyline through its via points) and the need for a picture of what the Foxglove view shows, made by
our own code for the README). Draws a :class:`viapath.viz.scene.CycleScene`, the same content as
the MCAP's ``/xyt`` and plan topics. matplotlib is imported lazily.

Usage: ``python -m viapath.viz.xyt_plot SCENARIO OUT.png [--time S] [--perception oracle|laser]``;
without ``--time`` the first cycle whose plan goes through a via point is drawn.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from viapath.viz.scene import CycleScene, ForecastSettings, SceneBuilder, candidate_colour


def collect_scenes(scenario, perception: str = "oracle", **run_kwargs) -> list[CycleScene]:
    """Run ``scenario`` and keep every cycle's scene (candidates recorded for display)."""
    return episode_and_scenes(scenario, perception, **run_kwargs)[1]


def episode_and_scenes(scenario, perception: str = "oracle", **run_kwargs) -> tuple[Any, list[CycleScene]]:
    """Run ``scenario`` (``run_kwargs``: :func:`viapath.sim.loop.run_episode`'s) and keep every cycle's scene
    (candidates recorded for display): the :class:`~viapath.sim.loop.Episode` and the scenes."""
    from viapath.observation import Obstacles
    from viapath.scenarios.build import scenario_path
    from viapath.sim.loop import run_episode
    from viapath.viz.foxglove import display_overrides

    path = scenario_path(scenario)
    scenes: list[CycleScene] = []
    builder: list[SceneBuilder] = []

    def on_step(record):
        if not builder:
            builder.append(SceneBuilder(path, scenario.robot.radius, ForecastSettings.from_planner(record.planner)))
        world = record.world
        present = np.isfinite(world.obstacle_positions).all(axis=1)
        truth = Obstacles(
            world.obstacle_positions[present],
            world.obstacle_velocities[present],
            world.obstacle_radii_m[present],
            ids=np.flatnonzero(present),
        )
        state = record.state
        scenes.append(
            builder[0].build(
                record.step,
                record.time_s,
                (state.x, state.y, state.heading_rad),
                state.speed_mps,
                state.turn_rate_radps,
                record.observation,
                record.decision,
                record.plan_time_ms,
                record.perception if record.scans is not None else None,
                truth,
            )
        )

    episode = run_episode(
        scenario,
        perception=perception,
        planner_overrides=display_overrides(scenario, scenario.planner.name),
        on_step=on_step,
        **run_kwargs,
    )
    return episode, scenes


def plot_cycle(scene: CycleScene, path_view, file: str | Path, title: str | None = None) -> Path:
    """Write one cycle's figure to ``file``: the world from above (left) and x-y-t (right)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(13.0, 5.4))
    grid = fig.add_gridspec(1, 2, width_ratios=[1.25, 1.0])
    top = fig.add_subplot(grid[0, 0])
    xyt = fig.add_subplot(grid[0, 1], projection="3d")
    _draw_from_above(top, scene, path_view)
    _draw_xyt(xyt, scene, path_view)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    file = Path(file)
    fig.savefig(file, dpi=110)
    plt.close(fig)
    return file


def _draw_from_above(top, scene: CycleScene, path_view) -> None:
    """The world from above: corridor, path, candidates (coloured by cost), the chosen plan and its via
    points, the robot, the people with their velocities, scan points and the subgoal."""
    import matplotlib.pyplot as plt

    plan = scene.plan
    for k, outline in enumerate(path_view.corridor_outlines):
        top.fill(outline[:, 0], outline[:, 1], color="#2ca02c", alpha=0.08, lw=0)
        top.plot(outline[:, 0], outline[:, 1], color="#2ca02c", lw=0.8, label="corridor" if k == 0 else None)
    top.plot(*path_view.waypoints.T, color="0.3", lw=1.0, ls="--", label="designated path")
    costs = plan.candidate_costs
    finite = costs[np.isfinite(costs)] if len(costs) else costs
    low, high = (finite.min(), finite.max()) if len(finite) else (0.0, 0.0)
    for i, line in enumerate(plan.candidate_polylines):
        colour = candidate_colour(float(costs[i]) if i < len(costs) else np.inf, low, high)
        top.plot(
            line[:, 0],
            line[:, 1],
            color=colour[:3],
            alpha=0.5,
            lw=0.8,
            label="candidates (green: low E, red: high E)" if i == 0 else None,
        )
    top.plot(plan.waypoints[:, 0], plan.waypoints[:, 1], color="#0072ff", lw=2.5, label="chosen plan")
    if len(plan.via_points):
        top.plot(plan.via_points[:, 0], plan.via_points[:, 1], "kx", ms=9, mew=2, label="via points")
    x, y, heading = scene.robot_pose
    top.add_patch(plt.Circle((x, y), scene.robot_radius_m, color="#1f4fe0", alpha=0.4))
    top.arrow(x, y, 0.3 * np.cos(heading), 0.3 * np.sin(heading), width=0.02, color="#1f4fe0")
    for person in scene.xyt.persons:
        px, py = person.position
        top.add_patch(plt.Circle((px, py), person.radius_m, color="#d62728", alpha=0.6))
        top.arrow(
            px,
            py,
            2.0 * person.velocity[0],
            2.0 * person.velocity[1],
            width=0.025,
            color="#8b0000",
            length_includes_head=True,
        )
    if len(scene.scan_points_world):
        top.plot(*scene.scan_points_world.T, ".", ms=2, color="#1f77b4", label="scan points")
    top.plot(*scene.subgoal, marker="*", ms=14, color="#e6b800", ls="none", label="subgoal")
    top.set_aspect("equal")
    top.set_xlabel("x (m)")
    top.set_ylabel("y (m)")
    top.set_title(
        f"t = {scene.time_s:.1f} s: {plan.status} at {plan.speed_mps:.2f} m/s "
        f"({len(plan.candidate_polylines)} candidates)"
    )
    top.plot([], [], color="#8b0000", lw=2, label="person: velocity × 2 s")
    top.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=3, fontsize=7.5, framealpha=0.9)
    top.grid(alpha=0.3)


def _draw_xyt(xyt, scene: CycleScene, path_view) -> None:
    """x-y-t, time as the height (seconds after this cycle): the people as oblique cylinders, the plan
    through its via points, the robot's time axis and the corridor at t = 0."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    x, y, _ = scene.robot_pose
    for i, _person in enumerate(scene.xyt.persons):
        triangles = scene.xyt.mesh(i, 32)
        xyt.add_collection3d(Poly3DCollection(triangles, facecolor="#d62728", alpha=0.18, edgecolor="none"))
        axis = scene.xyt.axis_xyt(i)
        xyt.plot(axis[:, 0], axis[:, 1], axis[:, 2], color="#8b0000", lw=1.0)
        for ring in scene.xyt.rings(i, 48):
            closed = np.vstack([ring, ring[:1]])
            xyt.plot(closed[:, 0], closed[:, 1], closed[:, 2], color="#b22222", lw=0.8)
    line = scene.xyt.plan_xyt
    xyt.plot(line[:, 0], line[:, 1], line[:, 2], color="#0072ff", lw=2.5, label="robot plan (x, y, t)")
    via = scene.xyt.via_points_xyt
    if len(via):
        xyt.scatter(via[:, 0], via[:, 1], via[:, 2], color="k", marker="x", s=50, depthshade=False, label="via points")
    horizon = scene.xyt.settings.horizon_s
    xyt.plot([x, x], [y, y], [0, horizon], color="0.5", lw=0.8, ls=":")
    for outline in path_view.corridor_outlines:
        xyt.plot(outline[:, 0], outline[:, 1], np.zeros(len(outline)), color="#2ca02c", lw=0.6)
    xyt.plot([], [], color="#d62728", lw=6, alpha=0.3, label="people: oblique cylinders |x - c - v t| <= R")
    xyt.set_xlabel("x (m)")
    xyt.set_ylabel("y (m)")
    xyt.set_zlabel("t (s)")
    xyt.set_zlim(0, horizon)
    xs = np.concatenate([line[:, 0], *[scene.xyt.axis_xyt(i)[:, 0] for i in range(len(scene.xyt.persons))]])
    ys = np.concatenate([line[:, 1], *[scene.xyt.axis_xyt(i)[:, 1] for i in range(len(scene.xyt.persons))]])
    xyt.set_xlim(xs.min() - 0.8, xs.max() + 0.8)
    span = max(1.5, 0.5 * (ys.max() - ys.min()) + 0.8)
    # y reversed: the robot's left (+y, where it passes a person met head-on) faces the viewer.
    xyt.set_ylim(0.5 * (ys.max() + ys.min()) + span, 0.5 * (ys.max() + ys.min()) - span)
    xyt.view_init(elev=22, azim=-62)
    xyt.set_title("x-y-t (paper Fig. 4): what the planner forecast")
    xyt.legend(loc="upper left", fontsize=7)


def main(argv: list[str] | None = None) -> None:
    from viapath.scenarios import load_scenario
    from viapath.viz.scene import path_view

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario")
    parser.add_argument("out", type=Path)
    parser.add_argument("--time", type=float, default=None, help="simulated time of the cycle to draw (s)")
    parser.add_argument("--perception", default="oracle")
    args = parser.parse_args(argv)
    scenario = load_scenario(args.scenario)
    scenes = collect_scenes(scenario, args.perception)
    if args.time is None:
        scene = next((s for s in scenes if len(s.plan.via_points)), scenes[0])
    else:
        scene = min(scenes, key=lambda s: abs(s.time_s - args.time))
    from viapath.scenarios.build import scenario_path

    view = path_view(scenario_path(scenario))
    out = plot_cycle(scene, view, args.out, title=f"{scenario.name}, {args.perception} perception, one planning cycle")
    print(f"wrote {out} (t = {scene.time_s:.1f} s)")


if __name__ == "__main__":
    main()
