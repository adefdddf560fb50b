"""MkDocs hook: the reference pages, generated from the code at every build (never written by hand).

Source: the definitions the program itself runs on, read at build time:
* the command line from the typer app (:data:`viapath.cli.app`): every command, argument and option with
  its help and default, as ``viapath COMMAND --help`` prints them;
* every option from its one schema (:class:`viapath.options.Option`): each planner's options, the shield's,
  the robot's limits and the subgoal policy, with default, unit and bounds;
* the scenario file from its pydantic models (:mod:`viapath.scenarios.models`);
* the ROS 2 node's parameters from :func:`viapath.ros2.settings.all_options` (no rclpy needed), and its
  topics from the parameters that name them;
* the Python API: one page per stable public module, rendered by mkdocstrings from the docstrings.

Choices made here: the pages are added to MkDocs' file collection in ``on_files`` (nothing is written into
``docs/``), so a stale reference page cannot exist; a module that fails to import fails the build.
"""

from __future__ import annotations

import sys
import typing
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT / "src") not in sys.path:
    sys.path.insert(0, str(ROOT / "src"))

#: Stable public modules whose docstrings make the Python API pages (module, title, one line).
API_MODULES = (
    ("viapath.planning", "Planners", "make a planner, call it every cycle, write your own"),
    ("viapath.scenarios", "Scenarios", "load and validate scenario files"),
    ("viapath.sim.loop", "Simulation loop", "run an episode and read its metrics"),
    ("viapath.path", "Designated path", "the path, its corridor and the subgoal tracker"),
    ("viapath.geometry", "x-y-t geometry", "tangents, via points and leg checks"),
    ("viapath.options", "Option schema", "one definition of every option"),
    ("viapath.safety", "Passive safety", "the shield and the shielded planner"),
)


def _cell(text: Any) -> str:
    """Text for one markdown table cell: one line, pipes escaped."""
    return " ".join(str(text).split()).replace("|", "\\|").replace("<", "&lt;").replace(">", "&gt;")


def _value(value: Any) -> str:
    if isinstance(value, tuple | list):
        return "[" + ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value) + "]"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, str):
        return f'"{value}"' if value == "" else value
    return str(value)


def _bounds(option: Any) -> str:
    parts = []
    if option.minimum is not None:
        parts.append(f"{'>' if option.exclusive_minimum else '≥'} {option.minimum:g}")
    if option.maximum is not None:
        parts.append(f"≤ {option.maximum:g}")
    if option.choices:
        parts.append("one of " + ", ".join(f"`{c}`" for c in option.choices))
    return "; ".join(parts)


def _option_table(options: Any, prefix: str = "") -> str:
    lines = ["| option | default | unit | bounds | what it does |", "|---|---|---|---|---|"]
    for o in options:
        lines.append(
            f"| `{prefix}{o.path}` | `{_cell(_value(o.default))}` | {_cell(o.unit)} | {_cell(_bounds(o))} | {_cell(o.help)} |"
        )
    return "\n".join(lines) + "\n"


# --- the command line ------------------------------------------------------------------------------


def _param_row(param: Any) -> str:
    if param.param_type_name == "argument":
        name = f"`{param.name.upper()}`"
    else:
        name = ", ".join(f"`{o}`" for o in [*param.opts, *param.secondary_opts])
    default = param.default
    shown = "" if default is None or param.required or callable(default) else f"`{_cell(_value(default))}`"
    if getattr(param, "is_flag", False) and not param.secondary_opts:
        shown = "off" if not default else "on"
    elif getattr(param, "is_flag", False):
        shown = f"`{param.opts[0] if default else param.secondary_opts[0]}`"
    kind = "argument" if param.param_type_name == "argument" else "option"
    required = " (required)" if param.required else ""
    return f"| {name} | {kind}{required} | {shown} | {_cell(getattr(param, 'help', '') or '')} |"


def _command_section(command: Any, path: str, level: int) -> list[str]:
    import typer._click as click  # typer ships its own click

    out = [f"{'#' * level} `{path}`", ""]
    help_text = (command.help or "").strip()
    if help_text:
        out += [help_text.replace("\b\n", "\n"), ""]
    params = [p for p in command.params if p.name != "help" and not getattr(p, "hidden", False)]
    if params:
        out += ["| name | kind | default | help |", "|---|---|---|---|", *(_param_row(p) for p in params), ""]
    if hasattr(command, "list_commands"):
        ctx = click.Context(command, info_name=path)
        for name in command.list_commands(ctx):
            sub = command.get_command(ctx, name)
            if sub is not None and not getattr(sub, "hidden", False):
                out += _command_section(sub, f"{path} {name}", level + 1)
    return out


