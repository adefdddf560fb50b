"""``viapath scenarios`` and ``viapath planners [NAME]``: what can be run, and each planner's options."""

from __future__ import annotations

import json
from typing import Any

import typer
from rich.markup import escape
from rich.table import Table

from viapath.cli.common import console, fail


def scenarios() -> None:
    """List the built-in scenarios."""
    from viapath.scenarios import builtin_names, load_scenario

    table = Table(title="built-in scenarios (viapath run NAME)")
    table.add_column("name", style="bold")
    table.add_column("obstacles", justify="right")
    table.add_column("description")
    for name in builtin_names():
        spec = load_scenario(name)
        table.add_row(name, str(len(spec.obstacles)), " ".join(spec.description.split()))
    console.print(table)


def planners(
    name: str | None = typer.Argument(None, help="A planner: list its options with defaults, units and bounds."),
    as_json: bool = typer.Option(False, "--json", help="Print the options as JSON."),
) -> None:
    """List the registered planners, or one planner's options."""
    from viapath.planning import available_planners, planner_class

    if name is None:
        for planner in available_planners():
            doc = (planner_class(planner).__doc__ or "").strip().splitlines()
            console.print(f"[bold]{planner}[/]: {doc[0] if doc else ''}")
        return
    if name not in available_planners():
        fail(f"unknown planner {name!r}; available: {', '.join(available_planners())}")
    schema = planner_class(name).options
    # What an option's default resolves to on this machine (viapath's arithmetic: numpy or compiled).
    resolved: dict[str, Any] = getattr(planner_class(name), "resolved_defaults", dict)()
    if as_json:
        print(
            json.dumps(
                [_option_json(o) | ({"resolved": resolved[o.path]} if o.path in resolved else {}) for o in schema]
            )
        )
        return
    console.print(
        f"[bold]{name}[/] options (scenario: planner: {{name: {name}, OPTION: VALUE}}; "
        "command line: --option NAME=VALUE)"
    )
    for o in schema:
        default = "[" + ", ".join(f"{v:g}" for v in o.default) + "]" if isinstance(o.default, tuple) else o.default
        console.print(
            f"  [bold]{o.path}[/] = {default}"
            + (f" {o.unit}" if o.unit else "")
            + (f" (here: {resolved[o.path]})" if o.path in resolved else ""),
            highlight=False,
        )
        console.print(f"      {escape(o.describe())}", highlight=False)


def _option_json(o) -> dict:
    return {
        "name": o.path,
        "default": o.default,
        "unit": o.unit,
        "minimum": o.minimum,
        "maximum": o.maximum,
        "choices": o.choices,
        "help": o.help,
    }
