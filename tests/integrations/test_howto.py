"""The how-to pages' world and experiment files and scripts run as written, and their option tables name
exactly the options the behaviours have."""

from __future__ import annotations

import contextlib
import io
import os
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
HOWTO = ROOT / "docs" / "howto"


def _blocks(page: str, language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", (HOWTO / page).read_text(), flags=re.S)


def _run_block(block: str, name: str) -> tuple[dict, str]:
    namespace: dict = {}
    out = io.StringIO()
    cwd = os.getcwd()
    os.chdir(ROOT)  # the pages' paths are relative to the repository, as a user runs them from a clone
    try:
        with contextlib.redirect_stdout(out):
            exec(compile(block, name, "exec"), namespace)
    finally:
        os.chdir(cwd)
    return namespace, out.getvalue()


def _table_names(page: str) -> set[str]:
    return set(re.findall(r"^\| `([a-z_0-9]+)` \|", (HOWTO / page).read_text(), flags=re.M))


def test_irsim_page_world_is_the_example_file_and_its_script_runs_as_written():
    pytest.importorskip("irsim", reason="IR-SIM is not installed (extra 'irsim')")
    (world,) = _blocks("irsim.md", "yaml")
    assert world == (ROOT / "examples" / "irsim" / "crossing.yaml").read_text()
    (script,) = _blocks("irsim.md", "python")
    namespace, out = _run_block(script, "docs/howto/irsim.md")
    assert namespace["env"].robot.arrive and namespace["collided"] is False
    assert "\narrived: True collided: False time: " in "\n" + out


def test_irsim_page_lists_every_option_the_behaviour_adds():
    pytest.importorskip("irsim", reason="IR-SIM is not installed (extra 'irsim')")
    from viapath.integrations.host import HOST_OPTIONS
    from viapath.integrations.irsim import IRSIM_OPTIONS

    assert _table_names("irsim.md") == {*HOST_OPTIONS.names, *IRSIM_OPTIONS.names, "path"}


def test_navground_page_experiment_is_the_example_file_and_its_script_runs_as_written():
    pytest.importorskip("navground", reason="navground is not installed (extra 'navground')")
    import viapath.integrations.navground  # noqa: F401  (load_plugins finds it only in an installed viapath)

    (experiment,) = _blocks("navground.md", "yaml")
    assert experiment == (ROOT / "examples" / "navground" / "crossing.yaml").read_text()
    script, python_api = _blocks("navground.md", "python")
    namespace, out = _run_block(script, "docs/howto/navground.md")
    assert "\ncollisions: 0 robot at: " in "\n" + out
    assert np.hypot(*(np.asarray(namespace["final"][:2]) - [9.0, 0.0])) <= 0.1 + 1e-6
    namespace, out = _run_block(python_api, "docs/howto/navground.md, From Python")
    assert np.hypot(*(np.asarray(namespace["robot"].position) - [5.0, 0.0])) <= 0.1 + 1e-6
    assert namespace["lowest"] < -0.3  # passed on the right, as asked
    assert "\nat [" in "\n" + out and "passed on the right by" in out


def test_navground_page_lists_every_property_the_behaviour_adds():
    pytest.importorskip("navground", reason="navground is not installed (extra 'navground')")
    from viapath.integrations.host import HOST_OPTIONS
    from viapath.integrations.navground import NAVGROUND_OPTIONS

    assert _table_names("navground.md") == {*HOST_OPTIONS.names, *NAVGROUND_OPTIONS.names, "path"}
