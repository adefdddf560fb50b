"""Faster suite handling (issue 16) changes no scenario.

* Generating a synthetic suite in worker processes gives the scenarios of a serial generation.
* Suite files written with libyaml's emitter and read with its parser hold the data the pure-Python
  dumper and loader give (and the same text).
"""

from __future__ import annotations

import yaml

from viapath.bench.runner import load_suite
from viapath.bench.suites import generate_suite


def test_parallel_generation_equals_serial():
    serial = generate_suite("mixed", 12, seed=5)
    parallel = generate_suite("mixed", 12, seed=5, workers=2)
    assert [s["name"] for s in serial] == [s["name"] for s in parallel]
    assert serial == parallel
    assert len({s["name"].rsplit("-", 1)[0] for s in serial}) >= 6  # several families, crowd ones included


def test_suite_files_round_trip_as_with_the_pure_python_yaml(tmp_path):
    loaded = load_suite("mixed", tmp_path, count=6, seed=2)
    generated = generate_suite("mixed", 6, seed=2)
    for scenario, data in zip(generated, loaded, strict=True):
        text = (tmp_path / "suite" / f"{scenario['name']}.yaml").read_text()
        assert text == yaml.safe_dump(scenario, sort_keys=False, default_flow_style=None, width=120)
        assert yaml.load(text, Loader=yaml.SafeLoader) == yaml.safe_load(yaml.safe_dump(scenario))
        assert data["name"] == scenario["name"] and len(data["obstacles"]) == len(scenario["obstacles"])


def test_suite_written_and_read_in_workers_equals_serial(tmp_path):
    """A generated suite is written and read back in the workers, chunk by chunk (more than one chunk of
    50 here): the same files and the same scenario dicts, in the same order, as in one process."""
    serial = load_suite("mixed", tmp_path / "serial", count=60, seed=4, workers=1)
    parallel = load_suite("mixed", tmp_path / "parallel", count=60, seed=4, workers=2)
    assert serial == parallel
    files = sorted(p.name for p in (tmp_path / "serial" / "suite").iterdir())
    assert files == sorted(p.name for p in (tmp_path / "parallel" / "suite").iterdir()) and len(files) == 60
    for name in files:
        assert (tmp_path / "serial" / "suite" / name).read_text() == (
            tmp_path / "parallel" / "suite" / name
        ).read_text()
