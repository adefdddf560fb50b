"""Every compiled entry with its numpy reference and the test that holds the two equal (the viapath planner's
compiled steps are not listed: each is the one implementation of its step, held by the oracles in tests/planning).

``tests/test_compiled_table.py`` checks this table: every public kernel of the kernel modules is listed, each
reference can be imported, each test exists. A kernel that is only called from another one (the pieces of
``choose``, of the shield's ``shield``) names the test of the entry that calls it. This module imports no numba.
"""

from __future__ import annotations

from typing import NamedTuple

# The critics of Eq. 1 that the compiled choice (planning.choose_candidate) sums, in critics_for's order: a planner
# with any other critic takes the numpy choice, and tests/test_compiled_table.py fails for a critic not listed.
COMPILED_CRITICS = ("distance", "time", "speed", "heading", "side", "hysteresis")


class Entry(NamedTuple):
    kernel: str  # "module.function" in viapath.compiled
    reference: str  # the numpy code it computes, importable: "viapath.module:qualified.name"
    test: str  # "tests/file.py::test_name"


ENTRIES = (
    # numpy's pairwise summation.
    Entry("sums.pairwise_sum", "numpy:sum", "tests/planning/test_compiled_choice.py::test_pairwise_sum_is_numpys_sum"),
)
