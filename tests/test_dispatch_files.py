"""Two execution paths (numpy, compiled), chosen in few places: once per recipe step of the planner, of the shield
and of the laser pipeline, never inside the numpy reference functions. Outside the compiled package
(src/viapath/compiled/) at most five files may name kernels, numba or backends: the ones in ``DISPATCH``. The
files in ``NOT_YET`` still name them (with why); a new file that names them fails, and so does an entry of
``NOT_YET`` once its file no longer does (then delete the entry)."""

from __future__ import annotations

import re
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "viapath"
WORDS = re.compile(r"kernel|numba|backend", re.IGNORECASE)

DISPATCH = {
    "planning/viapath/planner.py": "the planner's recipe: numpy or compiled per step (arithmetic_for, precompile, ...)",
    "safety/shield.py": "the shield's recipe: numpy or compiled per evaluation",
    "perception/detection.py": "the laser chain's retired options (ray_backend, fit_backend...), read with a warning",
    "bench/executors.py": "joblib's executors (loky, dask, ray): joblib's own keyword for them is backend=",
}

NOT_YET: dict[str, str] = {}


def _mentioning() -> set[str]:
    files = set()
    for path in SRC.rglob("*.py"):
        relative = path.relative_to(SRC).as_posix()
        if relative.startswith("compiled/"):
            continue
        if WORDS.search(path.read_text(encoding="utf-8")):
            files.add(relative)
    return files


def test_at_most_five_dispatch_files():
    assert len(DISPATCH) <= 5
    assert not set(DISPATCH) & set(NOT_YET)


def test_no_other_file_names_kernels_or_backends():
    unexpected = _mentioning() - set(DISPATCH) - set(NOT_YET)
    assert not unexpected, f"choose numpy or compiled in a dispatch file, not in: {sorted(unexpected)}"


def test_not_yet_list_only_shrinks():
    """An entry of NOT_YET whose file no longer names them must go (so the list only shrinks)."""
    done = set(NOT_YET) - _mentioning()
    assert not done, f"delete from NOT_YET: {sorted(done)}"


def test_the_words_are_found():
    """The search itself works: the dispatch files do name them (a broken pattern would pass everything)."""
    assert set(DISPATCH) <= _mentioning()