def cli_page() -> str:
    import typer.main

    from viapath.cli import app

    root = typer.main.get_command(app)
    lines = [
        "# Command line",
        "",
        "*Generated from the command definitions (`viapath.cli`); `viapath COMMAND --help` prints the same.*",
        "",
        "Exit codes shared by every command: 0 done, 2 bad input (the message names the file, field or "
        "option, and what was expected; no traceback), 130 interrupted. `viapath bench` adds 3 (some "
        "episode crashed or a worker died; the finished rows are kept and the same command resumes).",
        "",
    ]
    import typer._click as click

    ctx = click.Context(root, info_name="viapath")
    lines += ["| name | kind | default | help |", "|---|---|---|---|"]
    lines += [_param_row(p) for p in root.params if p.name != "help"]
    lines.append("")
    for name in root.list_commands(ctx):
        sub = root.get_command(ctx, name)
        if sub is not None and not getattr(sub, "hidden", False):
            lines += _command_section(sub, f"viapath {name}", 2)
    return "\n".join(lines) + "\n"


# --- options ---------------------------------------------------------------------------------------


def options_page() -> str:
    from viapath.limits import LIMITS_OPTIONS, ROBOT_OPTIONS, SUBGOAL_OPTIONS
    from viapath.planning import available_planners, planner_class
    from viapath.planning.base import COMMON_OPTIONS
    from viapath.safety import SHIELD_OPTIONS

    common = {o.path for o in COMMON_OPTIONS}
    lines = [
        "# Options",
        "",
        "*Generated from the option schema (`viapath.options.Option`): each option is defined once, with its "
        "default, unit and bounds, and the scenario file, the command line (`-o NAME=VALUE`), the ROS 2 "
        "parameters and `viapath planners NAME` all read that definition.*",
        "",
        "Set a planner option in a scenario (`planner: {name: viapath, horizon_s: 8}`, a group nests: "
        "`weights: {k2: 0.01}`), on the command line (`viapath run paper-front -o horizon_s=8 -o weights.k2=0.01`) "
        "or as a ROS 2 parameter (`planner.horizon_s`, `planner.weights.k2`). A value outside its bounds is an "
        "error naming the option.",
        "",
        "Planners that come with an extra (navground's `nav-*` with `navground`) or from a plug-in package are "
        "listed when they are installed where the site is built.",
        "",
        "## Options every planner has",
        "",
        _option_table(COMMON_OPTIONS),
    ]
    names = available_planners()
    for name in sorted(names, key=lambda n: (n != "viapath", n)):  # the paper's planner first
        cls = planner_class(name)
        own = [o for o in cls.options if o.path not in common]
        doc = (cls.__doc__ or "").strip().splitlines()
        lines += [f"## Planner `{name}`", "", doc[0] if doc else "", ""]
        lines += [_option_table(own) if own else "No options beyond the common ones.\n"]
    lines += [
        "## The shield",
        "",
        "On the command line `viapath run --shield on|off --shield-mode MODE` (and `viapath bench --shield "
        "on|off|friendly`); in Python `run_episode(..., shield_options={...})`; on the ROS 2 node under `shield.`.",
        "",
        _option_table(SHIELD_OPTIONS),
        "## The robot",
        "",
        "In a scenario under `robot:` (`speed`, `radius`) and `robot.limits:`; on the ROS 2 node by these names.",
        "",
        _option_table([*ROBOT_OPTIONS, *LIMITS_OPTIONS]),
        "## Subgoals",
        "",
        "In a scenario under `subgoals:`.",
        "",
        _option_table(SUBGOAL_OPTIONS),
    ]
    return "\n".join(lines)


# --- the scenario file -----------------------------------------------------------------------------


