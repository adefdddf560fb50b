"""``viapath presets`` and ``viapath tune``: named weight presets and a multi-objective study of k1..k4.

Everything heavy (Optuna, the benchmark
runner, matplotlib) is imported inside the commands, so ``viapath --help`` and ``viapath presets``
work without the ``tune`` extra. The study itself is :mod:`viapath.bench.tune`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from viapath.cli.common import console, errors, fail


def _number(value) -> str:
    if isinstance(value, float):
        return f"{value:.4g}" if math.isfinite(value) else "-"
    return str(value)


def presets(
    as_json: bool = typer.Option(False, "--json", help="Print the presets (values and evidence) as JSON."),
) -> None:
    """List the shipped weight presets with their values and the numbers that justify them.

    Use one with `viapath run --weights NAME`, `viapath bench --weights NAME`, a scenario's
    `planner: {weights: NAME}` or the ROS 2 node parameter `weights_preset`."""
    from viapath.presets import PresetError, all_presets

    try:
        shipped = all_presets()
    except PresetError as error:
        fail(str(error))
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
                    for p in shipped
                ],
                indent=2,
            )
        )
        return
    table = Table(title="weight presets (viapath planner)")
    for column in ("name", "options", "description", "evidence"):
        table.add_column(column, overflow="fold")
    for p in shipped:
        options = ", ".join(f"{k}={_number(v)}" for k, v in p.dotted().items())
        evidence = "\n".join(f"{k}: {_evidence_text(v)}" for k, v in p.evidence.items())
        table.add_row(p.name, options, p.description, evidence)
    console.print(table)


def _evidence_text(value) -> str:
    if isinstance(value, dict):
        return ", ".join(f"{k}={_number(v)}" for k, v in value.items())
    return _number(value)


Suite = Annotated[str, typer.Argument(help="train suite: a folder of scenario YAML files, or a suite name")]
Trials = Annotated[
    int,
    typer.Option(
        "--trials", "-n", help="total complete trials wanted in the study (a rerun runs only the missing ones)"
    ),
]
Workers = Annotated[int, typer.Option("--workers", "-w", help="parallel workers for each trial's episodes")]
Param = Annotated[
    list[str],
    typer.Option(
        "--param",
        metavar="NAME=LOW:HIGH",
        help="search range of a weight or another numeric planner option (repeatable)",
    ),
]
Test = Annotated[
    str | None,
    typer.Option(
        "--test", help="test suite: rerun the Pareto front (and the paper's weights) on it and rank them there"
    ),
]
Export = Annotated[
    Path | None,
    typer.Option(
        "--export", help="write a preset YAML of the chosen trial (best on --test, else the front's knee; or --pick)"
    ),
]
Pick = Annotated[int | None, typer.Option("--pick", help="trial number to --export")]
Plot = Annotated[Path | None, typer.Option("--plot", help="write the Pareto-front plot (PNG/PDF/SVG)")]
AsJson = Annotated[bool, typer.Option("--json", help="print the Pareto front (and test ranking) as JSON")]
Seed = Annotated[int, typer.Option("--seed", help="sampler and episode seed; suite seed for a suite name")]
Count = Annotated[int, typer.Option("--count", help="scenarios to generate when SUITE is a suite name")]
TestCount = Annotated[int, typer.Option("--test-count", help="scenarios when --test is a suite name")]
TestSeed = Annotated[
    int | None, typer.Option("--test-seed", help="suite seed when --test is a suite name (default: --seed + 1000)")
]
MaxAtFault = Annotated[int, typer.Option("--max-at-fault", help="constraint: at-fault contacts allowed")]
MaxOutside = Annotated[
    float, typer.Option("--max-outside-s", help="constraint: mean time outside the corridor per episode [s]")
]
MaxMisses = Annotated[
    int, typer.Option("--max-misses", help="constraint: goal misses without a contact (and crashed episodes) allowed")
]
Sampler = Annotated[str, typer.Option("--sampler", help="tpe (multi-objective TPE) or nsga2")]
Timeout = Annotated[float | None, typer.Option("--timeout", help="start no new trial after this many seconds")]
StartFrom = Annotated[
    list[str],
    typer.Option(
        "--start-from",
        metavar="PRESET",
        help="try this preset (name or file) early in the study (repeatable; once per study)",
    ),
]
TestTrials = Annotated[
    str | None,
    typer.Option("--test-trials", metavar="N,N", help="with --test: test these trials (numbers) instead of the front"),
]
TestTop = Annotated[
    int | None,
    typer.Option(
        "--test-top",
        help="with --test: test only the K front trials nearest the knee (smallest objectives relative to the paper's)",
    ),
]


def tune(
    suite: Suite,
    trials: Trials = 50,
    workers: Workers = 2,
    storage: str = typer.Option(..., "--storage", help="Optuna storage URL, e.g. sqlite:///tune.db"),
    study_name: str = typer.Option(..., "--study", help="study name in the storage (same name: continue it)"),
    param: Param = [],  # noqa: B006 - typer's default for a repeatable option, never mutated
    test: Test = None,
    export: Export = None,
    pick: Pick = None,
    plot: Plot = None,
    as_json: AsJson = False,
    seed: Seed = 0,
    count: Count = 50,
    test_count: TestCount = 200,
    test_seed: TestSeed = None,
    max_at_fault: MaxAtFault = 0,
    max_outside_s: MaxOutside = 0.25,
    max_misses: MaxMisses = 0,
    sampler: Sampler = "tpe",
    timeout: Timeout = None,
    start_from: StartFrom = [],  # noqa: B006 - as param
    test_trials: TestTrials = None,
    test_top: TestTop = None,
) -> None:
    """Search the viapath planner's weights k1..k4: minimise mean lateral deviation and median time
    ratio on SUITE, with at-fault contacts, time outside the corridor and goal misses as constraints.

    Each trial runs the whole suite through the benchmark runner (shield on, as shipped). The first
    trial of a study is the paper's weights. Exit code 2 on bad input (nothing is written)."""
    from viapath.bench import tune as tuning

    refused: tuple[type[Exception], ...] = (tuning.TuneError, *_suite_errors())
    try:
        space = _check_tune_arguments(tuning, param, trials, workers, study_name, export, plot, pick, storage)
        if timeout is not None and not (math.isfinite(timeout) and timeout > 0):
            raise tuning.TuneError(f"--timeout: expected a number of seconds > 0, found {timeout}")
        constraints = tuning.Constraints(max_at_fault, max_outside_s, max_misses)
        starts, scenarios, test_scenarios = _load_tune_suites(
            start_from, suite, count, seed, test, test_count, seed + 1000 if test_seed is None else test_seed
        )
    except refused as error:
        fail(str(error))
    train_key = _suite_key(scenarios)
    try:
        study = tuning.open_study(
            storage,
            study_name,
            seed,
            sampler,
            constraints,
            _study_identity(tuning, train_key, seed, space, constraints),
        )
    except tuning.TuneError as error:
        fail(str(error))
    info = {"study": study_name, "suite": f"{suite} ({len(scenarios)} scenarios, {train_key})"}
    show = errors.is_terminal and not as_json
    ran, wall = _run_with_progress(
        tuning, study, scenarios, space, trials, workers, seed, constraints, timeout, show,
        log=not errors.is_terminal, start_from=starts,
    )  # fmt: skip
    front, paper = tuning.pareto_front(study), tuning.paper_trial(study)
    test_results, ranking = _test_on(tuning, study, study_name, test_scenarios, test, info, front, paper, show, workers,
                                     seed, constraints, test_trials, test_top)  # fmt: skip
    if export is not None:
        _export(tuning, study, study_name, export, pick, ranking, front, paper, info, test_results)
    if plot is not None:
        tuning.plot_front(plot, study, front, paper, test_results or None)
    summary = _summary(tuning, study, front, paper, test_results, ranking, ran, wall)
    if as_json:
        typer.echo(json.dumps(summary, indent=2, default=_json_default))
        return
    _print_summary(summary)
    for label, file in (("preset", export), ("plot", plot)):
        if file is not None:
            console.print(f"{label}: {file}")


