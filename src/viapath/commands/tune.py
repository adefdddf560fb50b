"""``viapath presets`` and ``viapath tune``: named weight presets and a multi-objective study of k1..k4.

Registered into the main typer app by ``register(app)``. Everything heavy (Optuna, the benchmark
runner, matplotlib) is imported inside the commands, so ``viapath --help`` and ``viapath presets``
work without the ``tune`` extra. The study itself is :mod:`viapath.bench.tune`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

_console = Console()
_errors = Console(stderr=True)


def _fail(message: str, code: int = 2) -> None:
    _errors.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def _number(value) -> str:
    if isinstance(value, float):
        return f"{value:.4g}" if math.isfinite(value) else "-"
    return str(value)


def register(app: typer.Typer) -> None:
    """Add ``presets`` and ``tune`` to the viapath CLI."""

    @app.command("presets")
    def presets_command(
        as_json: bool = typer.Option(False, "--json", help="Print the presets (values and evidence) as JSON."),
    ) -> None:
        """List the shipped weight presets with their values and the numbers that justify them.

        Use one with `viapath run --weights NAME`, `viapath bench --weights NAME`, a scenario's
        `planner: {weights: NAME}` or the ROS 2 node parameter `weights_preset`."""
        from viapath.presets import PresetError, all_presets

        try:
            presets = all_presets()
        except PresetError as error:
            _fail(str(error))
        if as_json:
            typer.echo(
                json.dumps(
                    [
                        {
                            "name": p.name,
                            "description": p.description,
                            "planner": p.planner,
                            "options": p.dotted(),
                            "evidence": p.evidence,
                        }
                        for p in presets
                    ],
                    indent=2,
                )
            )
            return
        table = Table(title="weight presets (viapath planner)")
        for column in ("name", "options", "description", "evidence"):
            table.add_column(column, overflow="fold")
        for p in presets:
            options = ", ".join(f"{k}={_number(v)}" for k, v in p.dotted().items())
            evidence = "\n".join(f"{k}: {_evidence_text(v)}" for k, v in p.evidence.items())
            table.add_row(p.name, options, p.description, evidence)
        _console.print(table)

    _register_tune(app)


def _evidence_text(value) -> str:
    if isinstance(value, dict):
        return ", ".join(f"{k}={_number(v)}" for k, v in value.items())
    return _number(value)


def _register_tune(app: typer.Typer) -> None:
    @app.command("tune")
    def tune_command(
        suite: str = typer.Argument(..., help="train suite: a folder of scenario YAML files, or a suite name"),
        trials: int = typer.Option(
            50, "--trials", "-n", help="total complete trials wanted in the study (a rerun runs only the missing ones)"
        ),
        workers: int = typer.Option(2, "--workers", "-w", help="parallel workers for each trial's episodes"),
        storage: str = typer.Option(..., "--storage", help="Optuna storage URL, e.g. sqlite:///tune.db"),
        study_name: str = typer.Option(..., "--study", help="study name in the storage (same name: continue it)"),
        param: list[str] = typer.Option(
            [],
            "--param",
            metavar="NAME=LOW:HIGH",
            help="search range of a weight or another numeric planner option (repeatable)",
        ),
        test: str | None = typer.Option(
            None,
            "--test",
            help="test suite: rerun the Pareto front (and the paper's weights) on it and rank them there",
        ),
        export: Path | None = typer.Option(
            None,
            "--export",
            help="write a preset YAML of the chosen trial (best on --test, else the front's knee; or --pick)",
        ),
        pick: int | None = typer.Option(None, "--pick", help="trial number to --export"),
        plot: Path | None = typer.Option(None, "--plot", help="write the Pareto-front plot (PNG/PDF/SVG)"),
        as_json: bool = typer.Option(False, "--json", help="print the Pareto front (and test ranking) as JSON"),
        seed: int = typer.Option(0, "--seed", help="sampler and episode seed; suite seed for a suite name"),
        count: int = typer.Option(50, "--count", help="scenarios to generate when SUITE is a suite name"),
        test_count: int = typer.Option(200, "--test-count", help="scenarios when --test is a suite name"),
        test_seed: int | None = typer.Option(
            None, "--test-seed", help="suite seed when --test is a suite name (default: --seed + 1000)"
        ),
        max_at_fault: int = typer.Option(0, "--max-at-fault", help="constraint: at-fault contacts allowed"),
        max_outside_s: float = typer.Option(
            0.25, "--max-outside-s", help="constraint: mean time outside the corridor per episode [s]"
        ),
        max_misses: int = typer.Option(
            0, "--max-misses", help="constraint: goal misses without a contact (and crashed episodes) allowed"
        ),
        sampler: str = typer.Option("tpe", "--sampler", help="tpe (multi-objective TPE) or nsga2"),
        timeout: float | None = typer.Option(None, "--timeout", help="start no new trial after this many seconds"),
        start_from: list[str] = typer.Option(
            [],
            "--start-from",
            metavar="PRESET",
            help="try this preset (name or file) early in the study (repeatable; once per study)",
        ),
        test_trials: str | None = typer.Option(
            None, "--test-trials", metavar="N,N", help="with --test: test these trials (numbers) instead of the front"
        ),
        test_top: int | None = typer.Option(
            None,
            "--test-top",
            help="with --test: test only the K front trials "
            "nearest the knee (smallest objectives relative to the paper's)",
        ),
    ) -> None:
        """Search the viapath planner's weights k1..k4: minimise mean lateral deviation and median time
        ratio on SUITE, with at-fault contacts, time outside the corridor and goal misses as constraints.

        Each trial runs the whole suite through the benchmark runner (shield on, as shipped). The first
        trial of a study is the paper's weights. Exit code 2 on bad input (nothing is written)."""
        from viapath.bench import tune as tuning
        from viapath.bench.identity import scenario_hash
        from viapath.bench.runner import BenchError, load_suite
        from viapath.bench.suites import SuiteError

        try:
            tuning.optuna_module()
            space = tuning.parse_space(param)
            if trials < 1:
                raise tuning.TuneError(f"--trials: expected at least 1, found {trials}")
            if workers < 1:
                raise tuning.TuneError(f"--workers: expected at least 1, found {workers}")
            if not study_name.strip():
                raise tuning.TuneError("--study: expected a name")
            for option, file, suffixes in (
                ("--export", export, {".yaml", ".yml"}),
                ("--plot", plot, {".png", ".pdf", ".svg"}),
            ):
                if file is not None and file.suffix.lower() not in suffixes:
                    raise tuning.TuneError(f"{option} {file}: expected a file ending in {', '.join(sorted(suffixes))}")
                if file is not None and not file.parent.exists():
                    raise tuning.TuneError(f"{option} {file}: folder {file.parent} does not exist")
            if pick is not None and export is None:
                raise tuning.TuneError("--pick needs --export")
            tuning.check_storage(storage)
            from viapath.presets import PresetError, preset_values

            try:
                starts = [(text, preset_values(text)) for text in start_from]
            except PresetError as error:
                raise tuning.TuneError(f"--start-from: {error}") from None
            constraints = tuning.Constraints(max_at_fault, max_outside_s, max_misses)
            scenarios = load_suite(suite, None, count=count, seed=seed)
            test_scenarios = None
            if test is not None:
                test_scenarios = load_suite(
                    test, None, count=test_count, seed=seed + 1000 if test_seed is None else test_seed
                )
        except (tuning.TuneError, BenchError, SuiteError, OSError) as error:
            _fail(str(error))

        def suite_key(items):
            import hashlib

            text = ",".join(sorted(f"{s['name']}={scenario_hash(s)}" for s in items))
            return hashlib.sha256(text.encode()).hexdigest()[:16]

        train_key = suite_key(scenarios)
        identity = {
            "planner": tuning.PLANNER,
            "suite_hash": train_key,
            "seed": seed,
            "space": [[p.name, p.low, p.high, p.log, p.integer] for p in space],
            "constraints": dict(
                zip(
                    tuning.CONSTRAINT_NAMES,
                    [constraints.max_at_fault, constraints.max_outside_s, constraints.max_misses],
                )
            ),
        }
        try:
            study = tuning.open_study(storage, study_name, seed, sampler, constraints, identity)
        except tuning.TuneError as error:
            _fail(str(error))
        info = {"study": study_name, "suite": f"{suite} ({len(scenarios)} scenarios, {train_key})"}

        show = _errors.is_terminal and not as_json
        ran, wall = _run_with_progress(
            tuning,
            study,
            scenarios,
            space,
            trials,
            workers,
            seed,
            constraints,
            timeout,
            show,
            log=not _errors.is_terminal,
            start_from=starts,
        )
        front = tuning.pareto_front(study)
        paper = tuning.paper_trial(study)
        test_results: dict[int, dict] = {}
        ranking: list[int] = []
        if test_scenarios is not None:
            test_key = suite_key(test_scenarios)
            info["test_suite"] = f"{test} ({len(test_scenarios)} scenarios, {test_key})"
            nearest = sorted(front, key=lambda t: _relative(t, paper))
            if test_trials:
                by_number = {t.number: t for t in tuning.complete_trials(study)}
                try:
                    wanted = [int(n) for n in test_trials.split(",") if n.strip()]
                except ValueError:
                    _fail(f"--test-trials {test_trials}: expected trial numbers, e.g. 3,8")
                missing = [n for n in wanted if n not in by_number]
                if missing:
                    _fail(f"--test-trials: no complete trial {missing[0]} in study {study_name!r}")
                nearest = [by_number[n] for n in wanted]
            elif test_top is not None:
                nearest = [t for t in nearest if paper is None or t.number != paper.number][: max(0, test_top)]
            chosen = nearest + ([paper] if paper is not None and paper not in nearest else [])
            if show:
                _errors.print(f"testing {len(chosen)} trials on {len(test_scenarios)} scenarios ...")
            test_results = tuning.evaluate_on_test(study, chosen, test_scenarios, test_key, workers, seed)
            ranking = tuning.rank(test_results, constraints, paper.number if paper is not None else None)
        if export is not None:
            by_number = {t.number: t for t in tuning.complete_trials(study)}
            if pick is not None:
                trial = by_number.get(pick)
                if trial is None:
                    _fail(f"--pick {pick}: no complete trial of that number in study {study_name!r}")
            elif ranking:
                candidates = [n for n in ranking if paper is None or n != paper.number] or ranking
                trial = by_number[candidates[0]]
            else:
                trial = tuning.knee(front, paper)
            if trial is None:
                _fail("--export: the study has no feasible trial yet (nothing to export)")
            tuning.export_preset(
                trial,
                export,
                info,
                test_results.get(trial.number),
                paper.user_attrs.get("metrics") if paper is not None else None,
                test_results.get(paper.number) if paper is not None else None,
            )
        if plot is not None:
            tuning.plot_front(plot, study, front, paper, test_results or None)
        summary = _summary(tuning, study, front, paper, test_results, ranking, ran, wall)
        if as_json:
            typer.echo(json.dumps(summary, indent=2, default=_json_default))
        else:
            _print_summary(summary)
            for label, file in (("preset", export), ("plot", plot)):
                if file is not None:
                    _console.print(f"{label}: {file}")