def _type_name(annotation: Any) -> str:
    """A readable type: ``[x, y]`` for a point, ``list of ...``, ``A or B``; models by name."""
    from pydantic import BaseModel

    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin is typing.Annotated:
        return _type_name(args[0])
    if annotation is type(None):
        return "null"
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation.__name__
    if isinstance(annotation, type):
        return {"float": "number", "int": "integer", "str": "text", "bool": "true/false"}.get(
            annotation.__name__, annotation.__name__
        )
    if origin is tuple:
        if len(args) == 2 and all(_type_name(a) == "number" for a in args):
            return "[x, y]"
        if len(args) == 2 and args[1] is Ellipsis:
            return f"list of {_type_name(args[0])}"
        return "[" + ", ".join(_type_name(a) for a in args) + "]"
    if origin is list:
        return f"list of {_type_name(args[0])}"
    if origin is dict:
        return "mapping"
    if origin is typing.Literal:
        return " or ".join(f"`{a}`" for a in args)
    if args and (origin is typing.Union or str(origin) == "<class 'types.UnionType'>"):
        return " or ".join(dict.fromkeys(_type_name(a) for a in args))
    return str(annotation).replace("typing.", "")


def _constraints(field: Any) -> str:
    parts = []
    for item in field.metadata:
        for key, symbol in (("gt", ">"), ("ge", "≥"), ("lt", "<"), ("le", "≤"), ("min_length", "min items")):
            value = getattr(item, key, None)
            if value is not None:
                parts.append(f"{symbol} {value}")
    return ", ".join(parts)


def _models_in(annotation: Any) -> list[Any]:
    """The viapath models inside an annotation, however deep (lists, unions, Annotated, tagged unions)."""
    from pydantic import BaseModel

    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation] if annotation.__module__.startswith("viapath") else []
    return [model for arg in typing.get_args(annotation) for model in _models_in(arg)]


def _field_comments(model: Any) -> dict[str, str]:
    """The comment at the end of each field's line in the model's source (``start_time_s: ... = 0.0  # ...``):
    the code's own words for a field without a description."""
    import inspect
    import re

    try:
        source = inspect.getsource(model)
    except (OSError, TypeError):  # a model made at run time has no source
        return {}
    return {m.group(1): m.group(2).strip() for m in re.finditer(r"^\s+(\w+)\s*:[^#\n]*#\s*(.+)$", source, flags=re.M)}


def _model_section(model: Any, key: str, seen: set) -> list[str]:
    if model in seen:
        return []
    seen.add(model)
    doc = " ".join((model.__doc__ or "").split())
    out = [f"## `{key}`: {model.__name__}", "", doc, "", "| field | type | default | bounds | description |"]
    out.append("|---|---|---|---|---|")
    nested: list[tuple[Any, str]] = []
    comments = _field_comments(model)
    for name, field in model.model_fields.items():
        if field.is_required():
            default = "required"
        elif field.default_factory is not None:
            made = field.default_factory()  # type: ignore[call-arg]
            default = (
                "see below"
                if isinstance(field.annotation, type)
                else f"`{_value(made) if made else '[]' if isinstance(made, list) else '{}'}`"
            )
        else:
            default = f"`{_cell(_value(field.default))}`"
        out.append(
            f"| `{name}` | {_cell(_type_name(field.annotation))} | {default} | {_cell(_constraints(field))} | "
            f"{_cell(field.description or comments.get(name, ''))} |"
        )
        nested += [(inner, f"{key}.{name}") for inner in _models_in(field.annotation)]
    out.append("")
    for inner, where in nested:
        out += _model_section(inner, where, seen)
    return out


def scenario_page() -> str:
    from viapath.scenarios import Scenario, builtin_names

    lines = [
        "# Scenario file",
        "",
        "*Generated from the pydantic models of `viapath.scenarios.models`.*",
        "",
        "A scenario is a YAML file (or a built-in name). Unknown keys are errors, and so is a NaN, an infinity "
        "or a value outside its bounds: the message names the file, the field and what was expected. Lengths "
        "are in metres, times in seconds, speeds in m/s, angles in radians. A planner's options go in "
        "`planner:` beside its `name` (see [Options](options.md)); the laser chain's in `perception.options`.",
        "",
        "Built-in scenarios: " + ", ".join(f"`{n}`" for n in builtin_names()) + ".",
        "",
    ]
    lines += _model_section(Scenario, "scenario", set())
    return "\n".join(lines) + "\n"


# --- ROS 2 -----------------------------------------------------------------------------------------


