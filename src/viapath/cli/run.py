"""``viapath run SCENARIO``: one episode in the simulator, its metrics, and optionally a figure, a
trace, an animation or a Foxglove view of it."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from viapath.cli.common import (
    ANIMATION_SUFFIXES,
    PLOT_SUFFIXES,
    caused_by_interrupt,
    check_noise,
    check_output,
    compiled_or_plain,
    console,
    errors,
    fail,
    start_compiling,
)
from viapath.cli.extras import animation_progress, print_warnings
from viapath.io.jsonable import dumps as json_dumps

Scenario = Annotated[str, typer.Argument(help="Built-in scenario name (see `viapath scenarios`) or a YAML file.")]
Planner = Annotated[str | None, typer.Option("--planner", help="Planner name (default: the scenario's).")]
Perception = Annotated[
    str | None, typer.Option("--perception", help="oracle | tracked | laser (default: the scenario's).")
]
Seed = Annotated[int | None, typer.Option("--seed", help="Random seed (default: the scenario's).")]
PositionNoise = Annotated[
    float | None,
    typer.Option("--position-noise", help="Oracle position noise σ in m (mode tracked: the detections' σ)."),
]
VelocityNoise = Annotated[float | None, typer.Option("--velocity-noise", help="Oracle velocity noise σ in m/s.")]
AsJson = Annotated[bool, typer.Option("--json", help="Print one JSON object of metrics.")]
Plot = Annotated[Path | None, typer.Option("--plot", help="Write a figure (PNG/PDF/SVG) of the episode.")]
Trace = Annotated[Path | None, typer.Option("--trace", help="Write the per-step trace as CSV.")]
Animate = Annotated[Path | None, typer.Option("--animate", help="Write an animation (GIF, or MP4 with ffmpeg).")]
FrameStride = Annotated[
    int | None,
    typer.Option(
        "--frame-stride", help="With --animate: one frame every N steps (default: enough to keep at most 400 frames)."
    ),
]
Options = Annotated[
    list[str],
    typer.Option(
        "--option",
        "-o",
        metavar="NAME=VALUE",
        help="Set a planner option (repeatable); `viapath planners NAME` lists them.",
    ),
]
Weights = Annotated[
    str | None,
    typer.Option(
        "--weights",
        help="A weights preset (`viapath presets`) or preset "
        "YAML file for the viapath planner; --option values win over it.",
    ),
]
Mcap = Annotated[Path | None, typer.Option("--mcap", help="Write the run as MCAP for Foxglove (extra viz).")]
Force = Annotated[bool, typer.Option("--force", help="Overwrite an existing --mcap file.")]
Live = Annotated[bool, typer.Option("--live", help="Serve the run live to Foxglove on 127.0.0.1 (extra viz).")]
Rate = Annotated[float, typer.Option("--rate", help="With --live: simulated seconds per wall-clock second.")]
Port = Annotated[int, typer.Option("--port", help="With --live: the WebSocket port (0: any free one).")]
Shield = Annotated[
    str | None,
    typer.Option(
        "--shield",
        help="on | off: passive-safety shield on the planner's commands (default: on for viapath, off for the others).",
    ),
]
ShieldMode = Annotated[str, typer.Option("--shield-mode", help="passive | passive-friendly.")]


def run(
    scenario: Scenario,
    planner: Planner = None,
    perception: Perception = None,
    seed: Seed = None,
    position_noise: PositionNoise = None,
    velocity_noise: VelocityNoise = None,
    as_json: AsJson = False,
    plot: Plot = None,
    trace: Trace = None,
    animate: Animate = None,
    frame_stride: FrameStride = None,
    option: Options = [],  # noqa: B006 - typer's default for a repeatable option, never mutated
    weights: Weights = None,
    mcap: Mcap = None,
    force: Force = False,
    live: Live = False,
    rate: Rate = 1.0,
    port: Port = 8765,
    shield: Shield = None,
    shield_mode: ShieldMode = "passive",
) -> None:
    """Run one scenario in the simulator and report its metrics."""
    plain = compiled_or_plain()  # before anything makes a compiled step
    from viapath.scenarios import ScenarioError, load_scenario

    _check_arguments(plot, animate, trace, position_noise, velocity_noise, frame_stride, seed, perception)
    _check_shield(shield, shield_mode)
    try:
        spec = load_scenario(scenario)
    except ScenarioError as error:
        fail(str(error))
    print_warnings(spec, errors)
    planner_name, overrides = _planner_and_options(spec, scenario, planner, option, weights)
    views_options = {"mcap": mcap, "force": force, "live": live, "rate": rate, "port": port}
    episode_options = {
        "perception": perception,
        "seed": seed,
        "position_noise_m": position_noise,
        "velocity_noise_mps": velocity_noise,
        "record_perceived": plot is not None or animate is not None,
        "shield": None if shield is None else shield == "on",
        "shield_options": {"mode": shield_mode},
    }
    start_compiling(plain)
    episode = _simulate(spec, scenario, planner_name, overrides, views_options, episode_options)
    failed = _write_outputs(episode, plot, trace, animate, frame_stride)
    # The metrics are printed whatever became of the outputs: the episode ran (it may have taken hours).
    if as_json:
        print(json_dumps(episode.metrics))
    else:
        _print_metrics(episode.metrics)
        for label, file in (("plot", plot), ("trace", trace), ("animation", animate), ("mcap", mcap)):
            if file is not None and (failed is None or file != failed[0]):
                console.print(f"{label}: {file}")
    if failed is not None:
        fail(f"{failed[0]}: {failed[1]}")


def precompile() -> None:
    """Compile viapath's planner, shield and laser chain for this machine now (about a minute of CPU, once per
    version; waits for a compilation running in the background), so that the next runs load them."""
    from viapath.precompile import compile_now

    code = compile_now(lambda text: errors.print(text, highlight=False, soft_wrap=True, markup=False))
    if code:
        raise typer.Exit(code)


def _check_arguments(plot, animate, trace, position_noise, velocity_noise, frame_stride, seed, perception) -> None:
    check_output(plot, PLOT_SUFFIXES, "--plot")
    check_output(animate, ANIMATION_SUFFIXES, "--animate")
    check_output(trace, (".csv",), "--trace")
    check_noise(position_noise, "--position-noise")
    check_noise(velocity_noise, "--velocity-noise")
    if frame_stride is not None and frame_stride < 1:
        fail(f"--frame-stride: expected an integer >= 1, found {frame_stride}")
    if seed is not None and seed < 0:
        fail(f"--seed: expected an integer >= 0, found {seed}")
    from viapath.perception.modes import PERCEPTION_MODES

    if perception is not None and perception not in PERCEPTION_MODES:
        fail(f"--perception: expected {' or '.join(repr(m) for m in PERCEPTION_MODES.ordered())}, found {perception!r}")


def _check_shield(shield: str | None, shield_mode: str) -> None:
    if shield not in (None, "on", "off"):
        fail(f"--shield: expected 'on' or 'off', found {shield!r}")
    if shield_mode not in ("passive", "passive-friendly"):
        fail(f"--shield-mode: expected 'passive' or 'passive-friendly', found {shield_mode!r}")


def _planner_and_options(spec, scenario: str, planner: str | None, option: list[str], weights: str | None):
    """The planner that runs and the options given on the command line (--weights, then --option)."""
    from viapath.planning import available_planners

    planner_name = planner or spec.planner.name
    if planner_name not in available_planners():
        where = "--planner" if planner else f"{scenario}: planner.name"
        fail(f"{where}: unknown planner {planner_name!r}; available: {', '.join(available_planners())}")
    overrides = parse_options(option, planner_name)
    if weights is not None:
        from viapath.presets import PresetError, preset_values

        try:
            overrides = {**preset_values(weights, planner_name), **overrides}
        except PresetError as error:
            fail(f"--weights: {error}")
    if planner_name != spec.planner.name and spec.planner.given():
        errors.print(
            f"note: {scenario}'s planner block configures {spec.planner.name!r}; {planner_name!r} runs with "
            "its own defaults (and any --option)",
            highlight=False,
        )
    return planner_name, overrides


def _simulate(spec, scenario: str, planner_name: str, overrides: dict, views_options: dict, episode_options: dict):
    """The episode, shown live or recorded by the views asked for; exit 2 on a bad run, 130 on Ctrl-C."""
    from viapath.sim.loop import run_episode
    from viapath.viz.foxglove import ViewError, open_views

    try:
        views = open_views(
            spec, planner_name, announce=lambda text: errors.print(text, highlight=False), **views_options
        )
        with views:
            return run_episode(
                spec,
                planner=planner_name,
                planner_overrides={**overrides, **(views.planner_overrides or {})},
                on_step=views.on_step,
                **episode_options,
            )
    except ViewError as error:
        fail(str(error))
    except (ValueError, RuntimeError, FileNotFoundError) as error:
        fail(f"{scenario}: {error}")
    except KeyboardInterrupt:
        fail("interrupted", code=130)
    except SystemError as error:  # a Ctrl-C that landed in a compiled call back into Python arrives wrapped
        if not caused_by_interrupt(error):
            raise
        fail("interrupted", code=130)


def _write_outputs(
    episode, plot: Path | None, trace: Path | None, animate: Path | None, frame_stride
) -> tuple[Path, str] | None:
    """Write the outputs asked for; (the animation's file, why) if it could not be written, else None."""
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
        except MemoryError:
            return animate, "out of memory while drawing the animation (raise --frame-stride)"
        except (RuntimeError, ValueError, OSError) as error:
            return animate, str(error)
        finally:
            done()
    return None


def _print_metrics(metrics: dict) -> None:
    table = Table(title=f"{metrics['scenario']} — {metrics['planner']} ({metrics['perception']})", show_header=False)
    table.add_column("metric", style="bold")
    table.add_column("value", justify="right")
    for key, value in metrics.items():
        if key in ("scenario", "planner", "perception"):
            continue
        table.add_row(key, _metric_text(key, value))
    console.print(table)


def _metric_text(key: str, value: Any) -> str:
    if isinstance(value, bool):
        return (
            ("[red]yes[/]" if value else "[green]no[/]") if "collision" in key else ("yes" if value else "[red]no[/]")
        )
    if isinstance(value, float):
        return f"{value:.3f}"
    if value is None:
        return "—"
    return str(value)


def parse_options(assignments: list[str], planner_name: str) -> dict:
    """``--option NAME=VALUE`` items, validated by the planner's option schema (exit 2 on a bad one)."""
    from viapath.options import OptionError
    from viapath.planning import planner_options

    schema = planner_options(planner_name)
    values = {}
    try:
        for text in assignments:
            name, value = parse_assignment(text)
            values[name] = value
        values = schema.retired.drop(values, where="--option", separator=" ")  # read, warned about, left out
        values = schema.current_names(values, where="--option")  # an option's former name read as its name now
        schema.validate(values, where="--option")
    except OptionError as error:
        fail("\n".join(f"{field.replace('--option.', '--option ')}: {message}" for field, message in error.errors))
    return schema.nest(values)


def parse_assignment(text: str) -> tuple[str, Any]:
    """``NAME=VALUE`` from the command line (VALUE parsed as YAML: numbers, true/false, lists)."""
    from viapath.io.safe_read import InputError, load_yaml, short_repr
    from viapath.options import OptionError

    name, sep, raw = text.partition("=")
    name = name.strip()
    if not sep or not name:
        raise OptionError([("", f"expected NAME=VALUE, found {short_repr(text)}")])
    try:
        value = load_yaml(raw, name)
    except InputError as error:
        if "not valid YAML" not in str(error):
            raise OptionError([(name, str(error).split(": ", 1)[-1].replace("(top level): ", ""))]) from None
        value = raw
    return name, value
