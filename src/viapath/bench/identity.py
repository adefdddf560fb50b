"""What a benchmark row is, so that a results folder never mixes runs up.

* A row is identified by the scenario's **content hash**, the planner, a hash of the planner's
  **options**, the perception, the episode seed and the **viapath version** (columns
  ``scenario_hash``, ``options_hash``, ``viapath_version``; the scenario name stays for reading).
  The scenario hash is the SHA-256 of the validated scenario as canonical JSON (so comments and
  layout of the file do not count, every value does), with each replay file replaced by the hash of
  its bytes (moving the data folder changes nothing, changing the data does).
* A results folder records what wrote it in ``run.json``: the suite's scenario hashes, the
  perception, the bench seed and the viapath version. Benching another suite or configuration into
  it is refused with a message saying what differs, unless ``--force`` is given; then the folder's
  old rows stay in ``episodes.csv`` but are never reused or reported (their identity differs).
  Adding planners to a folder is not another configuration: their rows are new rows.
* An episode that crashed (its row has an ``error``) is not done: the next resume runs it again;
  the last row of an identity wins.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
from collections.abc import Set as AbstractSet
from functools import lru_cache
from pathlib import Path
from typing import Any

MANIFEST = "run.json"


def viapath_version() -> str:
    try:
        from importlib.metadata import version

        return version("viapath")
    except Exception:
        import viapath

        return getattr(viapath, "__version__", "unknown")


@lru_cache(maxsize=1024)
def _file_hash(path: str) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()[:16]


def scenario_hash(scenario: dict) -> str:
    data = json.loads(json.dumps(scenario))
    for item in data.get("obstacles", []) or []:
        replay = item.get("replay") if isinstance(item, dict) else None
        if isinstance(replay, dict) and replay.get("file"):
            with contextlib.suppress(OSError):  # the run reports the missing file; the name stands in for its content
                replay["file"] = "sha256:" + _file_hash(str(replay["file"]))
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def options_hash(scenario: dict, planner: str, overrides: dict | None = None) -> str:
    """Hash of the options the planner is built with for this scenario (its ``planner:`` block as
    the planner reads it, then ``overrides`` such as ``--weights``; the same for every scenario that
    shares the block)."""
    from viapath.scenarios import scenario_from_dict
    from viapath.scenarios.loader import planner_settings

    try:
        options = {
            **planner_settings(scenario_from_dict(scenario, scenario.get("name", "?")), planner),
            **(overrides or {}),
        }
        # An option that only chooses how the arithmetic runs (decides=False) gives the same rows: left out,
        # under its former names too (an old weights file's).
        left_out = _not_deciding(planner)
        options = {key: value for key, value in options.items() if key not in left_out}
        text = repr(sorted(options.items()))
    except Exception as error:
        text = f"error: {error}"
    return hashlib.sha256(f"{planner}:{text}".encode()).hexdigest()[:16]


def _not_deciding(planner: str) -> set[str]:
    """The names, now and former, of the planner's options that decide nothing (:attr:`Option.decides`), and the
    names it reads and ignores (:attr:`OptionSet.retired`)."""
    from viapath.planning import planner_class

    return set(planner_class(planner).options.retired) | {
        name
        for option in planner_class(planner).options
        if not option.decides
        for name in (option.name, *option.former_names)
    }


def manifest(scenario_hashes: dict[str, str], perception: str, seed: int) -> dict[str, Any]:
    """What a run is: its scenarios (name -> content hash), perception, bench seed, viapath version."""
    return {
        "scenarios": dict(sorted(scenario_hashes.items())),
        "perception": perception,
        "seed": seed,
        "viapath_version": viapath_version(),
    }


def check_folder(
    out_dir: Path, wanted: dict[str, Any], force: bool, crashed_only: AbstractSet[str] = frozenset()
) -> str | None:
    """None if the folder may be used (and then records ``wanted`` in it), else why not.

    Refused: another perception, bench seed or viapath version; a scenario of the same name whose
    content differs (the folder was written by another suite); no scenario in common at all. Growing
    or shrinking the same suite (more or fewer of its scenarios, more planners) is allowed, and so is
    a changed scenario whose every row in the folder crashed (``crashed_only``: the fixed file)."""
    path = Path(out_dir) / MANIFEST
    recorded = dict(wanted)
    if path.exists():
        try:
            found = json.loads(path.read_text())
        except (OSError, ValueError):
            found = {}
        problems = [
            f"{key}: folder has {found.get(key)!r}, this run {wanted[key]!r}"
            for key in ("perception", "seed", "viapath_version")
            if found.get(key) != wanted[key]
        ]
        old, new = found.get("scenarios") or {}, wanted["scenarios"]
        changed = sorted(name for name in set(old) & set(new) if old[name] != new[name] and name not in crashed_only)
        if changed:
            problems.append(
                f"{len(changed)} scenario(s) of the same name have other contents (e.g. {changed[0]!r}): another suite"
            )
        elif old and not set(old) & set(new):
            problems.append("no scenario in common: another suite")
        if problems and not force:
            return (
                f"{out_dir} holds results of another suite or configuration ({'; '.join(problems)}); "
                "use a new --out folder, or --force to add this run's rows beside them "
                "(the old rows are kept but never reused or reported)"
            )
        if not problems:
            recorded["scenarios"] = {**old, **new}
    elif (Path(out_dir) / "episodes.csv").exists() and not force:
        return (
            f"{out_dir} holds an episodes.csv without {MANIFEST} (written before rows were identified by "
            "content); use a new --out folder, or --force"
        )
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(recorded, indent=2))
    return None


def crash_lines(rows: list[dict[str, Any]], limit: int = 10) -> list[str]:
    """One line per crashed episode (the first ``limit``), for the console and summary.md."""
    crashed = [r for r in rows if r.get("error")]
    lines = [f"- {r['scenario']} / {r['planner']} (seed {r['seed']}): {r['error']}" for r in crashed[:limit]]
    if len(crashed) > limit:
        lines.append(f"- … and {len(crashed) - limit} more (see episodes.csv, column error)")
    return lines
