"""A multi-objective study of the planner's weights k1..k4 (paper §4.2 and its open question §5.2).

Method: Optuna (Akiba et al., KDD 2019). Each trial picks option values, runs the whole suite through
the benchmark runner (:func:`viapath.bench.runner.run_bench`: the same workers, episode seeds and
metrics as ``viapath bench``, the viapath planner as it ships, shield on) and reports two objectives,
both minimised:

* the **mean lateral deviation** over the episodes (m), and
* the **median time ratio** (time to goal / obstacle-free time; an episode that misses the goal counts
  as :data:`MISS_TIME_RATIO`, slower than any arrival).

Constraints (Optuna's ``constraints_func``: a trial that breaks one is *infeasible*, not merely worse;
it never enters the Pareto front):

* at-fault contacts ≤ ``max_at_fault`` (default 0) — the shield makes any contact one the robot did not
  cause, so an at-fault contact is a real failure;
* mean time outside the corridor per episode ≤ ``max_outside_s`` (default 0.25 s);
* goal misses without any contact (and crashed episodes) ≤ ``max_misses`` (default 0): the robot
  trailed, stalled or gave up. The median time ratio hardly sees a few misses, so they are a constraint
  rather than an objective. A miss after a contact is not counted again here: the contact is the
  failure, and it is either at fault (constrained above) or someone walked into a robot the shield
  had stopped (reported as ``contacts``, and the issue's target compares it with the paper's).

Choices where the issue is silent:
* Search space: each weight log-uniform over two decades around the paper's value (k1 0.01-1,
  k2 1e-4-0.1, k3 0.008-0.8, k4 0.03-3); ``--param NAME=LOW:HIGH`` narrows/widens one or adds another
  numeric planner option (uniform; log-uniform for the weights; integer options as integers).
* Sampler: multi-objective TPE with constraints, seeded (``sampler="nsga2"`` for NSGA-II). With a few
  hundred trials TPE converges faster than NSGA-II's generations of 50.
* The first trial of a new study is the paper's weights (enqueued), the reference point of the plot
  and of the test-suite ranking. ``--start-from PRESET`` enqueues more known points (once per study).
* ``trials`` is the **total** wanted: a rerun with the same storage and study name runs only what is
  missing (a trial that crashed or was killed does not count and is rerun by the sampler). The study
  records its suite (scenario content hashes), seeds, space and constraints; a rerun with other ones
  is refused.
* Test suite: the Pareto-front trials and the paper's are rerun on a second suite; results are kept in
  the study (user attributes), so a rerun does not repeat them. They are ranked there: feasible first,
  then by how many of the others dominate them, then by the sum of the two objectives relative to the
  paper's.
"""

from __future__ import annotations

import math
import statistics
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from viapath.bench.runner import BenchError, family_of, run_bench
from viapath.presets import preset_values

# The reference point of every study: the paper's weights (Eq. 1, §4.2), as the preset ``paper`` sets them.
PAPER_WEIGHTS = {name: value for name, value in preset_values("paper").items() if name in ("k1", "k2", "k3", "k4")}
DEFAULT_SPACE: dict[str, tuple[float, float]] = {
    "k1": (0.01, 1.0),
    "k2": (1e-4, 0.1),
    "k3": (0.008, 0.8),
    "k4": (0.03, 3.0),
}
MISS_TIME_RATIO = 10.0
PLANNER = "viapath"


class TuneError(ValueError):
    """Bad tuning input (unknown parameter, empty range, storage, suite, missing extra)."""


@dataclass(frozen=True)
class Param:
    name: str  # the option's name (k1, horizon_s)
    low: float
    high: float
    log: bool
    integer: bool = False


@dataclass(frozen=True)
class Constraints:
    max_at_fault: int = 0
    max_outside_s: float = 0.25
    max_misses: int = 0

    def __post_init__(self) -> None:
        # Counts and a duration: a NaN, a negative or an infinite bound is no constraint a study can keep.
        for name, unit in (("max_at_fault", ""), ("max_outside_s", " s"), ("max_misses", "")):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise TuneError(f"--{name.replace('_', '-')}: expected a finite number >= 0{unit}, found {value}")

    def values(self, m: dict[str, Any]) -> list[float]:
        """Optuna's convention: each value ≤ 0 means satisfied."""
        return [
            m["at_fault"] - self.max_at_fault,
            m["outside_s_per_episode"] - self.max_outside_s,
            m["misses_without_contact"] - self.max_misses,
        ]


CONSTRAINT_NAMES = ("at_fault", "outside_s_per_episode", "misses_without_contact")


