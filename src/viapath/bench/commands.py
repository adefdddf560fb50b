"""CLI commands of the benchmark: ``viapath suite`` and ``viapath bench`` (added by :func:`register`)."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from viapath.io.jsonable import dumps as json_dumps


def _fail(message: str) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def register(app: typer.Typer) -> None:
    """Add ``suite`` and ``bench`` to the viapath CLI."""

    @app.command("suite")
    def suite_command(
        name: str = typer.Argument(
            ...,
            help="suite name: mixed, crossing, head-on, overtaken, overtaking, multi, "
            "group, crowd, hallway, paper, static, slow-walker, eth-ucy, eth-ucy-react",
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

    @app.command("bench")
    def bench_command(
        suite: str = typer.Argument(..., help="a folder of scenario YAML files, or a suite name (see 'viapath suite')"),
        planners: str = typer.Option(
            "viapath,follow,stop,dwa,vo", "--planners", "-p", help="comma-separated planner names"
        ),
        workers: int = typer.Option(2, "--workers", "-w", help="parallel workers"),
        backend: str = typer.Option("loky", "--backend", help="loky (local processes), dask or ray"),
        scheduler: str | None = typer.Option(
            None, "--scheduler", help="address of an existing dask scheduler or ray cluster"
        ),
        out: Path = typer.Option(..., "--out", help="results folder (episodes.csv, summary.md/json, plots)"),
        count: int = typer.Option(200, "--count", "-n", help="scenarios to generate when SUITE is a suite name"),
        seed: int = typer.Option(0, "--seed", help="suite and episode seed"),
        perception: str = typer.Option("oracle", "--perception", help="oracle or laser"),
        plots: bool = typer.Option(True, "--plots/--no-plots", help="write rates.png and deviation_vs_time.png"),
        as_json: bool = typer.Option(False, "--json", help="print the per-planner table as JSON"),
        mcap_failures: Path | None = typer.Option(
            None, "--mcap-failures", help="write an MCAP (Foxglove) of each failed episode here (extra viz)"
        ),
        shield: str | None = typer.Option(
            None,
            "--shield",
            help="on | off | friendly: passive-safety shield "
            "(friendly: passive-friendly mode) for every planner; default: on "
            "for viapath, off for the others",
        ),
        force: bool = typer.Option(
            False,
            "--force",
            help="use an --out folder written by another suite or configuration (its rows are kept, never reused)",
        ),
        weights: str | None = typer.Option(
            None,
            "--weights",
            help="a weights preset (viapath presets) or preset "
            "YAML file for the viapath planner (enters the rows' options hash)",
        ),
    ) -> None:
        """Run planners on a suite in parallel; write per-episode results, tables and plots.

        Exit code 0: every episode ran; 3: some episode crashed (listed; rerun to retry them) or a worker
        process died (the finished rows are kept); 2: bad input, or another bench is writing into --out;
        130: interrupted (Ctrl-C or SIGTERM; the finished rows are kept, rerun the same command to resume)."""
        from viapath.bench.report import markdown_table, write_report
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

        names = [p.strip() for p in planners.split(",") if p.strip()]
        if not names:
            _fail("--planners is empty; give e.g. viapath,dwa,vo")
        if scheduler and backend == "loky":
            _fail("--scheduler needs --backend dask or ray")
        if mcap_failures is not None:
            from viapath.viz.foxglove import ViewError, check_failures_option

            try:
                check_failures_option(mcap_failures)
            except ViewError as error:
                _fail(str(error))
        planner_options = None
        if weights is not None:
            from viapath.presets import PresetError, preset_values

            if "viapath" not in names:
                _fail("--weights applies to the viapath planner, which is not in --planners")
            try:
                planner_options = {"viapath": preset_values(weights)}
            except PresetError as error:
                _fail(f"--weights: {error}")
        created = not out.exists()  # a run refused before any episode must leave no folder behind
        try:
            with terminate_as_interrupt(), results_lock(out):
                scenarios = load_suite(suite, out, count=count, seed=seed, workers=workers if backend == "loky" else 1)
                result = run_bench(
                    scenarios,
                    names,
                    out,
                    workers=workers,
                    backend=backend,
                    scheduler=scheduler,
                    perception=perception,
                    seed=seed,
                    progress=sys.stderr.isatty() and not as_json,
                    shield=shield,
                    force=force,
                    planner_options=planner_options,
                    note=lambda text: typer.echo(f"note: {text}", err=True),
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
            typer.echo(
                f"\n{stopped}; rerun the same command to resume ({stopped.total - stopped.finished} left)", err=True
            )
            raise typer.Exit(code=130) from None
        except BenchWorkerLost as lost:
            typer.echo(f"\n{lost}; rerun the same command to run the {lost.total - lost.finished} left", err=True)
            raise typer.Exit(code=3) from None
        except KeyboardInterrupt as interrupt:  # before or after the episodes (loading the suite, the report)
            typer.echo(
                f"\n{getattr(interrupt, 'reason', 'interrupted')}; rows already written are kept in "
                f"{out / 'episodes.csv'}",
                err=True,
            )
            raise typer.Exit(code=130) from None
        except (BenchError, SuiteError, OSError) as error:
            if created and not (out / "episodes.csv").exists() and not isinstance(error, FolderBusy):
                import shutil

                shutil.rmtree(out, ignore_errors=True)
            _fail(str(error))
        from viapath.bench.identity import crash_lines

        crashed = crash_lines(result["rows"])
        if as_json:
            typer.echo(json_dumps(summary, indent=2))
        else:
            typer.echo(markdown_table(summary))
            typer.echo(
                f"\n{result['ran']} episodes run, {result['skipped']} already done, {result['wall_s']:.1f} s; "
                f"results in {out}"
            )
        if crashed:
            typer.echo(
                f"\n{result['errors']} episode(s) crashed (not in the rates; rerun the same command to "
                "run them again):\n" + "\n".join(crashed),
                err=True,
            )
            raise typer.Exit(code=3)