def _json_default(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return str(value)


def _relative(trial, paper) -> float:
    d0, t0 = paper.values if paper is not None else (1.0, 1.0)
    return trial.values[0] / (d0 or 1.0) + trial.values[1] / (t0 or 1.0)


def _run_with_progress(
    tuning, study, scenarios, space, trials, workers, seed, constraints, timeout, show, log=False, start_from=()
):
    if not show:

        def line(study_, trial):  # one line per trial on stderr (a log file), never on stdout
            m = trial.user_attrs.get("metrics") or {}
            state = "feasible" if tuning.is_feasible(trial) else "infeasible"
            params = " ".join(f"{k}={v:.4g}" for k, v in trial.params.items())
            _errors.print(
                f"trial {trial.number} ({state}): {params}: dev {m.get('mean_lateral_deviation_m', float('nan')):.4f} m, "
                f"time ratio {m.get('median_time_ratio', float('nan')):.4f}, at-fault {m.get('at_fault')}, "
                f"contacts {m.get('contacts')}, misses {m.get('misses')} {m.get('misses_by_family')}, "
                f"outside {m.get('outside_s_per_episode', float('nan')):.2f} s/ep, "
                f"{trial.duration.total_seconds() if trial.duration else float('nan'):.1f} s",
                highlight=False,
                soft_wrap=True,
            )

        return tuning.run_study(
            study,
            scenarios,
            space,
            trials,
            workers,
            seed,
            constraints,
            timeout,
            on_trial=line if log else None,
            start_from=start_from,
        )
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    done = len(tuning.complete_trials(study))
    with Progress(
        TextColumn("trials"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TextColumn("/"),
        TimeRemainingColumn(),
        TextColumn("{task.description}"),
        console=_errors,
    ) as bar:
        job = bar.add_task(_best_text(tuning, study), total=trials, completed=min(done, trials))

        def on_trial(study_, trial):
            bar.update(
                job, completed=min(len(tuning.complete_trials(study_)), trials), description=_best_text(tuning, study_)
            )

        return tuning.run_study(
            study,
            scenarios,
            space,
            trials,
            workers,
            seed,
            constraints,
            timeout,
            on_trial=on_trial,
            start_from=start_from,
        )


def _best_text(tuning, study) -> str:
    try:
        front = tuning.pareto_front(study)
    except Exception:
        front = []
    if not front:
        return "no feasible trial yet"
    best = sorted(front, key=lambda t: t.values[0])[:3]
    return "front: " + "; ".join(f"#{t.number} dev {t.values[0]:.3f} m, time {t.values[1]:.3f}" for t in best)


def _summary(tuning, study, front, paper, test_results, ranking, ran, wall) -> dict:
    def entry(trial):
        item = {
            "trial": trial.number,
            "params": trial.params,
            "feasible": tuning.is_feasible(trial),
            "train": trial.user_attrs.get("metrics"),
        }
        if trial.number in test_results:
            item["test"] = test_results[trial.number]
            if paper is not None and paper.number in test_results:
                item["dominates_paper_on_test"] = tuning.dominates_paper(
                    test_results[trial.number], test_results[paper.number]
                )
        if ranking and trial.number in ranking:
            item["test_rank"] = ranking.index(trial.number) + 1
        return item

    front_sorted = sorted(front, key=lambda t: t.values[1])
    on_front = {t.number for t in front} | ({paper.number} if paper is not None else set())
    others = [t for t in tuning.complete_trials(study) if t.number in test_results and t.number not in on_front]
    return {
        "study": study.study_name,
        "trials": len(tuning.complete_trials(study)),
        "ran": ran,
        "wall_s": round(wall, 1),
        "front": [entry(t) for t in front_sorted],
        "paper": entry(paper) if paper is not None else None,
        "tested_off_front": [entry(t) for t in others],
        "test_ranking": ranking,
    }


def _print_summary(summary: dict) -> None:
    table = Table(
        title=f"study {summary['study']}: Pareto front ({summary['trials']} trials, {summary['ran']} run "
        f"now in {summary['wall_s']} s); train | test"
    )
    for column in (
        "trial",
        "k1",
        "k2",
        "k3",
        "k4",
        "dev m",
        "time",
        "fault/contact/miss",
        "dev m",
        "time",
        "fault/contact/miss",
        "rank",
        "beats paper",
    ):
        table.add_column(column, no_wrap=True)
    paper = summary["paper"]
    rows = list(summary["front"])
    if paper and all(item["trial"] != paper["trial"] for item in rows):
        rows.append(paper)
    rows += summary.get("tested_off_front", [])

    def counts(m):
        return f"{m['at_fault']}/{m['contacts']}/{m['misses']}" if m else "-"

    for item in rows:
        is_paper = paper is not None and item["trial"] == paper["trial"]
        m, t, p = item["train"] or {}, item.get("test") or {}, item["params"]
        table.add_row(
            f"{item['trial']}{' paper' if is_paper else ''}",
            *(_number(p.get(k, float("nan"))) for k in ("k1", "k2", "k3", "k4")),
            _number(m.get("mean_lateral_deviation_m", float("nan"))),
            _number(m.get("median_time_ratio", float("nan"))),
            counts(m),
            _number(t.get("mean_lateral_deviation_m", float("nan"))),
            _number(t.get("median_time_ratio", float("nan"))),
            counts(t),
            str(item.get("test_rank", "-")),
            {True: "yes", False: "no"}.get(item.get("dominates_paper_on_test"), "-"),
        )
    Console(width=max(_console.width, 150)).print(table)
