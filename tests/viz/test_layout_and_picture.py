"""The Foxglove layout in the repository is the one the code builds, and it names only topics that
runs publish; the README picture's renderer draws a real cycle."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("foxglove.layouts", reason="needs the viz extra (foxglove-sdk)")

from viapath.viz import foxglove as fg
from viapath.viz.foxglove import METRICS_SCHEMA
from viapath.viz.foxglove_layout import LAYOUT_FILE, layout_json

REPO = Path(__file__).resolve().parents[2]


def expected_topics(scanner_names: list[str] | tuple[str, ...] = ()) -> dict[str, str]:
    """Topic → schema name of a run (laser topics only when there are scanners)."""
    topics = {
        fg.TF: "foxglove.FrameTransforms",
        fg.FOOTPRINT: "foxglove.SceneUpdate",
        fg.TRACKS: "foxglove.SceneUpdate",
        fg.PATH: "foxglove.SceneUpdate",
        fg.STATIC: "foxglove.SceneUpdate",
        fg.CANDIDATES: "foxglove.SceneUpdate",
        fg.CHOSEN: "foxglove.SceneUpdate",
        fg.COSTS: "viapath.PlanCosts",
        fg.XYT: "foxglove.SceneUpdate",
        fg.METRICS: "viapath.Metrics",
    }
    if scanner_names:
        topics.update({fg.BLIND: "foxglove.SceneUpdate", fg.DETECTIONS: "foxglove.SceneUpdate"})
        topics.update({fg.scan_topic(name): "foxglove.LaserScan" for name in scanner_names})
    return topics


def _walk(node):
    if isinstance(node, dict):
        yield node
        for value in node.values():
            yield from _walk(value)
    elif isinstance(node, list):
        for value in node:
            yield from _walk(value)


def test_committed_layout_is_current():
    assert (REPO / LAYOUT_FILE).read_text() == layout_json(), "regenerate with: python -m viapath.viz.foxglove_layout"


def test_layout_names_only_published_topics_and_fields():
    data = json.loads((REPO / LAYOUT_FILE).read_text())
    published = expected_topics(("front", "rear"))
    panels = [n for n in _walk(data) if n.get("type") == "panel"]
    assert {p["panelType"] for p in panels} >= {"ThreeDee", "Plot", "RawMessages"}
    three_d = [p for p in panels if p["panelType"] == "ThreeDee"]
    assert len(three_d) == 2
    for panel in three_d:
        assert set(panel["config"]["topics"]) <= set(published)
    # The x-y-t panel shows /xyt alone, in its own frame; the world panel hides it.
    xyt = next(p for p in three_d if p["config"]["fixedFrame"] == "xyt")
    assert [t for t, s in xyt["config"]["topics"].items() if s["visible"]] == ["/xyt"]
    world = next(p for p in three_d if p["config"]["fixedFrame"] == "world")
    assert world["config"]["topics"]["/xyt"]["visible"] is False
    fields = set(METRICS_SCHEMA["properties"])
    plotted = [s["value"] for p in panels if p["panelType"] == "Plot" for s in p["config"]["paths"]]
    assert plotted and all(v.split(".", 1)[0] == "/metrics" and v.split(".", 1)[1] in fields for v in plotted)
    raw = next(p for p in panels if p["panelType"] == "RawMessages")
    assert raw["config"]["topicPath"] in published


def test_picture_renders_a_cycle_with_its_via_points(tmp_path):
    pytest.importorskip("matplotlib")
    from viapath.path import DesignatedPath
    from viapath.scenarios import load_scenario
    from viapath.viz.scene import path_view
    from viapath.viz.xyt_plot import collect_scenes, plot_cycle

    scenario = load_scenario("paper-front")
    scenario = scenario.model_copy(update={"duration_s": 3.0})
    scenes = collect_scenes(scenario)
    scene = next(s for s in scenes if len(s.plan.via_points))
    assert len(scene.plan.candidate_polylines) > 1  # candidates are recorded for display
    view = path_view(DesignatedPath(scenario.path.waypoints, half_widths_m=scenario.path.widths()))
    out = plot_cycle(scene, view, tmp_path / "cycle.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 20_000
