"""Command-line contracts found by an attacker: ``tune`` constraint values that are no constraint are
refused (exit 2, one line naming the option, no traceback); a ``bench`` episode that runs past its
time limit is a recorded failure (its row's error says so, the run exits 3), never a hang."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from viapath.bench.runner import run_bench
from viapath.cli import app


@pytest.mark.parametrize(
    "option, value",
    [
        ("--max-outside-s", "nan"),
        ("--max-outside-s", "inf"),
        ("--max-outside-s", "-1"),
        ("--max-at-fault", "-1"),
        ("--max-misses", "-2"),
        ("--timeout", "-1"),
        ("--timeout", "0"),
        ("--timeout", "nan"),
    ],
)
def test_tune_refuses_a_constraint_or_timeout_that_is_none(tmp_path, option, value):
    pytest.importorskip("optuna")
    storage = f"sqlite:///{tmp_path / 'tune.db'}"
    result = CliRunner().invoke(
        app, ["tune", "mixed", "--count", "2", "--trials", "1", "--storage", storage, "--study", "s", option, value]
    )
    assert result.exit_code == 2, result.output
    assert f"{option}: expected" in result.output
    assert "Traceback" not in result.output
    assert not (tmp_path / "tune.db").exists()  # nothing written


def _long_scenario() -> dict:
    return {
        "name": "long-walk",
        "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.2, "radius": 0.25},
        "path": {"waypoints": [[0.0, 0.0], [100.0, 0.0]], "half_width": 1.0},
        "duration_s": 600.0,
    }


def test_an_episode_past_its_time_limit_is_a_recorded_failure(tmp_path):
    result = run_bench([_long_scenario()], ["follow"], tmp_path, workers=1, progress=False, episode_time_limit_s=0.05)
    (row,) = result["rows"]
    assert row["error"].startswith("EpisodeTimeLimit") and "0.05 s" in row["error"]
    assert row["episode_wall_s"] < 30.0  # stopped at the limit, not run to its 600 s of simulated time
    assert result["errors"] == 1


def test_bench_exits_3_for_an_episode_past_its_time_limit_and_refuses_a_bad_limit(tmp_path):
    import yaml

    folder = tmp_path / "suite"
    folder.mkdir()
    (folder / "long.yaml").write_text(yaml.safe_dump(_long_scenario()))
    runner = CliRunner()
    ran = runner.invoke(
        app,
        ["bench", str(folder), "-p", "follow", "-w", "1", "--out", str(tmp_path / "out"), "--no-plots"]
        + ["--episode-time-limit", "0.05"],
    )
    assert ran.exit_code == 3, ran.output
    bad = runner.invoke(
        app, ["bench", str(folder), "-p", "follow", "--out", str(tmp_path / "out2"), "--episode-time-limit", "-1"]
    )
    assert bad.exit_code == 2 and "--episode-time-limit: expected" in bad.output


def test_the_gif_is_written_frame_by_frame(tmp_path):
    """Each frame is on disk before the next is drawn (memory does not grow with the number of frames):
    the generator of frames looks at the file as it is asked for the next one."""
    import numpy as np
    from PIL import Image

    from viapath.viz.animate import _write_gif

    file = tmp_path / "a.gif"
    sizes = []

    def frames():
        for k in range(6):
            sizes.append(file.stat().st_size if file.exists() else 0)
            image = np.zeros((40, 60, 4), dtype=np.uint8)
            image[:, : 10 * (k + 1), 0] = 255
            yield image

    _write_gif(frames(), file, fps=10, total=6, progress=None)
    assert all(b > a for a, b in zip(sizes[1:], sizes[2:]))  # grew with every frame written
    with Image.open(file) as gif:
        assert gif.n_frames == 6 and gif.info.get("loop") == 0
        gif.seek(5)
        assert np.asarray(gif.convert("RGB"))[0, 55, 0] > 200  # the last frame is the last one drawn


def test_the_metrics_are_printed_when_the_animation_fails(tmp_path, monkeypatch):
    import json

    import viapath.viz.animate as animate

    def out_of_memory(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(animate, "animate_episode", out_of_memory)
    result = CliRunner().invoke(app, ["run", "paper-front", "--json", "--animate", str(tmp_path / "a.gif")])
    assert result.exit_code != 0
    first = result.stdout.strip().splitlines()[0]
    assert json.loads(first)["scenario"] == "paper-front"
    assert "out of memory" in result.output and "Traceback" not in result.output


def test_replay_files_are_read_per_person_whatever_their_row_order(tmp_path):
    """Brute force: each track equals its rows filtered and sorted by frame (the reader sorts once)."""
    import numpy as np

    from viapath.io.eth_ucy import load_tracks

    rng = np.random.default_rng(5)
    people, rows = 300, 1500
    table = np.column_stack(
        [rng.permutation(rows) * 10.0, rng.integers(0, people, rows).astype(float), rng.normal(size=(rows, 2))]
    )
    path = tmp_path / "crowd.txt"
    np.savetxt(path, table, fmt="%.6f")
    tracks = load_tracks(path, 0.4)
    table = np.round(table, 6)
    assert [t.ped_id for t in tracks] == sorted({int(i) for i in table[:, 1]})
    for track in tracks:
        mine = table[table[:, 1] == track.ped_id]
        mine = mine[np.argsort(mine[:, 0])]
        assert np.allclose(track.times_s, mine[:, 0] / 10 * 0.4) and np.allclose(track.positions, mine[:, 2:4])
