"""The animation: blitted frames are the full figure's pixels, GIFs need no ffmpeg, every step can be a frame."""

from __future__ import annotations

import numpy as np
import pytest

from viapath.scenarios import load_scenario
from viapath.sim.loop import run_episode
from viapath.viz.animate import _scene, animate_episode, frame_indices
from viapath.viz.plot import _matplotlib


@pytest.fixture(scope="module")
def episode():
    return run_episode(load_scenario("cross-left"), record_perceived=True)


def test_frame_indices_keep_the_last_step_and_the_cap():
    assert frame_indices(10, stride=3) == [0, 3, 6, 9]
    assert frame_indices(11, stride=3) == [0, 3, 6, 9, 10]
    assert len(frame_indices(2401, max_frames=400)) <= 401 and frame_indices(2401)[-1] == 2400
    assert frame_indices(5) == [0, 1, 2, 3, 4] and frame_indices(0) == []


def test_a_blitted_frame_is_the_whole_figure_redrawn(episode):
    plt = _matplotlib()
    fig, draw = _scene(plt, episode.trace, dpi=60)
    try:
        k = len(episode.trace.times_s) // 2
        blitted = draw(k).copy()
        for artist in fig.axes[0].get_children():
            if artist.get_animated():
                artist.set_animated(False)
        fig.canvas.draw()
        full = np.asarray(fig.canvas.buffer_rgba())
    finally:
        plt.close(fig)
    differing = np.any(blitted != full, axis=-1).mean()
    assert differing < 0.002, f"{differing:.2%} of the pixels differ"


def test_a_gif_has_one_frame_per_shown_step_and_reports_progress(episode, tmp_path):
    from PIL import Image

    calls = []
    file = animate_episode(episode, tmp_path / "a.gif", stride=7, progress=lambda i, n: calls.append((i, n)))
    expected = frame_indices(len(episode.trace.times_s), stride=7)
    with Image.open(file) as image:
        assert image.n_frames == len(expected)
        image.seek(0)
        first = np.asarray(image.convert("RGB")).copy()
        image.seek(image.n_frames - 1)
        last = np.asarray(image.convert("RGB"))
    assert (first != last).any()  # the robot moved
    assert calls == [(i, len(expected)) for i in range(len(expected))]


def test_other_suffixes_are_refused(episode, tmp_path):
    with pytest.raises(ValueError, match=r"gif or \.mp4"):
        animate_episode(episode, tmp_path / "a.avi")
