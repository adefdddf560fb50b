"""How pytest-xdist shares the tests out (the README's test command: ``pytest -n auto --dist loadgroup``).

Every test is a unit of its own, sent to whichever worker is free, except two groups that must stay on
one worker, in order:

* the ROS 2 end-to-end tests that read the session launcher's processes (``tests/ros2/conftest.py``):
  one launcher starts them all at once; on two workers it would start them twice;
* ``tests/test_examples.py``: a page's examples run in order in one folder (later blocks use what
  earlier ones wrote); ``tests/tune/test_tune.py``: its tests read the folders of one study and
  of a bench the tests before them wrote; ``tests/planning/test_compiled_choice.py``: a test counts the
  cycles with recorded candidates that the property test before it saw.

The groups are made here from the test files (the scheduler below), not from ``xdist_group`` marks:
with pytest 9.2, pytest-xdist 3.8's ``--dist loadgroup`` loses the marks' groups (it writes a node-id
field pytest no longer reads; pytest-xdist issue 1386) and would send each test anywhere.

A ``viapath run`` with a cold cache of compiled steps would run plain Python and leave a compiler running in the
background (viapath.precompile): the suite switches that off (``VIAPATH_BACKGROUND_COMPILE=0``, inherited by the
commands the tests start), so a cold test compiles in its own process; tests/test_cold_run.py switches it on
for its own commands and ends what they start.

Property tests draw the same cases on every run (hypothesis ``derandomize``), so a run's verdict is the code's,
not the draw's; ``VIAPATH_FULL_TESTS=1`` draws new ones each run (tests/_sizes.py), for searching, with the
counts at their full sizes.
"""

from __future__ import annotations

import os

import pytest
from hypothesis import settings

from tests._sizes import FULL

os.environ["VIAPATH_BACKGROUND_COMPILE"] = "0"

settings.register_profile("viapath-tests", derandomize=not FULL)
settings.load_profile("viapath-tests")

LAUNCHER_FILES = (
    "tests/ros2/test_ros2_e2e.py",
    "tests/ros2/test_ros2_faults.py",
    "tests/ros2/test_ros2_nav2.py",
    "tests/ros2/test_ros2_play.py",
)
IN_ORDER_FILES = ("tests/test_examples.py", "tests/tune/test_tune.py", "tests/planning/test_compiled_choice.py")


def group_of(nodeid: str) -> str | None:
    """The group a test belongs to, or None (a unit of its own)."""
    path = nodeid.split("::", 1)[0]
    if path in LAUNCHER_FILES:
        return "ros2-launcher"
    if path in IN_ORDER_FILES:
        return path
    return None


@pytest.hookimpl(optionalhook=True, tryfirst=True)
def pytest_xdist_make_scheduler(config, log):
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadGroupScheduling

    class FileGroups(LoadGroupScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return group_of(nodeid) or super()._split_scope(nodeid)

    return FileGroups(config, log)
