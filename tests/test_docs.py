"""The documentation site: its generated reference covers the code, its nav covers its pages, and the
results page is written from the runs it names.

The site itself is built by ``mkdocs build --strict`` (extra ``docs``); these tests need no mkdocs."""

import importlib.util
import json
import re
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _load(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up while the class is made
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def reference():
    return _load(ROOT / "docs_hooks" / "reference.py", "docs_reference").pages()


def test_the_cli_page_has_every_command_and_option(reference):
    import typer._click as click
    import typer.main

    from viapath.cli import app

    page = reference["reference/cli.md"]
    root = typer.main.get_command(app)
    ctx = click.Context(root, info_name="viapath")
    seen = 0
    for name in root.list_commands(ctx):
        command = root.get_command(ctx, name)
        commands = [(f"viapath {name}", command)]
        if hasattr(command, "list_commands"):
            commands += [(f"viapath {name} {sub}", command.get_command(ctx, sub)) for sub in command.list_commands(ctx)]
        for title, cmd in commands:
            assert f"`{title}`" in page, title
            for param in cmd.params:
                if param.param_type_name == "option" and param.name != "help":
                    assert f"`{param.opts[0]}`" in page.split(f"`{title}`", 1)[1], (title, param.opts)
                    seen += 1
    assert seen > 50


def test_the_options_page_has_every_option_of_every_planner_with_its_default_and_unit(reference):
    from viapath.planning import available_planners, planner_class
    from viapath.safety import SHIELD_OPTIONS

    page = reference["reference/options.md"]
    for name in available_planners():
        assert f"## Planner `{name}`" in page
        for option in planner_class(name).options:
            row = re.search(rf"^\| `{re.escape(option.path)}` \|(.*)$", page, flags=re.M)
            assert row, (name, option.path)
            if option.unit:
                assert f"| {option.unit} |" in row.group(0), (option.path, row.group(0))
    for option in SHIELD_OPTIONS:
        assert f"| `{option.path}` |" in page


def test_the_scenario_page_has_every_field_of_every_model(reference):
    from pydantic import BaseModel

    from viapath.scenarios import Scenario

    page = reference["reference/scenario.md"]
    todo, done = [Scenario], set()
    while todo:
        model = todo.pop()
        if model in done:
            continue
        done.add(model)
        assert f": {model.__name__}" in page, model.__name__
        for field_name, field in model.model_fields.items():
            assert f"| `{field_name}` |" in page, (model.__name__, field_name)
            todo += [m for m in _models(field.annotation) if m not in done]
    assert len(done) >= 10
    assert BaseModel not in done


def _models(annotation) -> list:
    """The viapath pydantic models inside a field's annotation (lists, unions, Annotated)."""
    import typing

    from pydantic import BaseModel

    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation] if annotation.__module__.startswith("viapath") else []
    return [model for arg in typing.get_args(annotation) for model in _models(arg)]


def test_the_ros2_page_has_every_parameter_and_every_topic_parameter():
    pytest.importorskip("viapath.ros2.settings")
    from viapath.ros2.settings import all_options

    page = _load(ROOT / "docs_hooks" / "reference.py", "docs_reference_ros2").ros2_page()
    options = all_options("viapath")
    for option in options:
        assert f"| `{option.path}` |" in page, option.path
    topics = page.split("## Topics", 1)[1].split("## Parameters", 1)[0]
    for option in options:
        if option.name.endswith("topic"):
            assert f"| `{option.name}` | `" in topics, option.name


def _nav_pages(nav) -> list[str]:
    pages = []
    for item in nav:
        value = next(iter(item.values())) if isinstance(item, dict) else item
        pages += _nav_pages(value) if isinstance(value, list) else [value]
    return pages


