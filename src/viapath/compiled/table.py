"""Every compiled entry with its numpy reference and the test that holds the two equal.

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


_BACKENDS = "tests/planning/test_backends.py"
_CHOICE = f"{_BACKENDS}::test_compiled_choice_is_the_numpy_choice"
_ESCAPE = f"{_BACKENDS}::test_compiled_escape_is_the_reference"
_CORRIDOR = f"{_BACKENDS}::test_corridor_kernels_match_reference"

ENTRIES = (
    # The viapath planner (viapath.compiled.arithmetic dispatches to them).
    Entry(
        "planning.legs_first_contact",
        "viapath.geometry:legs_first_contact",
        f"{_BACKENDS}::test_kernels_match_reference_on_edge_cases",
    ),
    Entry("planning.track", "viapath.kinematics:track", f"{_BACKENDS}::test_track_kernel_matches_reference"),
    Entry(
        "planning.clear_positions",
        "viapath.planning.viapath.checks:LegChecks.clear",
        f"{_BACKENDS}::test_clear_kernel_gives_the_reference_verdicts",
    ),
    Entry(
        "planning.via_options",
        "viapath.geometry:via_options",
        f"{_BACKENDS}::test_via_options_kernel_matches_reference",
    ),
    Entry("planning.legs_inside", "viapath.path:DesignatedPath.legs_inside", _CORRIDOR),
    Entry("planning.goal_legs_inside", "viapath.path:DesignatedPath.legs_inside", _CORRIDOR),
    Entry(
        "planning.corridor_excess",
        "viapath.path:DesignatedPath.corridor_excess",
        f"{_BACKENDS}::test_escape_scores_match_reference",
    ),
    Entry(
        "planning.escape_contacts",
        "viapath.planning.viapath.escape:escape_scores",
        f"{_BACKENDS}::test_escape_contacts_skip_only_free_steps",
    ),
    Entry("planning.escape_headings", "viapath.planning.viapath.escape:stop_or_escape", _ESCAPE),
    Entry("planning.escape_scores", "viapath.planning.viapath.escape:escape_scores", _ESCAPE),
    Entry(
        "planning.goal_legs",
        "viapath.planning.viapath.checks:LegChecks.goal_legs",
        f"{_BACKENDS}::test_goal_legs_kernel_matches_reference",
    ),
    Entry(
        "planning.grow",
        "viapath.planning.viapath.candidates:grow",
        f"{_BACKENDS}::test_tree_kernel_builds_the_same_candidates",
    ),
    Entry("planning.choose_tree", "viapath.planning.viapath.planner:ViaPathPlanner._choose", _CHOICE),
    Entry("planning.choose_candidate", "viapath.planning.viapath.critics:score", _CHOICE),
    Entry("planning.choose", "viapath.planning.viapath.planner:ViaPathPlanner._choose", _CHOICE),
    # numpy's pairwise summation.
    Entry("sums.pairwise_sum", "numpy:sum", f"{_BACKENDS}::test_escape_kernel_pieces_match_numpy"),
)
