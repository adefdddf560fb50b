"""The Foxglove layout for viapath runs (``docs/foxglove/viapath-layout.json``), built with foxglove-sdk.

Source: a layout in the repository arranges the panels, Foxglove's layout model
(``foxglove.layouts``). Left: the world seen from above (scans, tracks, corridor, candidates, the
chosen plan); middle: the x-y-t view of the paper's Fig. 4 in its own 3-D panel (frame ``xyt``,
time as the height); right: time series (speed, clearance, lateral deviation, plan time, shield
interventions) and the cost breakdown of the chosen and runner-up candidates.

Regenerate the file after a change of topics: ``python -m viapath.viz.foxglove_layout FILE``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from viapath.viz.foxglove import (
    BLIND,
    CANDIDATES,
    CHOSEN,
    COSTS,
    DETECTIONS,
    FOOTPRINT,
    METRICS,
    PATH,
    TRACKS,
    XYT,
    XYT_FRAME,
    scan_topic,
)

LAYOUT_FILE = Path("docs") / "foxglove" / "viapath-layout.json"


def layout(scanners: tuple[str, ...] = ("front", "rear")):
    """The layout as a ``foxglove.layouts.Layout``: the world, x-y-t and time-series columns side by side."""
    import foxglove.layouts as fl

    world_topics = _world_topics(scanners)
    return fl.Layout(
        content=fl.SplitContainer(
            direction="row",
            items=[
                fl.SplitItem(proportion=2, content=_world_panel(world_topics)),
                fl.SplitItem(proportion=2, content=_xyt_panel(world_topics)),
                fl.SplitItem(proportion=1.3, content=_series_column()),
            ],
        )
    )


def _world_topics(scanners: tuple[str, ...]) -> dict[str, Any]:
    """The world panel's topics: the scene's markers, the x-y-t scene hidden, each scanner's scan in a colour."""
    import foxglove.layouts as fl

    scene = fl.BaseRendererSceneUpdateTopicSettings
    world_topics: dict[str, Any] = {
        topic: scene(visible=True) for topic in (FOOTPRINT, BLIND, DETECTIONS, TRACKS, PATH, CANDIDATES, CHOSEN)
    }
    world_topics[XYT] = scene(visible=False)
    for name, colour in zip(scanners, ("#1f77b4", "#9467bd", "#8c564b", "#e377c2")):
        world_topics[scan_topic(name)] = fl.BaseRendererLaserScanTopicSettings(
            visible=True, point_size=3.0, color_mode="flat", flat_color=colour
        )
    return world_topics


def _world_panel(world_topics: dict[str, Any]):
    """The world from above, following the robot, with a 20 m grid."""
    import foxglove.layouts as fl

    grid: dict[str, Any] = {
        "grid": fl.BaseRendererGridLayerSettings(layer_id="foxglove.Grid", frame_id="world", size=20.0, divisions=20.0)
    }
    return fl.ThreeDeePanel(
        title="world (from above)",
        config=fl.ThreeDeeConfig(
            fixed_frame="world",
            follow_tf="base",
            follow_mode="follow-position",
            topics=world_topics,
            layers=grid,
            camera_state=fl.ThreeDeeCameraState(perspective=False, distance=12.0, phi=0.0, theta_offset=0.0),
        ),
    )


def _xyt_panel(world_topics: dict[str, Any]):
    """x-y-t in its own frame (time as the height): only the x-y-t scene shown, seen from an angle."""
    import foxglove.layouts as fl

    scene = fl.BaseRendererSceneUpdateTopicSettings
    xyt_topics: dict[str, Any] = {topic: scene(visible=False) for topic in world_topics if topic != XYT}
    xyt_topics[XYT] = scene(visible=True)
    return fl.ThreeDeePanel(
        title="x-y-t (paper Fig. 4): people as cylinders, plan through via points",
        config=fl.ThreeDeeConfig(
            fixed_frame=XYT_FRAME,
            follow_tf=XYT_FRAME,
            follow_mode="follow-none",
            topics=xyt_topics,
            layers={
                "grid": fl.BaseRendererGridLayerSettings(
                    layer_id="foxglove.Grid", frame_id=XYT_FRAME, size=20.0, divisions=20.0
                )
            },
            camera_state=fl.ThreeDeeCameraState(
                perspective=True, distance=14.0, phi=60.0, theta_offset=45.0, target_offset=(3.0, 0.0, 2.5)
            ),
        ),
    )


def _plot(title: str, *series: tuple[str, str]):
    """A plot panel of fields of the metrics topic: (field, label) per series."""
    import foxglove.layouts as fl

    return fl.PlotPanel(
        title=title,
        config=fl.PlotConfig(paths=[fl.PlotSeries(value=f"{METRICS}.{field}", label=label) for field, label in series]),
    )


def _series_column():
    """Time series (speed, clearance and deviation, the planner) above the cost breakdown."""
    import foxglove.layouts as fl

    speed = _plot(
        "speed",
        ("speed_mps", "speed m/s"),
        ("command_speed_mps", "commanded m/s"),
        ("turn_rate_radps", "turn rate rad/s"),
    )
    clearance = _plot(
        "clearance and deviation", ("clearance_m", "clearance m"), ("lateral_deviation_m", "lateral deviation m")
    )
    planner = _plot(
        "planner",
        ("plan_time_ms", "plan time ms"),
        ("shield_interventions", "shield interventions"),
        ("candidates", "candidates"),
    )
    costs = fl.RawMessagesPanel(
        title="costs: chosen vs runner-up", config=fl.RawMessagesConfig(topic_path=COSTS, expansion="all")
    )
    return fl.SplitContainer(
        direction="column", items=[fl.SplitItem(content=panel) for panel in (speed, clearance, planner, costs)]
    )


def layout_json() -> str:
    """The layout file's text (indented, stable)."""
    return json.dumps(json.loads(layout().to_json()), indent=2, sort_keys=True) + "\n"


def main(argv: list[str] | None = None) -> None:
    args = sys.argv[1:] if argv is None else argv
    target = Path(args[0]) if args else LAYOUT_FILE
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(layout_json())
    print(f"wrote {target}")


if __name__ == "__main__":
    main()