def test_every_page_is_in_the_nav_and_every_nav_entry_is_a_page_or_generated(reference):
    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text())
    nav = _nav_pages(config["nav"])
    written = {p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md")}
    assert written - set(nav) == set(), "pages missing from mkdocs.yml's nav"
    assert set(nav) - written - set(reference) == set(), "nav entries that are no page"
    assert len(nav) == len(set(nav))


def test_the_manual_carries_no_history():
    pattern = re.compile(r"wave [0-9]|issue [0-9]|used for no choice", re.I)
    for path in [ROOT / "README.md", *DOCS.rglob("*.md")]:
        for number, line in enumerate(path.read_text().splitlines(), 1):
            assert not pattern.search(line), f"{path.relative_to(ROOT)}:{number}: {line}"


def test_design_notes_keep_the_section_numbers_the_code_cites():
    headings = re.findall(r"^## (\d+)\. ", (DOCS / "design.md").read_text(), flags=re.M)
    assert headings == [str(n) for n in range(1, 13)]


# --- the results page ------------------------------------------------------------------------------


@pytest.fixture
def results_page():
    return _load(ROOT / "benchmarks" / "results_page.py", "results_page")


def _summary(planner: str, success: float, episodes: int = 200) -> list[dict]:
    return [
        {
            "planner": planner,
            "episodes": episodes,
            "errors": 0,
            "success_rate": success,
            "reached_goal_rate": 0.99,
            "collision_rate": 1 - success,
            "at_fault_collision_rate": 0.005,
            "at_fault_avoidable": 1,
            "at_fault_unavoidable": 2,
            "static_contact_rate": 0.0,
            "time_ratio_median": 0.8869,
            "mean_lateral_deviation_m": 0.15464,
            "time_outside_corridor_s": 0.0,
            "min_clearance_m": -0.49,
            "shield_interventions_per_episode": 2.085,
        }
    ]


def test_results_page_shows_each_run_beside_its_command(results_page, tmp_path):
    (tmp_path / "mixed0").mkdir()
    (tmp_path / "mixed0" / "summary.json").write_text(json.dumps(_summary("viapath +shield", 0.945)))
    metrics = {"reached_goal": True, "collision": False, "min_clearance_m": 0.1897, "time_to_goal_s": 24.2}
    (tmp_path / "paper-front.json").write_text(json.dumps(metrics | {"max_speed_mps": 0.5}))
    page = results_page.render(tmp_path, 2, previous="")
    mixed = page.split("## Generated encounters", 1)[1].split("\n## ", 1)[0]
    assert "viapath bench mixed --count 200 --seed 0 -p viapath -w 2 --no-plots --out OUT/mixed0" in mixed
    assert "| mixed, seed 0 | viapath +shield | 200 | 94.5 % | 99.0 % | 5.5 % | 0.5 % | 1 / 2 |" in mixed
    assert "| 0.89 | 0.155 |" in mixed
    assert "Not measured in this run: mixed, seed 3." in mixed  # its summary is missing
    assert "| paper-front | oracle | yes | no | 0.19 | 24.2 |" in page
    assert "paper-side |" not in page.split("## Generated", 1)[0].split("|---|")[-1]
    assert "## Every planner" not in page  # the optional run was not made


def test_results_page_keeps_the_ros2_table_when_the_runs_did_not_make_one(results_page, tmp_path):
    table = "| scenario | time to goal, ROS 2 / run |\n|---|---|\n| paper-front | 27.4 s / 27.4 s |"
    first = results_page.render(tmp_path, 2, previous="")
    assert "Not measured in this run: run the command above (extra `ros2`)" in first
    (tmp_path / results_page.ROS2_TABLE).write_text(table + "\n")
    with_table = results_page.render(tmp_path, 2, previous="")
    assert table in with_table
    (tmp_path / results_page.ROS2_TABLE).unlink()
    assert table in results_page.render(tmp_path, 2, previous=with_table)


def test_the_shipped_results_page_is_the_scripts_output():
    text = (DOCS / "results.md").read_text()
    assert text.startswith("# Results\n\n<!-- Generated by benchmarks/results_page.py")
    assert "python benchmarks/results_page.py --from DIR" in text
