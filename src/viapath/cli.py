"""Command-line interface: ``viapath run SCENARIO``, ``viapath scenarios`` and friends (DESIGN §4)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from viapath.io.jsonable import dumps as json_dumps

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Follow a designated path and avoid moving obstacles by choosing speed as well as direction.",
)
console = Console()
errors = Console(stderr=True)

_PLOT_SUFFIXES = {".png", ".pdf", ".svg"}
_ANIMATION_SUFFIXES = {".gif", ".mp4"}


def _fail(message: str, code: int = 2) -> None:
    errors.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def _caused_by_interrupt(error: BaseException) -> bool:
    """Whether a KeyboardInterrupt is behind ``error`` (numba turns one raised while a compiled kernel calls
    back into Python, e.g. to unpickle a constant, into a chain of SystemErrors)."""
    seen = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, KeyboardInterrupt):
            return True
        seen.add(id(error))
        error = error.__cause__ or error.__context__
    return False


def _check_output(file: Path | None, suffixes: set[str], option: str) -> None:
    if file is None:
        return
    if file.suffix.lower() not in suffixes:
        _fail(f"{option} {file}: expected a file ending in {', '.join(sorted(suffixes))}")
    if not file.parent.exists():
        _fail(f"{option} {file}: folder {file.parent} does not exist")


def _check_noise(value: float | None, option: str) -> None:
    if value is not None and (not math.isfinite(value) or value < 0):
        _fail(f"{option}: expected a finite number >= 0, found {value}")


@app.command()
def run(
    scenario: str = typer.Argument(..., help="Built-in scenario name (see `viapath scenarios`) or a YAML file."),
    planner: str | None = typer.Option(None, "--planner", help="Planner name (default: the scenario's)."),
    perception: str | None = typer.Option(None, "--perception", help="oracle | laser (default: the scenario's)."),
    seed: int | None = typer.Option(None, "--seed", help="Random seed (default: the scenario's)."),
    position_noise: float | None = typer.Option(None, "--position-noise", help="Oracle position noise σ in m."),
    velocity_noise: float | None = typer.Option(None, "--velocity-noise", help="Oracle velocity noise σ in m/s."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object of metrics."),
    plot: Path | None = typer.Option(None, "--plot", help="Write a figure (PNG/PDF/SVG) of the episode."),
    trace: Path | None = typer.Option(None, "--trace", help="Write the per-step trace as CSV."),
    animate: Path | None = typer.Option(None, "--animate", help="Write an animation (GIF, or MP4 with ffmpeg)."),
    frame_stride: int | None = typer.Option(
        None,
        "--frame-stride",
        help="With --animate: one frame every N steps (default: enough to keep at most 400 frames).",
    ),
    option: list[str] = typer.Option(
        [],
        "--option",
        "-o",
        metavar="NAME=VALUE",
        help="Set a planner option (repeatable); `viapath planners NAME` lists them.",
    ),
    weights: str | None = typer.Option(
        None,
        "--weights",
        help="A weights preset (`viapath presets`) or preset "
        "YAML file for the viapath planner; --option values win over it.",
    ),
    mcap: Path | None = typer.Option(None, "--mcap", help="Write the run as MCAP for Foxglove (extra viz)."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing --mcap file."),
    live: bool = typer.Option(False, "--live", help="Serve the run live to Foxglove on 127.0.0.1 (extra viz)."),
    rate: float = typer.Option(1.0, "--rate", help="With --live: simulated seconds per wall-clock second."),
    port: int = typer.Option(8765, "--port", help="With --live: the WebSocket port (0: any free one)."),
    shield: str | None = typer.Option(
        None,
        "--shield",
        help="on | off: passive-safety shield on the planner's commands (default: on for viapath, off for the others).",
    ),
    shield_mode: str = typer.Option("passive", "--shield-mode", help="passive | passive-friendly."),
) -> None:
    """Run one scenario in the simulator and report its metrics."""
    from viapath.planning import available_planners
    from viapath.scenarios import ScenarioError, load_scenario
    from viapath.sim.loop import run_episode

    _check_output(plot, _PLOT_SUFFIXES, "--plot")
    _check_output(animate, _ANIMATION_SUFFIXES, "--animate")
    _check_output(trace, {".csv"}, "--trace")
    _check_noise(position_noise, "--position-noise")
    _check_noise(velocity_noise, "--velocity-noise")
    if frame_stride is not None and frame_stride < 1:
        _fail(f"--frame-stride: expected an integer >= 1, found {frame_stride}")
    if seed is not None and seed < 0:
        _fail(f"--seed: expected an integer >= 0, found {seed}")
    from viapath.perception.modes import PERCEPTION_MODES

    if perception is not None and perception not in PERCEPTION_MODES:
        _fail(
            f"--perception: expected {' or '.join(repr(m) for m in PERCEPTION_MODES.ordered())}, found {perception!r}"
        )
    if shield not in (None, "on", "off"):
        _fail(f"--shield: expected 'on' or 'off', found {shield!r}")
    if shield_mode not in ("passive", "passive-friendly"):
        _fail(f"--shield-mode: expected 'passive' or 'passive-friendly', found {shield_mode!r}")
    try:
        spec = load_scenario(scenario)
    except ScenarioError as error:
        _fail(str(error))
    from viapath.cli_extras import animation_progress, print_warnings

    print_warnings(spec, errors)
    planner_name = planner or spec.planner.name
    if planner_name not in available_planners():
        where = "--planner" if planner else f"{scenario}: planner.name"
        _fail(f"{where}: unknown planner {planner_name!r}; available: {', '.join(available_planners())}")
    overrides = parse_options(option, planner_name)
    if weights is not None:
        from viapath.presets import PresetError, preset_values

        try:
            overrides = {**preset_values(weights, planner_name), **overrides}
        except PresetError as error:
            _fail(f"--weights: {error}")
    if planner_name != spec.planner.name and spec.planner.given():
        errors.print(
            f"note: {scenario}'s planner block configures {spec.planner.name!r}; {planner_name!r} runs with "
            "its own defaults (and any --option)",
            highlight=False,
        )
    from viapath.viz.foxglove import ViewError, open_views

    try:
        views = open_views(
            spec,
            planner_name,
            mcap=mcap,
            force=force,
            live=live,
            rate=rate,
            port=port,
            announce=lambda text: errors.print(text, highlight=False),
        )
        with views:
            episode = run_episode(
                spec,
                planner=planner_name,
                perception=perception,
                seed=seed,
                position_noise_m=position_noise,
                velocity_noise_mps=velocity_noise,
                record_perceived=plot is not None or animate is not None,
                planner_overrides={**overrides, **(views.planner_overrides or {})},
                on_step=views.on_step,
                shield=None if shield is None else shield == "on",
                shield_options={"mode": shield_mode},
            )
    except ViewError as error:
        _fail(str(error))
    except (ValueError, RuntimeError, FileNotFoundError) as error:
        _fail(f"{scenario}: {error}")
    except KeyboardInterrupt:
        _fail("interrupted", code=130)
    except SystemError as error:  # a Ctrl-C that landed in numba's call back into Python arrives wrapped
        if not _caused_by_interrupt(error):
            raise
        _fail("interrupted", code=130)

    if plot is not None:
        from viapath.viz.plot import plot_episode

        plot_episode(episode, plot)
    if trace is not None:
        from viapath.io.trace import write_trace_csv

        write_trace_csv(episode.trace, trace)
    if animate is not None:
        from viapath.viz.animate import animate_episode

        progress, done = animation_progress(errors)
        try:
            animate_episode(episode, animate, progress=progress, stride=frame_stride)
        except (RuntimeError, ValueError) as error:
            _fail(str(error))
        finally:
            done()

    if as_json:
        print(json_dumps(episode.metrics))
        return
    _print_metrics(episode.metrics)
    for label, file in (("plot", plot), ("trace", trace), ("animation", animate), ("mcap", mcap)):
        if file is not None:
            console.print(f"{label}: {file}")


def _print_metrics(metrics: dict) -> None:
    table = Table(title=f"{metrics['scenario']} — {metrics['planner']} ({metrics['perception']})", show_header=False)
    table.add_column("metric", style="bold")
    table.add_column("value", justify="right")
    for key, value in metrics.items():
        if key in ("scenario", "planner", "perception"):
            continue
        if isinstance(value, bool):
            text = (
                ("[red]yes[/]" if value else "[green]no[/]")
                if "collision" in key
                else ("yes" if value else "[red]no[/]")
            )
        elif isinstance(value, float):
            text = f"{value:.3f}"
        elif value is None:
            text = "—"
        else:
            text = str(value)
        table.add_row(key, text)
    console.print(table)


@app.command()
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


def parse_options(assignments: list[str], planner_name: str) -> dict:
    """``--option NAME=VALUE`` items, validated by the planner's option schema (exit 2 on a bad one)."""
    from viapath.options import OptionError
    from viapath.planning import planner_options

    schema = planner_options(planner_name)
    values = {}
    try:
        for text in assignments:
            name, value = schema.parse_assignment(text)
            values[name] = value
        schema.validate(values, where="--option")
    except OptionError as error:
        _fail("\n".join(f"{field.replace('--option.', '--option ')}: {message}" for field, message in error.errors))
    return schema.nest(values)


@app.command()
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
        _fail(f"unknown planner {name!r}; available: {', '.join(available_planners())}")
    schema = planner_class(name).options
    # What an option's default resolves to on this machine (viapath's backend: numpy or numba).
    resolved = getattr(planner_class(name), "resolved_defaults", dict)()
    if as_json:
        print(
            json.dumps(
                [
                    {
                        "name": o.path,
                        "default": o.default,
                        "unit": o.unit,
                        "minimum": o.minimum,
                        "maximum": o.maximum,
                        "choices": o.choices,
                        "help": o.help,
                    }
                    | ({"resolved": resolved[o.path]} if o.path in resolved else {})
                    for o in schema
                ]
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


def _register_plugins() -> None:
    """Commands that live beside their subsystem (laser scans, benchmark)."""
    import importlib

    for module in (
        "viapath.commands.scans",
        "viapath.bench.commands",
        "viapath.ros2.commands",
        "viapath.commands.tune",
    ):
        try:
            spec = importlib.util.find_spec(module)
        except ModuleNotFoundError:
            spec = None
        if spec is not None:
            importlib.import_module(module).register(app)


_register_plugins()
__import__("viapath.cli_extras").cli_extras.install(app)  # --version, plain flags


def main() -> None:  # pragma: no cover
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
