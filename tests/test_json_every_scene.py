"""``viapath run --json`` prints one strict JSON document (no NaN, no Infinity, no traceback) on every
built-in scenario and on a generated scene of every suite family, with oracle and with laser perception.

Scenes without people, laser runs without tracks and static scenes are where a metric is undefined
(NaN) or unbounded (inf); such values must reach the document as ``null``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from viapath.bench.suites import FAMILIES, data_root, generate_suite
from viapath.cli import app
from viapath.scenarios.loader import builtin_names

BUILTIN_DIR = Path(__file__).resolve().parents[1] / "src" / "viapath" / "scenarios" / "builtin"
BUILTINS = builtin_names()


def _refuse_constant(name: str):
    raise AssertionError(f"--json wrote the non-JSON constant {name}")


def _strict_run_json(scene: str) -> list[dict]:
    """Both perceptions of ``scene`` (a built-in name or a YAML path), parsed strictly."""
    documents = []
    for perception in ("oracle", "laser"):
        result = CliRunner().invoke(app, ["run", scene, "--perception", perception, "--json"])
        assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
        assert result.exit_code == 0, result.output
        assert "Traceback" not in result.output
        document = json.loads(result.stdout, parse_constant=_refuse_constant)
        assert isinstance(document, dict) and document["perception"] == perception
        for key, value in document.items():
            assert not (isinstance(value, float) and not math.isfinite(value)), (scene, perception, key, value)
        documents.append(document)
    return documents


def test_every_builtin_file_is_run_here():
    assert set(BUILTINS) == {p.stem for p in BUILTIN_DIR.glob("*.yaml")} and len(BUILTINS) >= 12


@pytest.mark.parametrize("name", BUILTINS)
def test_run_json_is_strict_on_every_builtin(name):
    oracle, laser = _strict_run_json(name)
    assert oracle["scenario"] == laser["scenario"] == name


@pytest.mark.parametrize("family", FAMILIES.ordered())
def test_run_json_is_strict_on_a_generated_scene_of_every_family(family, tmp_path):
    (scenario,) = generate_suite(family, 1, seed=5)
    scene = tmp_path / f"{scenario['name']}.yaml"
    scene.write_text(yaml.safe_dump(scenario))
    _strict_run_json(str(scene))


def test_run_json_is_strict_on_a_replayed_window(tmp_path):
    if not (data_root() / "eth_ucy_trajectron").is_dir():
        pytest.skip(f"ETH/UCY data not found under {data_root()}")
    (scenario,) = generate_suite("eth-ucy", 1, seed=5)
    scene = tmp_path / f"{scenario['name']}.yaml"
    scene.write_text(yaml.safe_dump(scenario))
    _strict_run_json(str(scene))


def test_a_scene_without_people_writes_null_not_nan(tmp_path):
    """The metric that has no value without people (clearance to a person) is null, not NaN."""
    scene = tmp_path / "empty.yaml"
    scene.write_text(
        yaml.safe_dump(
            {
                "name": "empty",
                "robot": {"start": [0.0, 0.0], "heading": 0.0, "speed": 0.3},
                "path": {"waypoints": [[0.0, 0.0], [3.0, 0.0]], "half_width": 1.0},
                "duration_s": 30,
            }
        )
    )
    oracle, laser = _strict_run_json(str(scene))
    assert oracle["reached_goal"] is True and laser["reached_goal"] is True
    assert any(value is None for value in oracle.values())
