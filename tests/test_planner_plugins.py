"""Planners from other packages are found through the "viapath.planners" entry-point group."""

from importlib.metadata import EntryPoint

import pytest

from viapath.planning import base


def _fake_entry_points(*entries):
    return lambda group: [e for e in entries if e.group == group]


def test_an_entry_point_module_registers_its_planner(monkeypatch):
    source = (
        "from viapath.planning import Planner, Decision, Plan\n"
        "from viapath.observation import Command\n"
        "class Standstill(Planner, name='test-standstill'):\n"
        "    def plan(self, observation):\n"
        "        return Decision(Command.stop(), Plan('stop', 0.0, observation.robot.position))\n"
    )
    base.available_planners()  # the built-ins register into the real registry first
    entry = EntryPoint("standstill", "viapath_test_plugin", "viapath.planners")
    monkeypatch.setattr("importlib.metadata.entry_points", _fake_entry_points(entry))
    # Loading the entry point imports the plug-in module, whose class definition registers it.
    monkeypatch.setattr(EntryPoint, "load", lambda self: exec(compile(source, self.value, "exec"), {}))
    monkeypatch.setattr(base, "_REGISTRY", dict(base._REGISTRY))
    assert "test-standstill" not in base._REGISTRY
    assert "test-standstill" in base.available_planners()


def test_a_broken_plugin_warns_and_leaves_the_built_ins(monkeypatch):
    entry = EntryPoint("broken", "no_such_module_for_viapath", "viapath.planners")
    monkeypatch.setattr("importlib.metadata.entry_points", _fake_entry_points(entry))
    with pytest.warns(UserWarning, match="broken"):
        names = base.available_planners()
    assert {"viapath", "dwa", "follow"} <= set(names)
