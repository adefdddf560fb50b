"""Small CLI pieces: ``viapath --version``, boolean flags shown
without a ``<bool>`` type in the help (they take no value: ``--json``, not ``--json true``), scenario
warnings before a run, and a progress bar while an animation is written."""

from __future__ import annotations

from collections.abc import Callable

import typer


def _plain_flags() -> None:
    """typer's rich help prints ``<bool>`` beside on/off flags, which reads as if they took a value."""
    try:
        from typer.core import TyperOption
    except ImportError:  # pragma: no cover - another typer layout
        return
    if getattr(TyperOption.display_type_rich, "__viapath_plain__", False):
        return
    original = TyperOption.display_type_rich

    def display_type_rich(self, ctx):
        if getattr(self, "is_flag", False) and self.metavar is None:
            return None
        return original(self, ctx)

    setattr(display_type_rich, "__viapath_plain__", True)  # noqa: B010 - a mark on a function object
    setattr(TyperOption, "display_type_rich", display_type_rich)  # noqa: B010 - replacing typer's method


def _version(value: bool) -> None:
    if value:
        from viapath.bench.identity import viapath_version

        typer.echo(f"viapath {viapath_version()}")
        raise typer.Exit()


def install(app: typer.Typer) -> None:
    _plain_flags()

    @app.callback()
    def _main(
        version: bool | None = typer.Option(
            None, "--version", callback=_version, is_eager=True, help="Print the viapath version and exit."
        ),
    ) -> None:
        """Follow a designated path and avoid moving obstacles by choosing speed as well as direction."""


def print_warnings(scenario, console) -> None:
    from rich.markup import escape

    from viapath.sim.checks import scenario_warnings

    for warning in scenario_warnings(scenario):
        console.print(f"[bold yellow]warning:[/] {escape(warning)}", highlight=False, soft_wrap=True)


def animation_progress(console) -> tuple[Callable[[int, int], None], Callable[[], None]]:
    """A ``progress_callback(frame, total)`` for matplotlib's ``Animation.save`` and a ``close``."""
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    bar = Progress(
        TextColumn("writing frames"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("elapsed"),
        TimeElapsedColumn(),
        TextColumn("/"),
        TimeRemainingColumn(),
        TextColumn("left"),
        console=console,
        transient=True,
    )
    state: dict = {}

    def update(frame: int, total: int) -> None:
        if "job" not in state:
            bar.start()
            state["job"] = bar.add_task("frames", total=total)
        bar.update(state["job"], completed=frame + 1)

    def close() -> None:
        if "job" in state:
            bar.stop()

    return update, close
