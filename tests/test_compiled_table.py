"""The table of compiled entries (:mod:`viapath.compiled.table`) is complete and true: every public kernel of the
kernel modules is listed, each numpy reference can be imported, each equality test exists; every critic of the
viapath planner is compiled; the layouts the kernels compile in carry their digest (numba's cache notices a
change of the kernel's own file only)."""

from __future__ import annotations

import ast
import importlib
import inspect
from pathlib import Path

import pytest

from viapath.compiled import KERNEL_MODULES, dependency_digest
from viapath.compiled.table import COMPILED_CRITICS, ENTRIES

ROOT = Path(__file__).resolve().parents[1]
COMPILED = ROOT / "src" / "viapath" / "compiled"


def _public_kernels(module: str) -> set[str]:
    """The module-level functions of a kernel module whose names do not start with an underscore (read from
    the source: no numba needed)."""
    tree = ast.parse((COMPILED / f"{module}.py").read_text())
    return {f"{module}.{node.name}" for node in tree.body if isinstance(node, ast.FunctionDef) and node.name[0] != "_"}


def test_every_kernel_is_listed_once():
    listed = [entry.kernel for entry in ENTRIES]
    assert len(listed) == len(set(listed))
    # The laser chain's compiled steps live with their feature (viapath.perception), and the planner's are each the
    # one implementation of its step (no numpy twin to list).
    modules = [module for module in (*KERNEL_MODULES, "sums") if module not in ("perception", "planning")]
    kernels = set().union(*(_public_kernels(module) for module in modules))
    assert kernels - set(listed) == set(), "compiled entries missing from viapath.compiled.table"
    assert set(listed) - kernels == set(), "viapath.compiled.table lists what is not a kernel"


@pytest.mark.parametrize("entry", ENTRIES, ids=lambda entry: entry.kernel)
def test_each_reference_imports_and_each_test_exists(entry):
    module_name, _, qualified = entry.reference.partition(":")
    target = importlib.import_module(module_name)
    for part in qualified.split("."):
        target = getattr(target, part)
    assert callable(target)
    assert not inspect.getmodule(target).__name__.startswith("viapath.compiled"), "a reference is numpy code"
    file, _, test = entry.test.partition("::")
    tree = ast.parse((ROOT / file).read_text())
    assert test in {node.name for node in tree.body if isinstance(node, ast.FunctionDef)}, entry.test


def test_every_critic_of_the_planner_is_compiled():
    """A new critic (a Critic subclass in critics.py) must get its term in planning.choose_candidate and its name
    in COMPILED_CRITICS; until then the planner would quietly take the numpy choice with it."""
    from viapath.planning.viapath import critics
    from viapath.planning.viapath.options import VIAPATH_OPTIONS

    defined = [
        value
        for value in vars(critics).values()
        if isinstance(value, type) and issubclass(value, critics.Critic) and value is not critics.Critic
    ]
    missing = [cls.__name__ for cls in defined if cls.name not in COMPILED_CRITICS]
    assert not missing, (
        f"critics without a compiled twin (planning.choose_candidate, table.COMPILED_CRITICS): {missing}"
    )
    default = critics.critics_for(VIAPATH_OPTIONS.validate({}, where="test"))
    assert tuple(critic.name for critic in default) == COMPILED_CRITICS
    assert tuple(map(type, default)) == critics.PAPER_CRITICS


@pytest.mark.parametrize("module", ["planning"])
def test_each_kernel_module_carries_the_digest_of_what_it_compiles_in(module):
    tree = ast.parse((COMPILED / f"{module}.py").read_text())
    values = {
        node.targets[0].id: ast.literal_eval(node.value)
        for node in tree.body
        if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name)
        if node.targets[0].id in ("DEPENDENCIES", "DEPENDENCY_DIGEST")
    }
    assert dependency_digest(values["DEPENDENCIES"]) == values["DEPENDENCY_DIGEST"], (
        f"viapath/compiled/{module}.py: set DEPENDENCY_DIGEST = {dependency_digest(values['DEPENDENCIES'])!r}"
    )


def test_a_changed_layout_changes_the_digest(tmp_path, monkeypatch):
    """The digest follows the files' bytes: a slot renumbered in slots.py gives another digest."""
    import viapath.compiled as compiled

    for name in ("slots", "sums"):
        (tmp_path / f"{name}.py").write_bytes((COMPILED / f"{name}.py").read_bytes())
    monkeypatch.setattr(compiled, "__file__", str(tmp_path / "__init__.py"))
    before = dependency_digest(("slots", "sums"))
    slots = tmp_path / "slots.py"
    slots.write_text(slots.read_text().replace("C_COUNT = 20", "C_COUNT = 21"))
    assert dependency_digest(("slots", "sums")) != before
