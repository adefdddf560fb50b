"""The README's examples are code users paste first: they must work as written."""

import re
from pathlib import Path

import pytest
import yaml

from viapath.scenarios import scenario_from_dict

README = (Path(__file__).resolve().parents[1] / "README.md").read_text()


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", README, flags=re.S)


def test_readme_scenario_example_is_a_valid_scenario():
    (block,) = _blocks("yaml")
    scenario = scenario_from_dict(yaml.safe_load(block), origin="README.md")
    assert scenario.path.widths() == [1.0, 1.0]
    assert len(scenario.obstacles) == 3


@pytest.mark.parametrize("index", range(2))
def test_readme_python_examples_run(index):
    block = _blocks("python")[index]
    namespace: dict = {}
    exec(compile(block, f"README.md python block {index}", "exec"), namespace)
    if "decision" in namespace:
        command = namespace["decision"].command
        assert 0.0 <= command.speed_mps <= 0.6
        # Head-on at 2 m: the plan must go round (via points) or wait, never straight on at speed.
        assert namespace["decision"].plan.status != "straight"
    else:
        assert namespace["episode"].metrics["reached_goal"] is True


def test_readme_commands_are_one_line_and_use_a_fresh_venv():
    for marker in ("run-command", "test-command"):
        body = re.search(rf"<!-- {marker} -->\n```bash\n(.*?)```\n<!-- /{marker} -->", README, flags=re.S).group(1)
        assert body.count("\n") == 1 and "python3 -m venv .venv" in body


def test_readme_plugin_planner_example_registers_and_drives(monkeypatch):
    from viapath.planning import available_planners
    from viapath.planning.base import PLANNERS
    from viapath.scenarios import load_scenario
    from viapath.sim.loop import run_episode

    (block,) = [b for b in _blocks("python") if "name=\"mine\"" in b]
    monkeypatch.setattr(PLANNERS, "_entries", dict(PLANNERS._entries))
    exec(compile(block, "README.md plug-in example", "exec"), {})
    assert "mine" in available_planners()
    # It follows the path line at the nominal speed, avoiding no one.
    metrics = run_episode(load_scenario("paper-side"), planner="mine").metrics
    assert metrics["max_lateral_deviation_m"] < 0.05
    assert metrics["max_speed_mps"] <= 0.2 + 1e-9
    assert metrics["path_length_m"] > 4.5
