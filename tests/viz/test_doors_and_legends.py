"""Pictures say what the run had: a door is drawn while it is closed (its ``until_s``), the grey dots of
the bench's deviation plot are named in a legend."""

from __future__ import annotations

import numpy as np
import pytest

from viapath.scenarios.loader import scenario_from_dict
from viapath.sim.loop import run_episode
from viapath.viz.plot import _matplotlib, draw_scene

DOOR = [[2.0, -1.0], [2.0, 1.0]]
OPENS_S = 6.0


@pytest.fixture(scope="module")
def door_episode():
    scene = {
        "name": "door",
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.3, "radius": 0.25},
        "path": {"waypoints": [[0.0, 0.0], [4.0, 0.0]], "half_width": 0.6},
        "walls": [{"points": DOOR, "until_s": OPENS_S}, [[-1.0, 0.9], [5.0, 0.9]]],
        "duration_s": 30.0,
    }
    return run_episode(scenario_from_dict(scene))


def _door_lines(ax):
    door = np.array(DOOR)
    return [
        line
        for line in ax.get_lines()
        if np.asarray(line.get_xydata()).shape == door.shape and np.allclose(line.get_xydata(), door)
    ]


def test_the_plot_draws_the_door_as_a_wall_while_closed_and_dotted_once_open(door_episode):
    plt = _matplotlib()
    trace = door_episode.trace
    before = int(np.searchsorted(trace.times_s, OPENS_S - 1.0))
    for upto, closed in ((before, True), (None, False)):
        fig, ax = plt.subplots()
        try:
            draw_scene(ax, trace, upto=upto)
            (line,) = _door_lines(ax)
            if closed:
                assert line.get_linestyle() == "-" and line.get_linewidth() == 2.5 and line.get_label() == "wall"
            else:
                assert line.get_linestyle() == ":" and line.get_label() == "door (opened)"
            standing = [ln for ln in ax.get_lines() if ln.get_label() == "wall"]
            assert standing, "the wall that stays is drawn as a wall"
        finally:
            plt.close(fig)


def test_the_animation_shows_the_door_only_in_frames_before_it_opens(door_episode):
    from viapath.viz.animate import _scene

    plt = _matplotlib()
    trace = door_episode.trace
    fig, draw = _scene(plt, trace, dpi=50)
    try:
        (line,) = _door_lines(fig.axes[0])
        shown = {}
        for k in range(0, len(trace.times_s), 5):
            draw(k)
            shown[float(trace.times_s[k])] = line.get_visible()
    finally:
        plt.close(fig)
    assert all(visible == (t < OPENS_S) for t, visible in shown.items()), shown
    assert any(shown.values()) and not all(shown.values())


def test_deviation_plot_names_its_dots_in_a_legend(tmp_path, monkeypatch):
    from viapath.bench import report

    rows = [
        {"planner": p, "shield": "off", "time_ratio": 1.0 + 0.1 * i, "max_lateral_deviation_m": 0.1 * i}
        for p in ("viapath", "dwa")
        for i in range(4)
    ]
    plt = _matplotlib()
    saved = []
    monkeypatch.setattr(plt.Figure, "savefig", lambda fig, *a, **k: saved.append(fig))
    monkeypatch.setattr(plt, "close", lambda fig=None: None)
    report.plot_deviation_vs_time(rows, tmp_path / "deviation_vs_time.png")
    (fig,) = saved
    legend = fig.axes[0].get_legend()
    assert legend is not None
    assert [t.get_text() for t in legend.get_texts()] == [
        "every planner's episodes",
        "this planner's episodes",
        "median",
    ]
