"""``viapath tune`` (issue 15): a small real study on a tiny suite, checked from the outside.

* The Pareto front printed by ``--json`` is checked by brute force over every trial in the storage
  (read with Optuna directly): no feasible trial dominates a front trial, every feasible trial off the
  front is dominated by one on it, and no infeasible trial is on it.
* Constraint marking is recomputed from each trial's metrics and the limits given on the command line.
* Resuming with the same storage continues the trial count (``--trials`` is the total).
* An exported preset, benched with ``viapath bench --weights``, gives the trial's metrics again.
* Bad input: exit 2, one message, no file written.
"""

from __future__ import annotations

import csv
import json
import sys

import pytest
from typer.testing import CliRunner

optuna = pytest.importorskip("optuna", reason="viapath tune needs the extra 'tune' (Optuna)")

from tests.tune._tiny import write_tiny_suite  # noqa: E402 -- after the importorskip of optuna
from viapath.cli import app  # noqa: E402


def _invoke(*args):
    result = CliRunner().invoke(app, [str(a) for a in args])
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result


@pytest.fixture(scope="module")
def study_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tune")
    suite = write_tiny_suite(folder / "suite")
    storage = f"sqlite:///{folder / 'tune.db'}"
    common = [suite, "--workers", "1", "--storage", storage, "--study", "tiny", "--seed", "3", "--json"]
    first = _invoke("tune", *common, "--trials", "4")
    assert first.exit_code == 0, first.output
    first_trials = {t.number: dict(t.params) for t in optuna.load_study(study_name="tiny", storage=storage).trials}
    second = _invoke(
        "tune", *common, "--trials", "7", "--export", folder / "picked.yaml", "--plot", folder / "front.png"
    )
    assert second.exit_code == 0, second.output
    return {
        "folder": folder,
        "suite": suite,
        "storage": storage,
        "first": json.loads(first.stdout),
        "first_trials": first_trials,
        "second": json.loads(second.stdout),
    }


def _objectives(trial):
    m = trial.user_attrs["metrics"]
    return m["mean_lateral_deviation_m"], m["median_time_ratio"]


def _dominates(a, b):
    return a[0] <= b[0] and a[1] <= b[1] and a != b


def _feasible(metrics):  # the command-line defaults: 0 at-fault, 0.25 s/episode outside, 0 misses (without contact)
    return (
        metrics["at_fault"] <= 0 and metrics["outside_s_per_episode"] <= 0.25 and metrics["misses_without_contact"] <= 0
    )


def test_front_is_the_non_dominated_feasible_set(study_run):
    trials = [
        t
        for t in optuna.load_study(study_name="tiny", storage=study_run["storage"]).trials
        if t.state == optuna.trial.TrialState.COMPLETE
    ]
    feasible = [t for t in trials if _feasible(t.user_attrs["metrics"])]
    infeasible = [t for t in trials if not _feasible(t.user_attrs["metrics"])]
    assert feasible and infeasible, "the tiny suite is made to give both kinds of trial"
    front = {item["trial"] for item in study_run["second"]["front"]}
    assert front and front <= {t.number for t in feasible}
    for trial in feasible:
        beaten = any(_dominates(_objectives(o), _objectives(trial)) for o in feasible)
        assert (trial.number in front) == (not beaten) or (
            # equal objectives: Optuna keeps every copy of a non-dominated point
            not beaten and any(_objectives(o) == _objectives(trial) for o in feasible if o.number in front)
        )


def test_constraints_are_marked_from_the_metrics(study_run):
    study = optuna.load_study(study_name="tiny", storage=study_run["storage"])
    for trial in study.trials:
        if trial.state != optuna.trial.TrialState.COMPLETE:
            continue
        m = trial.user_attrs["metrics"]
        # Optuna's own record of the constraints (what its samplers and best_trials read); Optuna 5 keys
        # them by name (Trial.set_constraint), 3.6-4.x as a list from constraints_func.
        stored = getattr(trial, "constraints", None) or dict(enumerate(trial.system_attrs.get("constraints", [])))
        assert len(stored) == 3
        assert (max(stored.values()) <= 0) == _feasible(m)
        assert stored.get("misses_without_contact", stored.get(2)) == m["misses_without_contact"]  # max-misses 0
    paper = study_run["second"]["paper"]
    assert paper["trial"] == 0 and paper["params"] == {"k1": 0.1, "k2": 0.001, "k3": 0.08, "k4": 0.3}
    assert paper["train"]["misses"] == 1 and not paper["feasible"]  # the paper's k2 is too slow for 9.5 s


def test_a_rerun_continues_the_study(study_run):
    assert study_run["first"]["trials"] == 4 and study_run["second"]["trials"] == 7
    assert study_run["second"]["ran"] == 3
    study = optuna.load_study(study_name="tiny", storage=study_run["storage"])
    numbers = sorted(t.number for t in study.trials)
    assert numbers == list(range(7))
    for number, params in study_run["first_trials"].items():  # the first run's trials are kept as they were
        assert study.trials[number].params == params
    later = [tuple(sorted(t.params.items())) for t in study.trials[4:]]
    assert not set(later) & {tuple(sorted(p.items())) for p in study_run["first_trials"].values()}
    again = _invoke(
        "tune",
        study_run["suite"],
        "--workers",
        "1",
        "--storage",
        study_run["storage"],
        "--study",
        "tiny",
        "--seed",
        "3",
        "--trials",
        "7",
        "--json",
    )
    assert again.exit_code == 0 and json.loads(again.stdout)["ran"] == 0


