"""``viapath suite`` and ``viapath bench``: generate a scenario suite, run planners on one in parallel.

Errors are one plain ``error:`` line on stderr (exit 2); the benchmark runner is imported inside
the commands."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Annotated, NoReturn

import typer

from viapath.io.jsonable import dumps as json_dumps


def _fail(message: str) -> NoReturn:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def suite(
    name: str = typer.Argument(
        ...,
        help="suite name: mixed, crossing, head-on, overtaken, overtaking, multi, "
        "group, crowd, hallway, paper, static, slow-walker, eth-ucy, eth-ucy-react, eth-ucy-maps",
    ),
    count: int = typer.Option(200, "--count", "-n", help="number of scenarios"),
    seed: int = typer.Option(0, "--seed", help="same seed, same suite"),
    out: Path = typer.Option(..., "--out", help="folder to write the scenario YAML files to"),
) -> None:
    """Generate a scenario suite from a seed and write it as scenario YAML files."""
    from viapath.bench.suites import SuiteError, generate_suite, write_suite

    try:
        scenarios = generate_suite(name, count, seed)
        files = write_suite(scenarios, out)
    except (SuiteError, OSError) as error:
        _fail(str(error))
    typer.echo(f"wrote {len(files)} scenarios to {out}")


Suite = Annotated[str, typer.Argument(help="a folder of scenario YAML files, or a suite name (see 'viapath suite')")]
Planners = Annotated[str, typer.Option("--planners", "-p", help="comma-separated planner names")]
Workers = Annotated[int, typer.Option("--workers", "-w", help="parallel workers")]
Executor = Annotated[str, typer.Option("--executor", help="where episodes run: loky (local processes), dask or ray")]
Scheduler = Annotated[
    str | None, typer.Option("--scheduler", help="address of an existing dask scheduler or ray cluster")
]
Count = Annotated[int, typer.Option("--count", "-n", help="scenarios to generate when SUITE is a suite name")]
Seed = Annotated[int, typer.Option("--seed", help="suite and episode seed")]
Perception = Annotated[
    str, typer.Option("--perception", help="oracle, tracked (noisy detections through the tracker) or laser")
]
Plots = Annotated[bool, typer.Option("--plots/--no-plots", help="write rates.png and deviation_vs_time.png")]
AsJson = Annotated[bool, typer.Option("--json", help="print the per-planner table as JSON")]
McapFailures = Annotated[
    Path | None,
    typer.Option("--mcap-failures", help="write an MCAP (Foxglove) of each failed episode here (extra viz)"),
]
Shield = Annotated[
    str | None,
    typer.Option(
        "--shield",
        help="on | off | friendly: passive-safety shield "
        "(friendly: passive-friendly mode) for every planner; default: on "
        "for viapath, off for the others",
    ),
]
Force = Annotated[
    bool,
    typer.Option(
        "--force",
        help="use an --out folder written by another suite or configuration (its rows are kept, never reused)",
    ),
]
Weights = Annotated[
    str | None,
    typer.Option(
        "--weights",
        help="a weights preset (viapath presets) or preset "
        "YAML file for the viapath planner (enters the rows' options hash)",
    ),
]

EpisodeTimeLimit = Annotated[
    float,
    typer.Option(
        "--episode-time-limit",
        help="wall seconds an episode may take; one that takes longer is a failed episode (0: no limit)",
    ),
]


def bench(
    suite: Suite,
    planners: Planners = "viapath,follow,stop,dwa,vo",
    workers: Workers = 2,
    executor: Executor = "loky",
    scheduler: Scheduler = None,
    out: Path = typer.Option(..., "--out", help="results folder (episodes.csv, summary.md/json, plots)"),
    count: Count = 200,
    seed: Seed = 0,
    perception: Perception = "oracle",
    plots: Plots = True,
    as_json: AsJson = False,
    mcap_failures: McapFailures = None,
    shield: Shield = None,
    force: Force = False,
    weights: Weights = None,
    episode_time_limit: EpisodeTimeLimit = 600.0,
) -> None:
    """Run planners on a suite in parallel; write per-episode results, tables and plots.

    Exit code 0: every episode ran; 3: some episode crashed (listed; rerun to retry them) or a worker
    process died (the finished rows are kept); 2: bad input, or another bench is writing into --out;
    130: interrupted (Ctrl-C or SIGTERM; the finished rows are kept, rerun the same command to resume)."""
    names = [p.strip() for p in planners.split(",") if p.strip()]
    if not names:
        _fail("--planners is empty; give e.g. viapath,dwa,vo")
    if scheduler and executor == "loky":
        _fail("--scheduler needs --executor dask or ray")
    _check_failures_folder(mcap_failures)
    if not (math.isfinite(episode_time_limit) and episode_time_limit >= 0):
        _fail(f"--episode-time-limit: expected a number of seconds >= 0, found {episode_time_limit}")
    planner_options = _weights_options(weights, names)
    run_options = {
        "workers": workers,
        "executor": executor,
        "scheduler": scheduler,
        "perception": perception,
        "seed": seed,
        "progress": sys.stderr.isatty() and not as_json,
        "shield": shield,
        "force": force,
        "planner_options": planner_options,
        "episode_time_limit_s": episode_time_limit or None,
    }
    result, summary = _run_and_report(suite, names, out, count, plots, mcap_failures, run_options)
    _print_result(result, summary, out, as_json)


def _check_failures_folder(mcap_failures: Path | None) -> None:
    if mcap_failures is None:
        return
    from viapath.viz.foxglove import ViewError, check_failures_option

    try:
        check_failures_option(mcap_failures)
    except ViewError as error:
        _fail(str(error))


def _weights_options(weights: str | None, names: list[str]) -> dict | None:
    if weights is None:
        return None
    from viapath.presets import PresetError, preset_values

    if "viapath" not in names:
        _fail("--weights applies to the viapath planner, which is not in --planners")
    try:
        return {"viapath": preset_values(weights)}
    except PresetError as error:
        _fail(f"--weights: {error}")


def _run_and_report(suite, names, out: Path, count, plots, mcap_failures, run_options: dict):
    """Run the episodes and write the report; the exit codes of an interrupted or failed run."""
    from viapath.bench.report import write_report
    from viapath.bench.runner import (
        BenchError,
        BenchInterrupted,
        BenchWorkerLost,
        FolderBusy,
        load_suite,
        results_lock,
        run_bench,
        terminate_as_interrupt,
    )
    from viapath.bench.suites import SuiteError

    created = not out.exists()  # a run refused before any episode must leave no folder behind
    workers, executor = run_options["workers"], run_options["executor"]
    try:
        with terminate_as_interrupt(), results_lock(out):
            scenarios = load_suite(
                suite, out, count=count, seed=run_options["seed"], workers=workers if executor == "loky" else 1
            )
            result = run_bench(
                scenarios, names, out, note=lambda text: typer.echo(f"note: {text}", err=True), **run_options
            )
            summary = write_report(result["rows"], out, plots=plots, order=names)
            if mcap_failures is not None:
                from viapath.viz.foxglove import write_failure_mcaps

                write_failure_mcaps(
                    result["rows"],
                    scenarios,
                    mcap_failures,
                    progress=lambda text: typer.echo(f"mcap: {text}", err=True),
                )
    except BenchInterrupted as stopped:
        typer.echo(f"\n{stopped}; rerun the same command to resume ({stopped.total - stopped.finished} left)", err=True)
        raise typer.Exit(code=130) from None
    except BenchWorkerLost as lost:
        typer.echo(f"\n{lost}; rerun the same command to run the {lost.total - lost.finished} left", err=True)
        raise typer.Exit(code=3) from None
    except KeyboardInterrupt as interrupt:  # before or after the episodes (loading the suite, the report)
        typer.echo(
            f"\n{getattr(interrupt, 'reason', 'interrupted')}; rows already written are kept in {out / 'episodes.csv'}",
            err=True,
        )
        raise typer.Exit(code=130) from None
    except (BenchError, SuiteError, OSError) as error:
        if created and not (out / "episodes.csv").exists() and not isinstance(error, FolderBusy):
            import shutil

            shutil.rmtree(out, ignore_errors=True)
        _fail(str(error))
    return result, summary


def _print_result(result: dict, summary, out: Path, as_json: bool) -> None:
    """The per-planner table, and exit 3 when some episode crashed."""
    from viapath.bench.identity import crash_lines
    from viapath.bench.report import markdown_table

    crashed = crash_lines(result["rows"])
    if as_json:
        typer.echo(json_dumps(summary, indent=2))
    else:
        typer.echo(markdown_table(summary))
        typer.echo(
            f"\n{result['ran']} episodes run, {result['skipped']} already done, {result['wall_s']:.1f} s; results in {out}"
        )
    if crashed:
        typer.echo(
            f"\n{result['errors']} episode(s) crashed (not in the rates; rerun the same command to "
            "run them again):\n" + "\n".join(crashed),
            err=True,
        )
        raise typer.Exit(code=3)