def _test_on(tuning, study, study_name, test_scenarios, test, info, front, paper, show, workers, seed,
             constraints, test_trials, test_top) -> tuple[dict[int, dict], list[int]]:  # fmt: skip
    """The chosen trials' results on the test suite and their ranking there (nothing without --test)."""
    if test_scenarios is None:
        return {}, []
    test_key = _suite_key(test_scenarios)
    info["test_suite"] = f"{test} ({len(test_scenarios)} scenarios, {test_key})"
    chosen = _trials_to_test(tuning, study, study_name, front, paper, test_trials, test_top)
    if show:
        errors.print(f"testing {len(chosen)} trials on {len(test_scenarios)} scenarios ...")
        test_results = _test_with_progress(tuning, study, chosen, test_scenarios, test_key, workers, seed)
    else:
        test_results = tuning.evaluate_on_test(study, chosen, test_scenarios, test_key, workers, seed)
    return test_results, tuning.rank(test_results, constraints, paper.number if paper is not None else None)


def _test_with_progress(tuning, study, chosen, scenarios, key, workers, seed) -> dict[int, dict]:
    """``evaluate_on_test`` with a bar of the trials tested and one of the running trial's episodes."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    columns = (TextColumn("{task.fields[kind]:>8}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    with Progress(*columns, TextColumn("{task.description}"), console=errors) as bar:
        tested = bar.add_task("tested", total=len(chosen), kind="trials")
        episodes = bar.add_task("of the running trial", total=len(scenarios), kind="episodes")

        def on_done(trial, metrics):
            bar.advance(tested)
            bar.reset(episodes, total=len(scenarios))

        # drawn at once: the bar is reset as the trial ends, so its last episode might never be shown
        return tuning.evaluate_on_test(
            study, chosen, scenarios, key, workers, seed,
            on_done=on_done, on_episode=lambda done, total: bar.update(episodes, completed=done, total=total, refresh=True),
        )  # fmt: skip


def _suite_errors() -> tuple[type[Exception], ...]:
    from viapath.bench.runner import BenchError
    from viapath.bench.suites import SuiteError

    return BenchError, SuiteError, OSError


def _check_tune_arguments(tuning, param, trials, workers, study_name, export, plot, pick, storage) -> list:
    """The search space (--param), after checking every argument; raises ``TuneError``."""
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
    return space


def _load_tune_suites(start_from, suite, count, seed, test, test_count, test_seed):
    """The presets to start from, the train suite and the test suite (None without --test)."""
    from viapath.bench import tune as tuning
    from viapath.bench.runner import load_suite
    from viapath.presets import PresetError, preset_values

    try:
        starts = [(text, preset_values(text)) for text in start_from]
    except PresetError as error:
        raise tuning.TuneError(f"--start-from: {error}") from None
    scenarios = load_suite(suite, None, count=count, seed=seed)
    test_scenarios = None if test is None else load_suite(test, None, count=test_count, seed=test_seed)
    return starts, scenarios, test_scenarios


def _suite_key(items) -> str:
    import hashlib

    from viapath.bench.identity import scenario_hash

    text = ",".join(sorted(f"{s['name']}={scenario_hash(s)}" for s in items))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _study_identity(tuning, train_key: str, seed: int, space, constraints) -> dict:
    return {
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


def _trials_to_test(tuning, study, study_name, front, paper, test_trials, test_top) -> list:
    """--test-trials, or the front (its --test-top nearest the knee), and the paper's trial."""
    nearest = sorted(front, key=lambda t: _relative(t, paper))
    if test_trials:
        by_number = {t.number: t for t in tuning.complete_trials(study)}
        try:
            wanted = [int(n) for n in test_trials.split(",") if n.strip()]
        except ValueError:
            fail(f"--test-trials {test_trials}: expected trial numbers, e.g. 3,8")
        missing = [n for n in wanted if n not in by_number]
        if missing:
            fail(f"--test-trials: no complete trial {missing[0]} in study {study_name!r}")
        nearest = [by_number[n] for n in wanted]
    elif test_top is not None:
        nearest = [t for t in nearest if paper is None or t.number != paper.number][: max(0, test_top)]
    return nearest + ([paper] if paper is not None and paper not in nearest else [])


