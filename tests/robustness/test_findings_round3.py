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
    result = run_bench([_long_scenario()], ["follow"], tmp_path, workers=1, progress=False, episode_time_limit_s=0.5)
    (row,) = result["rows"]
    assert row["error"].startswith("EpisodeTimeLimit") and "0.5 s" in row["error"]
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
        + ["--episode-time-limit", "0.5"],
    )
    assert ran.exit_code == 3, ran.output
    bad = runner.invoke(
        app, ["bench", str(folder), "-p", "follow", "--out", str(tmp_path / "out2"), "--episode-time-limit", "-1"]
    )
    assert bad.exit_code == 2 and "--episode-time-limit: expected" in bad.output
