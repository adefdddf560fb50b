"""How many random cases the long property tests draw: a quick count by default, the full count with
``VIAPATH_FULL_TESTS=1`` (or any value but empty or 0) in the environment.

The quick counts keep the default run to minutes; they are large enough that every assertion of the
tests (both sides of each verdict drawn many times) still holds and still fails when a rule is
removed. Run the full counts before a release and after touching the shield or the geometry:
``VIAPATH_FULL_TESTS=1 pytest -n auto tests/safety``."""

from __future__ import annotations

import os

FULL = os.environ.get("VIAPATH_FULL_TESTS", "").strip() not in ("", "0")


def cases(quick: int, full: int) -> int:
    """``full`` under VIAPATH_FULL_TESTS, else ``quick``."""
    return full if FULL else quick
