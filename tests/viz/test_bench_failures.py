"""``viapath bench ... --mcap-failures DIR``: one MCAP per failed episode (contact, at-fault contact,
time outside the corridor, missed goal), named after scenario and planner, holding that episode."""

from __future__ import annotations

import csv

import pytest
import yaml

pytest.importorskip("foxglove", reason="needs the viz extra (foxglove-sdk)")
mcap_reader = pytest.importorskip("mcap.reader", reason="needs the viz extra (mcap)")

from typer.testing import CliRunner  # noqa: E402

from viapath.cli import app  # noqa: E402
from viapath.scenarios import load_scenario  # noqa: E402


def _suite(folder):
    folder.mkdir()
    for name in ("paper-behind", "paper-side"):
        data = load_scenario(name).model_dump(mode="json")
        data["name"] = f"{name}-short"
        data["duration_s"] = 30.0
        (folder / f"{name}.yaml").write_text(yaml.safe_dump(data))
    return folder


def _failed(row: dict) -> bool:
    """A failure as issue 14 defines it, from the CSV text (independent of viapath's own helper)."""
    return (
        row["collision"] == "True"
        or row["at_fault_collision"] == "True"
        or float(row["time_outside_corridor_s"] or 0) > 0
        or row["reached_goal"] != "True"
    )


def test_bench_writes_an_mcap_for_each_failed_episode(tmp_path):
    suite, out, failures = _suite(tmp_path / "suite"), tmp_path / "out", tmp_path / "failures"
    result = CliRunner().invoke(
        app,
        [
            "bench",
            str(suite),
            "--planners",
            "viapath,stop",
            "--workers",
            "1",
            "--out",
            str(out),
            "--no-plots",
            "--mcap-failures",
            str(failures),
        ],
    )
    assert result.exit_code == 0, result.output
    with open(out / "episodes.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 4
    expected = {f"{r['scenario']}__{r['planner']}__oracle.mcap" for r in rows if _failed(r)}
    # 'stop' is run into from behind on paper-behind; the paper planner passes both cleanly.
    assert ("paper-behind-short", "stop") in {(r["scenario"], r["planner"]) for r in rows if _failed(r)}
    assert not any(_failed(r) for r in rows if r["planner"] == "viapath")
    assert {p.name for p in failures.iterdir()} == expected
    for row in rows:
        if not _failed(row):
            continue
        file = failures / f"{row['scenario']}__{row['planner']}__oracle.mcap"
        with open(file, "rb") as handle:
            summary = mcap_reader.make_reader(handle).get_summary()
        counts = summary.statistics.channel_message_counts
        tf = next(cid for cid, c in summary.channels.items() if c.topic == "/tf")
        # One planning cycle per 0.1 s until the goal, or to duration_s (30 s) when it was missed.
        cycles = round(float(row["time_to_goal_s"]) / 0.1) if row["reached_goal"] == "True" else 300
        assert counts[tf] == cycles
        assert summary.statistics.message_end_time == (cycles - 1) * 100_000_000


def test_bench_refuses_an_unusable_failures_folder_before_running(tmp_path):
    suite, out = _suite(tmp_path / "suite"), tmp_path / "out"
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    for bad, words in ((blocker, "is a file"), (tmp_path / "no" / "where", "does not exist")):
        result = CliRunner().invoke(
            app,
            [
                "bench",
                str(suite),
                "--planners",
                "stop",
                "--workers",
                "1",
                "--out",
                str(out),
                "--no-plots",
                "--mcap-failures",
                str(bad),
            ],
        )
        assert result.exit_code == 2 and words in result.output, result.output
    assert not out.exists()  # nothing ran