def optuna_module():
    try:
        import optuna
    except ImportError:
        raise TuneError("viapath tune needs Optuna: pip install 'viapath[tune]'") from None
    import warnings

    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    return optuna


def _has_set_constraint() -> bool:
    import optuna

    return hasattr(optuna.trial.Trial, "set_constraint")


def parse_space(assignments: list[str]) -> list[Param]:
    """The default weights space with ``NAME=LOW:HIGH`` items applied (checked against the planner's options)."""
    from viapath.planning.viapath.options import VIAPATH_OPTIONS as schema

    space: dict[str, Param] = {name: Param(name, low, high, log=True) for name, (low, high) in DEFAULT_SPACE.items()}
    for text in assignments:
        name, sep, bounds = text.partition("=")
        name = name.strip().split(".")[-1]
        low_text, colon, high_text = bounds.partition(":")
        if not sep or not colon:
            raise TuneError(f"--param {text}: expected NAME=LOW:HIGH, e.g. k2=0.001:0.1")
        if name not in schema:
            raise TuneError(
                f"--param {text}: unknown option {name!r}; the viapath planner's numeric options: "
                + ", ".join(o.path for o in schema if o.kind in (int, float))
            )
        option = schema[name]
        if option.kind not in (int, float):
            raise TuneError(f"--param {text}: option {option.path} is not a number (it is {option.kind.__name__})")
        try:
            low, high = float(low_text), float(high_text)
        except ValueError:
            raise TuneError(f"--param {text}: LOW and HIGH must be numbers") from None
        if not (math.isfinite(low) and math.isfinite(high)) or not low < high:
            raise TuneError(f"--param {text}: empty range; expected LOW < HIGH, finite")
        for value in (low, high):
            try:
                schema.validate({name: int(value) if option.kind is int else value})
            except Exception as error:
                raise TuneError(f"--param {text}: {error}") from None
        log = option.group == "weights" and low > 0
        space[name] = Param(name, low, high, log=log, integer=option.kind is int)
    return list(space.values())