def ros2_page() -> str:
    from viapath.ros2.settings import all_options

    options = all_options("viapath")
    topics = [o for o in options if o.name.endswith("topic") or o.name.endswith("_service")]
    lines = [
        "# ROS 2 node",
        "",
        "*Generated from the node's parameter schema (`viapath.ros2.settings`), which includes the planner's "
        "option schema under `planner.` and the shield's under `shield.`.*",
        "",
        "`viapath ros2 params FILE` writes every parameter at its default with unit and bounds; "
        "`viapath ros2 node --params-file FILE` (or `viapath ros2 nav2 ...`) reads it. A bad value is refused "
        "at start, naming the parameter, and the node does not drive.",
        "",
        "## Topics",
        "",
        "Each topic's name is a parameter; the table shows the default name. Besides these the node reads "
        "`/clock` (with `use_sim_time`) and, as Nav2's controller, `/tf` and `/tf_static`, serves the action "
        "`follow_path` (`nav2_msgs/action/FollowPath`) and answers the local costmap's clearing service.",
        "",
        "| parameter | default name | what |",
        "|---|---|---|",
        *(f"| `{o.name}` | `{_cell(_value(o.default))}` | {_cell(o.help)} |" for o in topics),
        "",
        "## Diagnostics",
        "",
        "The node publishes one `diagnostic_msgs/DiagnosticArray` per cycle on `status_topic`, and the same array on "
        "`diagnostics_topic` (`/diagnostics`, where `rqt_robot_monitor` and `diagnostic_aggregator` look) once a "
        "second and at once when the way's state changes. Each status is named `NODE: PART` and carries its "
        "values as key/values.",
        "",
        "| status | level | message | key/values |",
        "|---|---|---|---|",
        "| `planner` | OK driving or at the goal; WARN degraded (a scanner silent) or waiting (no path, inactive); "
        "ERROR braking or stopped for a fault | the mode and the reasons | mode, reasons, plan status, speed, "
        "via points, tracks, cycle and plan times, events |",
        "| `way` | WARN while static geometry (a closed door, a wall across the corridor) closes the way to the "
        "subgoal and the robot waits short of it (the plan's status `blocked`, also when the guard brakes it); OK "
        "otherwise | `blocked: static geometry closes the way 1.20 m ahead; the robot waits at (3.10, 0.00) m in "
        "odom`, or `the way is open` | `blocked` (1 or 0), `wait_x_m`, `wait_y_m` (where the robot waits, "
        "odometry frame), `blocked_for_s` |",
        "| `shield` | OK | — | the shield's verdict of the cycle |",
        "| `scanner NAME` | OK receiving; WARN silent or no scan yet | the state | good and refused scans "
        "(by reason), the last problem, the invalid fraction, the mount's source |",
        "| `odometry` | OK fresh; WARN stale or a fault | the state | refused messages (by reason), the last "
        "problem |",
        "| `timing` | OK | — | the cycle time, its median and 99th percentile over the last 100 cycles |",
        "",
        "The way's state is the one `viapath run --json` counts as `blocked_s` (and the bench table as "
        "*blocked*); Nav2's FollowPath feedback has no field for it, so as Nav2's controller the node says it "
        "here too, while the goal runs (its progress check ends a goal that waits longer than "
        "`progress_patience_s` with FAILED_TO_MAKE_PROGRESS).",
        "",
        "## Parameters",
        "",
        _option_table(options),
    ]
    return "\n".join(lines)


# --- Python API ------------------------------------------------------------------------------------


def api_pages() -> dict[str, str]:
    pages = {}
    index = ["# Python API", "", "*Rendered from the docstrings of the stable public modules.*", ""]
    for module, title, line in API_MODULES:
        slug = module.removeprefix("viapath.").replace(".", "-")
        pages[f"reference/api/{slug}.md"] = f"# {title}: `{module}`\n\n::: {module}\n"
        index.append(f"* [{title}]({slug}.md) (`{module}`): {line}")
    pages["reference/api/index.md"] = "\n".join(index) + "\n"
    return pages


def pages() -> dict[str, str]:
    return {
        "reference/cli.md": cli_page(),
        "reference/options.md": options_page(),
        "reference/scenario.md": scenario_page(),
        "reference/ros2.md": ros2_page(),
        **api_pages(),
    }


def on_files(files: Any, config: Any) -> Any:
    from mkdocs.structure.files import File  # imported here: the page functions above run without mkdocs (tests)

    for uri, content in pages().items():
        files.append(File.generated(config, uri, content=content))
    return files


if __name__ == "__main__":  # print the generated pages (to read them without building the site)
    for uri, content in pages().items():
        print(f"===== {uri}\n{content}")
