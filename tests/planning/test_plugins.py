"""Planners from other packages are found through the "viapath.planners" entry-point group; the
registry refuses a second planner under a taken name."""

from importlib.metadata import EntryPoint

import pytest

import viapath.planning as planning
from viapath.planning.base import PLANNERS
from viapath.registry import DuplicateNameError


def _fake_entry_points(*entries):
    return lambda group: [e for e in entries if e.group == group]


@pytest.fixture
def fresh_registry(monkeypatch):
    monkeypatch.setattr(PLANNERS, "_entries", dict(PLANNERS._entries))
    monkeypatch.setattr(planning, "_plugins_loaded", False)


def test_an_entry_point_module_registers_its_planner(monkeypatch, fresh_registry):
    source = (
        "from viapath.planning import Planner, Decision, Plan\n"
        "from viapath.observation import Command\n"
        "class Standstill(Planner, name='test-standstill'):\n"
        "    def decide(self, situation):\n"
        "        return Decision(Command.stop(), Plan('stop', 0.0, situation.position))\n"
    )
    entry = EntryPoint("standstill", "viapath_test_plugin", "viapath.planners")
    monkeypatch.setattr("importlib.metadata.entry_points", _fake_entry_points(entry))
    # Loading the entry point imports the plug-in module, whose class definition registers it.
    monkeypatch.setattr(EntryPoint, "load", lambda self: exec(compile(source, self.value, "exec"), {}))
    assert "test-standstill" not in PLANNERS._entries
    assert "test-standstill" in planning.available_planners()


def test_a_broken_plugin_warns_and_leaves_the_built_ins(monkeypatch, fresh_registry):
    entry = EntryPoint("broken", "no_such_module_for_viapath", "viapath.planners")
    monkeypatch.setattr("importlib.metadata.entry_points", _fake_entry_points(entry))
    with pytest.warns(UserWarning, match="broken"):
        names = planning.available_planners()
    assert {"viapath", "dwa", "follow"} <= set(names)


def test_a_second_planner_of_a_taken_name_is_refused(fresh_registry):
    with pytest.raises(DuplicateNameError, match="'dwa' is already registered"):

        class AnotherDWA(planning.Planner, name="dwa"):
            pass

    assert planning.planner_class("dwa").__name__ == "DWAPlanner"