def suite_metrics(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The objectives and constraint counts of one suite run (rows of :func:`run_bench`)."""
    if not rows:
        raise TuneError("the suite ran no episodes")
    ok = [r for r in rows if not r.get("error")]
    deviations = [r["mean_lateral_deviation_m"] for r in ok if r.get("mean_lateral_deviation_m") is not None]
    ratios = [
        r["time_ratio"] if r.get("reached_goal") and r.get("time_ratio") is not None else MISS_TIME_RATIO for r in rows
    ]
    misses = [r for r in rows if r.get("error") or not r.get("reached_goal")]
    by_family: dict[str, int] = {}
    for r in misses:
        family = r.get("family") or family_of(r["scenario"])
        by_family[family] = by_family.get(family, 0) + 1
    return {
        "episodes": len(rows),
        "mean_lateral_deviation_m": statistics.fmean(deviations) if deviations else math.inf,
        "median_time_ratio": statistics.median(ratios),
        "at_fault": sum(1 for r in ok if r.get("at_fault_collision")),
        "contacts": sum(1 for r in ok if r.get("collision")),
        "outside_s_per_episode": statistics.fmean([r.get("time_outside_corridor_s") or 0.0 for r in ok])
        if ok
        else math.inf,
        "misses": len(misses),
        "misses_without_contact": sum(1 for r in misses if r.get("error") or not r.get("collision")),
        "misses_by_family": dict(sorted(by_family.items())),
        "crashed": sum(1 for r in rows if r.get("error")),
    }


def evaluate(
    scenarios: list[dict],
    values: dict[str, Any],
    workers: int,
    seed: int,
    executor: str = "loky",
    progress: bool | Callable[[int, int], None] = False,
) -> dict[str, Any]:
    """Run the suite with the viapath planner and these option values; its :func:`suite_metrics`
    (``progress``: as :func:`viapath.bench.runner.run_bench`'s)."""
    with tempfile.TemporaryDirectory(prefix="viapath-tune-") as folder:
        result = run_bench(
            scenarios,
            [PLANNER],
            Path(folder),
            workers=workers,
            executor=executor,
            seed=seed,
            progress=progress,
            planner_options={PLANNER: dict(values)},
        )
    return suite_metrics(result["rows"])


def dominates(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """a Pareto-dominates b on (mean lateral deviation, median time ratio): no worse in both, better in one."""
    x = (a["mean_lateral_deviation_m"], a["median_time_ratio"])
    y = (b["mean_lateral_deviation_m"], b["median_time_ratio"])
    return x[0] <= y[0] and x[1] <= y[1] and x != y


def dominates_paper(candidate: dict[str, Any], paper: dict[str, Any]) -> bool:
    """The issue's target: no more contacts or at-fault contacts, and strictly lower deviation AND time ratio."""
    return (
        candidate["contacts"] <= paper["contacts"]
        and candidate["at_fault"] <= paper["at_fault"]
        and candidate["mean_lateral_deviation_m"] < paper["mean_lateral_deviation_m"]
        and candidate["median_time_ratio"] < paper["median_time_ratio"]
    )


# -- the study ----------------------------------------------------------------------------------------


def check_storage(url: str) -> None:
    """Refuse a storage that cannot be opened, before anything is created."""
    if "://" not in url:
        raise TuneError(f"--storage {url}: expected a database URL such as sqlite:///tune.db")
    if url.startswith("sqlite:///"):
        path = Path(url[len("sqlite:///") :])
        if not path.parent.exists() or not path.parent.is_dir():
            raise TuneError(f"--storage {url}: folder {path.parent} does not exist")
        if path.is_dir():
            raise TuneError(f"--storage {url}: {path} is a folder")
        if path.exists():
            with open(path, "rb") as handle:
                head = handle.read(16)
            if head and head != b"SQLite format 3\x00":
                raise TuneError(f"--storage {url}: {path} is not an SQLite database")


def open_study(url: str, name: str, seed: int, sampler: str, constraints: Constraints, identity: dict[str, Any]):
    """Create or load the study; refuse one recorded with another suite, seed, space or constraints."""
    optuna = optuna_module()
    check_storage(url)
    if sampler not in ("tpe", "nsga2"):
        raise TuneError(f"--sampler {sampler}: expected tpe or nsga2")
    sqlite_file = Path(url[len("sqlite:///") :]) if url.startswith("sqlite:///") else None
    existed = sqlite_file is not None and sqlite_file.exists()

    def constraints_func(trial):
        return trial.user_attrs.get("constraints", [1.0, 1.0, 1.0])

    # Optuna 5 takes constraints from ``trial.set_constraint`` (see run_study); 3.6-4.x from constraints_func.
    given = {} if _has_set_constraint() else {"constraints_func": constraints_func}

    def make_sampler(sampler_seed: int):
        if sampler == "tpe":
            return optuna.samplers.TPESampler(seed=sampler_seed, multivariate=True, n_startup_trials=10, **given)
        return optuna.samplers.NSGAIISampler(seed=sampler_seed, **given)

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        storage = optuna.storages.RDBStorage(url, heartbeat_interval=60, grace_period=180)
        study = optuna.create_study(
            study_name=name,
            storage=storage,
            sampler=make_sampler(seed),
            load_if_exists=True,
            directions=["minimize", "minimize"],
        )
        # A resumed study must not replay the first run's random draws: the seed moves on with the trials
        # already stored (still deterministic for the same history).
        study.sampler = make_sampler(seed + len(study.trials))
    except Exception as error:
        if sqlite_file is not None and not existed and sqlite_file.exists():
            sqlite_file.unlink()
        message = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise TuneError(f"--storage {url}: cannot open the study: {message}") from None
    recorded = study.user_attrs.get("identity")
    if recorded is None:
        study.set_user_attr("identity", identity)
    elif recorded != identity:
        differs = [key for key in identity if recorded.get(key) != identity[key]]
        raise TuneError(
            f"study {name!r} in {url} was run with another {', '.join(differs)}; use another --study "
            "name (or the same settings to continue it)"
        )
    return study


def complete_trials(study) -> list[Any]:
    from optuna.trial import TrialState

    return [t for t in study.get_trials(deepcopy=False) if t.state == TrialState.COMPLETE]


def is_feasible(trial) -> bool:
    return all(value <= 0 for value in trial.user_attrs.get("constraints", [1.0]))


def paper_trial(study):
    return next((t for t in complete_trials(study) if t.user_attrs.get("reference") == "paper"), None)


def run_study(
    study,
    scenarios: list[dict],
    space: list[Param],
    trials: int,
    workers: int,
    seed: int,
    constraints: Constraints,
    timeout_s: float | None = None,
    executor: str = "loky",
    on_trial: Callable[[Any, Any], None] | None = None,
    start_from: Sequence[tuple[str, dict[str, Any]]] = (),
    on_episode: Callable[[int, int], None] | None = None,
) -> tuple[int, float]:
    """Run trials until the study has ``trials`` complete ones (or ``timeout_s`` passes); returns
    (trials run now, wall seconds). ``on_trial`` is called after each trial, ``on_episode(done, total)``
    after each episode of the running trial. ``start_from``: (label, option values) tried first (once per study),
    e.g. presets a user already trusts; values outside the searched ranges are left to the sampler."""
    optuna_module()
    from optuna.storages import fail_stale_trials

    fail_stale_trials(study)
    from optuna.trial import TrialState

    waiting = any(t.state == TrialState.WAITING for t in study.get_trials(deepcopy=False))
    if paper_trial(study) is None and not waiting:
        reference = {name: value for name, value in PAPER_WEIGHTS.items() if name in {p.name for p in space}}
        from viapath.planning.viapath.options import VIAPATH_OPTIONS

        paper = preset_values("paper")
        for p in space:  # the other searched options at the paper's values, else their defaults, where in range
            default = paper.get(p.name, VIAPATH_OPTIONS[p.name].default)
            if p.name not in reference and p.low <= default <= p.high:
                reference[p.name] = default
        study.enqueue_trial(reference, user_attrs={"reference": "paper"})
    tried = {t.user_attrs.get("start_from") for t in study.get_trials(deepcopy=False)}
    for label, values in start_from:
        if label in tried:
            continue
        fixed = {p.name: values[p.name] for p in space if p.name in values and p.low <= values[p.name] <= p.high}
        study.enqueue_trial(fixed, user_attrs={"start_from": label})

    def objective(trial):
        values = {}
        for p in space:
            if p.integer:
                values[p.name] = trial.suggest_int(p.name, int(p.low), int(p.high), log=p.log)
            else:
                values[p.name] = trial.suggest_float(p.name, p.low, p.high, log=p.log)
        metrics = evaluate(scenarios, values, workers, seed, executor, progress=on_episode or False)
        trial.set_user_attr("metrics", metrics)
        trial.set_user_attr("constraints", constraints.values(metrics))
        if _has_set_constraint():
            for key, value in zip(CONSTRAINT_NAMES, constraints.values(metrics)):
                trial.set_constraint(key, float(value))
        return metrics["mean_lateral_deviation_m"], metrics["median_time_ratio"]

    callbacks = [on_trial] if on_trial else []
    started = time.perf_counter()
    done_before = len(complete_trials(study))
    while True:
        need = trials - len(complete_trials(study))
        left = None if timeout_s is None else timeout_s - (time.perf_counter() - started)
        if need <= 0 or (left is not None and left <= 0):
            break
        complete_then = len(complete_trials(study))
        # Optuna's own progress bar is off: the command draws a rich one. A trial whose suite cannot run
        # is marked failed and does not count; if every trial of a round fails, stop rather than loop.
        study.optimize(
            objective,
            n_trials=need,
            timeout=left,
            callbacks=callbacks,
            catch=(BenchError,),
            gc_after_trial=False,
            show_progress_bar=False,
        )
        if len(complete_trials(study)) == complete_then:
            break
    return len(complete_trials(study)) - done_before, time.perf_counter() - started


def pareto_front(study) -> list[Any]:
    """Optuna's best trials: non-dominated among the feasible complete trials."""
    return [t for t in study.best_trials if is_feasible(t)]


def evaluate_on_test(
    study,
    trials: list[Any],
    scenarios: list[dict],
    key: str,
    workers: int,
    seed: int,
    executor: str = "loky",
    on_done: Callable[[Any, dict], None] | None = None,
    on_episode: Callable[[int, int], None] | None = None,
) -> dict[int, dict]:
    """Each trial's metrics on the test suite (cached in the study under ``key``); ``on_done`` after
    each trial, ``on_episode(done, total)`` after each episode run."""
    cache = dict(study.user_attrs.get(f"test:{key}", {}))
    results: dict[int, dict] = {}
    for trial in trials:
        stored = cache.get(str(trial.number))
        if stored is None:
            stored = evaluate(scenarios, trial_values(trial), workers, seed, executor, progress=on_episode or False)
            cache[str(trial.number)] = stored
            study.set_user_attr(f"test:{key}", cache)
        results[trial.number] = stored
        if on_done:
            on_done(trial, stored)
    return results


def trial_values(trial) -> dict[str, Any]:
    return dict(trial.params)


def rank(results: dict[int, dict], constraints: Constraints, reference: int | None) -> list[int]:
    """Feasible first, then fewer dominators among the others, then the objectives' sum relative to the reference."""
    ref = results.get(reference) if reference is not None else None

    def key(number):
        m = results[number]
        feasible = all(v <= 0 for v in constraints.values(m))
        dominated_by = sum(1 for other, o in results.items() if other != number and dominates(o, m))
        scale_d = ref["mean_lateral_deviation_m"] if ref and ref["mean_lateral_deviation_m"] > 0 else 1.0
        scale_t = ref["median_time_ratio"] if ref and ref["median_time_ratio"] > 0 else 1.0
        return (
            not feasible,
            dominated_by,
            m["mean_lateral_deviation_m"] / scale_d + m["median_time_ratio"] / scale_t,
            number,
        )

    return sorted(results, key=key)


def knee(trials: list[Any], reference) -> Any | None:
    """The front trial with the smallest sum of objectives relative to the reference's (the pick without --test)."""
    if not trials:
        return None
    d0, t0 = reference.values if reference is not None else (1.0, 1.0)
    return min(trials, key=lambda t: (t.values[0] / (d0 or 1.0) + t.values[1] / (t0 or 1.0), t.number))


def export_preset(
    trial,
    path: Path,
    identity: dict[str, Any],
    test: dict[str, Any] | None,
    paper_train: dict[str, Any] | None,
    paper_test: dict[str, Any] | None,
) -> None:
    from viapath.presets import preset_from_dict

    def short(m):
        return None if m is None else {k: (round(v, 4) if isinstance(v, float) else v) for k, v in m.items()}

    evidence = {
        "study": identity.get("study"),
        "trial": trial.number,
        "train_suite": identity.get("suite"),
        "train": short(trial.user_attrs.get("metrics")),
        "paper_on_train": short(paper_train),
    }
    if test is not None:
        evidence.update(
            test_suite=identity.get("test_suite"),
            test=short(test),
            paper_on_test=short(paper_test),
            dominates_paper_on_test=bool(paper_test and dominates_paper(test, paper_test)),
        )
    from viapath.planning.viapath.options import VIAPATH_OPTIONS

    data = {
        "name": path.stem,
        "description": f"trial {trial.number} of study {identity.get('study')!r}",
        "planner": PLANNER,
        "options": VIAPATH_OPTIONS.nest(trial_values(trial)),
        "evidence": evidence,
    }
    preset = preset_from_dict(data, str(path))  # validated before it is written
    path.write_text(preset.to_yaml())


def plot_front(path: Path, study, front: list[Any], paper, test: dict[int, dict] | None = None) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    trials = complete_trials(study)
    feasible = [t for t in trials if is_feasible(t)]
    infeasible = [t for t in trials if not is_feasible(t)]
    panels = 2 if test else 1
    fig, axes = plt.subplots(1, panels, figsize=(6.4 * panels, 4.8), squeeze=False)
    ax = axes[0][0]
    ax.scatter(
        [t.values[1] for t in infeasible],
        [t.values[0] for t in infeasible],
        marker="x",
        color="0.6",
        label=f"infeasible ({len(infeasible)})",
    )
    ax.scatter(
        [t.values[1] for t in feasible],
        [t.values[0] for t in feasible],
        color="tab:blue",
        s=18,
        label=f"feasible ({len(feasible)})",
    )
    ordered = sorted(front, key=lambda t: t.values[1])
    ax.plot(
        [t.values[1] for t in ordered],
        [t.values[0] for t in ordered],
        "-o",
        color="tab:orange",
        ms=6,
        label=f"Pareto front ({len(front)})",
    )
    for t in ordered:
        ax.annotate(str(t.number), (t.values[1], t.values[0]), textcoords="offset points", xytext=(4, 4), fontsize=7)
    if paper is not None:
        ax.scatter(
            [paper.values[1]], [paper.values[0]], marker="*", s=220, color="tab:red", zorder=5, label="paper's weights"
        )
    ax.set_xlabel("median time ratio (time to goal / obstacle-free time)")
    ax.set_ylabel("mean lateral deviation [m]")
    ax.set_title(f"train suite: {len(trials)} trials")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    if test:
        ax = axes[0][1]
        paper_number = paper.number if paper is not None else None
        for number, m in test.items():
            is_paper = number == paper_number
            ax.scatter(
                [m["median_time_ratio"]],
                [m["mean_lateral_deviation_m"]],
                marker="*" if is_paper else "o",
                s=220 if is_paper else 30,
                color="tab:red" if is_paper else "tab:orange",
                zorder=5 if is_paper else 3,
            )
            ax.annotate(
                "paper" if is_paper else str(number),
                (m["median_time_ratio"], m["mean_lateral_deviation_m"]),
                textcoords="offset points",
                xytext=(4, 4),
                fontsize=7,
            )
        ax.set_xlabel("median time ratio")
        ax.set_ylabel("mean lateral deviation [m]")
        ax.set_title("test suite: the front's trials and the paper's")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