def _export(tuning, study, study_name, export, pick, ranking, front, paper, info, test_results) -> None:
    """Write the preset of --pick, else the best on the test suite, else the front's knee."""
    by_number = {t.number: t for t in tuning.complete_trials(study)}
    if pick is not None:
        trial = by_number.get(pick)
        if trial is None:
            fail(f"--pick {pick}: no complete trial of that number in study {study_name!r}")
    elif ranking:
        candidates = [n for n in ranking if paper is None or n != paper.number] or ranking
        trial = by_number[candidates[0]]
    else:
        trial = tuning.knee(front, paper)
    if trial is None:
        fail("--export: the study has no feasible trial yet (nothing to export)")
    tuning.export_preset(
        trial,
        export,
        info,
        test_results.get(trial.number),
        paper.user_attrs.get("metrics") if paper is not None else None,
        test_results.get(paper.number) if paper is not None else None,
    )


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
            errors.print(
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
        TextColumn("{task.fields[kind]:>8}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TextColumn("/"),
        TimeRemainingColumn(),
        TextColumn("{task.description}"),
        console=errors,
    ) as bar:
        job = bar.add_task(_best_text(tuning, study), total=trials, completed=min(done, trials), kind="trials")
        # The running trial's episodes: a trial on a large suite takes minutes, the trials bar moves once per trial.
        episodes = bar.add_task("of the running trial", total=len(scenarios), kind="episodes")

        def on_trial(study_, trial):
            bar.update(
                job, completed=min(len(tuning.complete_trials(study_)), trials), description=_best_text(tuning, study_)
            )
            bar.reset(episodes, total=len(scenarios))

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
            # drawn at once: the bar is reset as the trial ends, so its last episode might never be shown
            on_episode=lambda done_, total: bar.update(episodes, completed=done_, total=total, refresh=True),
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
    Console(width=max(console.width, 150)).print(table)
