"""One implementation of each step: numba is named only where the compiled steps' one decorator is defined
(``viapath/jit.py``); every compiled step imports that decorator. The files in ``NOT_YET`` still name numba
(their steps still have a second, numpy implementation or a dispatch between the two); a new file that names
it fails, and so does an entry of ``NOT_YET`` once its file no longer does (then delete the entry), so the
list only shrinks."""

from __future__ import annotations

import re
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "viapath"
NUMBA = re.compile(r"\bnumba\b", re.IGNORECASE)
DECORATOR = "jit.py"

NOT_YET: dict[str, str] = {}


def _naming_numba() -> set[str]:
    return {
        path.relative_to(SRC).as_posix() for path in SRC.rglob("*.py") if NUMBA.search(path.read_text(encoding="utf-8"))
    }


def test_only_the_decorator_names_numba():
    unexpected = _naming_numba() - {DECORATOR} - set(NOT_YET)
    assert not unexpected, f"compile with viapath.jit.compiled; do not name numba in: {sorted(unexpected)}"


def test_not_yet_list_only_shrinks():
    done = set(NOT_YET) - _naming_numba()
    assert not done, f"delete from NOT_YET: {sorted(done)}"


def test_the_search_finds_the_decorator():
    """The search itself works (a broken pattern would pass everything)."""
    assert DECORATOR in _naming_numba()
