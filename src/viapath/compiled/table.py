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


_SHIELD = "tests/safety/test_shield_backends.py::test_numba_shield_gives_the_numpy_verdicts"
_HARNESS = "tests/robustness/test_harness_kernels.py"

ENTRIES = (
    # The passive-safety shield.
    Entry("shield.braking_sweep", "viapath.safety.shield:braking_sweep", _SHIELD),
    Entry("shield.achieved_first_period", "viapath.safety.shield:achieved_first_period", _SHIELD),
    Entry("shield.evaluate", "viapath.safety.shield:Shield.evaluate", _SHIELD),
    Entry("shield.candidates", "viapath.safety.shield:Shield.candidates", _SHIELD),
    Entry("shield.shield", "viapath.safety.shield:Shield.filter", _SHIELD),
    # The harness every planner gets (guard, inflation).
    Entry(
        "harness.obstacles_sound",
        "viapath.guard:_obstacles_sound",
        f"{_HARNESS}::test_obstacles_sound_agrees_with_the_numpy_reductions",
    ),
    Entry(
        "harness.first_touched",
        "viapath.guard:check_command",
        f"{_HARNESS}::test_the_braking_test_agrees_with_check_commands_numpy_code",
    ),
    Entry(
        "harness.inflation",
        "viapath.planning.base:Inflation.of",
        f"{_HARNESS}::test_inflation_is_the_numpy_inflation_bit_for_bit",
    ),
    Entry(
        "harness.situation_numbers",
        "viapath.planning.base:Planner.situation",
        f"{_HARNESS}::test_the_situations_inflation_and_corridor_excess_are_the_numpy_ones_bit_for_bit",
    ),
    # numpy's pairwise summation.
    Entry("sums.pairwise_sum", "numpy:sum", "tests/planning/test_compiled_choice.py::test_pairwise_sum_is_numpys_sum"),
)