def test_exported_preset_gives_the_trials_metrics_again(study_run):
    from viapath.bench.runner import read_rows
    from viapath.bench.tune import suite_metrics
    from viapath.presets import load_preset

    folder = study_run["folder"]
    preset = load_preset(folder / "picked.yaml")
    study = optuna.load_study(study_name="tiny", storage=study_run["storage"])
    trial = study.trials[preset.evidence["trial"]]
    assert preset.options == trial.params
    assert (folder / "front.png").stat().st_size > 10_000
    out = folder / "bench"
    result = _invoke(
        "bench",
        study_run["suite"],
        "--planners",
        "viapath",
        "--weights",
        folder / "picked.yaml",
        "--workers",
        "1",
        "--seed",
        "3",
        "--out",
        out,
        "--no-plots",
        "--json",
    )
    assert result.exit_code == 0, result.output
    again = suite_metrics(read_rows(out / "episodes.csv"))
    for key, value in trial.user_attrs["metrics"].items():
        assert again[key] == pytest.approx(value), key


@pytest.mark.parametrize(
    "args, message",
    [
        (["--param", "k9=0.1:1"], "unknown option 'k9'"),
        (["--param", "k1=1:0.5"], "empty range"),
        (["--param", "k1=0.5"], "expected NAME=LOW:HIGH"),
        (["--param", "preferred_side=0:1"], "not a number"),
        (["--storage", "sqlite:///{tmp}/missing/folder/t.db"], "does not exist"),
        (["--storage", "sqlite:///{tmp}/junk.db"], "not an SQLite database"),
        (["--storage", "nonsense"], "expected a database URL"),
        (["--suite", "no-such-suite"], "not a folder of scenario files nor a suite name"),
        (["--test", "no-such-suite"], "not a folder of scenario files nor a suite name"),
    ],
)
def test_bad_input_is_one_message_exit_2_nothing_written(tmp_path, args, message):
    suite = write_tiny_suite(tmp_path / "suite")
    (tmp_path / "junk.db").write_text("not a database")
    before = sorted(p.name for p in tmp_path.rglob("*"))
    storage = f"sqlite:///{tmp_path / 'tune.db'}"
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    if args[0] == "--suite":
        suite, args = args[1], []
    if args and args[0] == "--storage":
        storage, args = args[1], []
    result = _invoke("tune", suite, "--trials", "2", "--workers", "1", "--storage", storage, "--study", "s", *args)
    assert result.exit_code == 2, result.output
    assert message in result.output and "Traceback" not in result.output
    assert sorted(p.name for p in tmp_path.rglob("*")) == before


def test_without_optuna_one_message_exit_2(tmp_path, monkeypatch):
    suite = write_tiny_suite(tmp_path / "suite")
    monkeypatch.setitem(sys.modules, "optuna", None)
    result = _invoke("tune", suite, "--storage", f"sqlite:///{tmp_path / 't.db'}", "--study", "s")
    assert result.exit_code == 2 and "pip install 'viapath[tune]'" in result.output
    assert not (tmp_path / "t.db").exists()


def test_bench_rows_read_back(study_run):
    """The bench folder of the round trip holds one row per scenario, with the preset's options hash."""
    with open(study_run["folder"] / "bench" / "episodes.csv") as file:
        rows = list(csv.DictReader(file))
    assert len(rows) == 2 and len({r["options_hash"] for r in rows}) == 1


def test_on_a_terminal_trials_and_the_running_trials_episodes_show_progress(tmp_path, monkeypatch):
    """As ``viapath bench``: a bar of trials and one of the running trial's episodes (a trial on a large
    suite takes minutes), also while the chosen trials run on the test suite."""
    import io

    from rich.console import Console

    import viapath.cli.tune as tune_cli

    screen = io.StringIO()
    monkeypatch.setattr(tune_cli, "errors", Console(file=screen, force_terminal=True, width=160))
    suite = write_tiny_suite(tmp_path / "suite")
    storage = f"sqlite:///{tmp_path / 'tune.db'}"
    result = _invoke(
        "tune", suite, "--trials", "2", "--workers", "1", "--storage", storage, "--study", "bars", "--test", suite
    )
    colorama = sys.modules.get("colorama.initialise")
    if colorama is not None and getattr(colorama, "orig_stdout", None) is not None:
        # numba's coloured messages start colorama under the bar: it kept the bar's proxy of the runner's
        # stdout, closed now, for its exit handler
        colorama.orig_stdout, colorama.orig_stderr = sys.__stdout__, sys.__stderr__
    assert result.exit_code == 0, result.output
    shown = screen.getvalue()
    # the last frame of each bar: both trials done, every episode of the last trial done (2 scenarios)
    assert "trials" in shown and "2/2" in shown and "testing" in shown
    episode_lines = [line for line in shown.splitlines() if "episodes" in line and "of the running trial" in line]
    assert episode_lines and any("2/2" in line for line in episode_lines), shown[-2000:]
    assert any("1/2" in line for line in shown.replace("\r", "\n").splitlines()) or "0/2" in shown
