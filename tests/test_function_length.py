"""No function over 80 lines in src outside the compiled package, and none over 150 lines inside it (numba
kernels are written as one loop nest on purpose; the last tests). A function outside that must stay longer
is listed in KNOWN_EXCEPTIONS with the reason; a new long function fails, and so does an entry once its
function is short (then delete the entry)."""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
MAX_LINES = 80

KNOWN_EXCEPTIONS: dict[tuple[str, str], str] = {}  # (file, function) -> why it is still long; empty now


def long_functions(root: Path = SRC, limit: int = MAX_LINES) -> dict[tuple[str, str], int]:
    """(file relative to ``root``, function name) -> lines, for every function (nested ones too) over ``limit``."""
    found = {}
    for file in sorted(root.rglob("*.py")):
        relative = file.relative_to(root).as_posix()
        if relative.startswith("viapath/compiled/"):  # the compiled package: its own limit (150, below)
            continue
        for node in ast.walk(ast.parse(file.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines > limit:
                    found[(relative, node.name)] = lines
    return found


def test_no_new_function_over_80_lines():
    new = {key: lines for key, lines in long_functions().items() if key not in KNOWN_EXCEPTIONS}
    assert new == {}, "functions over 80 lines (split them): " + ", ".join(
        f"{file}:{name} ({lines} lines)" for (file, name), lines in sorted(new.items())
    )


def test_every_known_exception_is_still_long():
    """An entry whose function is now short (or gone) is deleted from the list, so the list only shrinks."""
    found = long_functions()
    assert sorted(key for key in KNOWN_EXCEPTIONS if key not in found) == []


def test_the_counter_counts_a_planted_long_function(tmp_path):
    package = tmp_path / "viapath"
    package.mkdir()
    body = "\n".join(f"    x{i} = {i}" for i in range(80))
    (package / "long.py").write_text(f"def long():\n{body}\n\n\ndef short():\n    return 1\n")
    assert long_functions(tmp_path) == {("viapath/long.py", "long"): 81}


COMPILED = SRC / "viapath" / "compiled"
MAX_COMPILED_LINES = 150


def compiled_long_functions(root: Path = COMPILED, limit: int = MAX_COMPILED_LINES) -> dict[tuple[str, str], int]:
    """(file relative to ``root``, function name) -> lines, for every function of the compiled package (nested
    ones too) over ``limit``: the kernels may be long loop nests, but none over 150 lines."""
    found = {}
    for file in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(file.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines > limit:
                    found[(file.relative_to(root).as_posix(), node.name)] = lines
    return found


def test_no_function_of_the_compiled_package_is_over_150_lines():
    assert any(COMPILED.rglob("*.py")), COMPILED
    long = compiled_long_functions()
    assert long == {}, "compiled functions over 150 lines (split them): " + ", ".join(
        f"{file}:{name} ({lines} lines)" for (file, name), lines in sorted(long.items())
    )


def test_the_compiled_counter_counts_a_planted_long_function(tmp_path):
    body = "\n".join(f"    x{i} = {i}" for i in range(150))
    (tmp_path / "kernels.py").write_text(f"def long():\n{body}\n\n\ndef short():\n    return 1\n")
    (tmp_path / "limit.py").write_text("def at_limit():\n" + "\n".join(f"    y{i} = {i}" for i in range(149)) + "\n")
    assert compiled_long_functions(tmp_path) == {("kernels.py", "long"): 151}


# The laser chain (viapath.perception: ray casting, detection, tracking, static layer): functions of at most
# 60 lines, classes of at most 300, compiled steps included.
PERCEPTION = SRC / "viapath" / "perception"
MAX_PERCEPTION_FUNCTION_LINES = 60
MAX_PERCEPTION_CLASS_LINES = 300


def laser_chain_long_definitions(root: Path, kinds: tuple[type, ...], limit: int) -> dict[tuple[str, str], int]:
    """(file relative to ``root``, name) -> lines, for every definition of one of ``kinds`` (nested ones too)
    over ``limit`` lines."""
    found = {}
    for file in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(file.read_text())):
            if isinstance(node, kinds):
                lines = node.end_lineno - node.lineno + 1
                if lines > limit:
                    found[(file.relative_to(root).as_posix(), node.name)] = lines
    return found


def test_no_function_of_the_laser_chain_is_over_60_lines():
    assert any(PERCEPTION.rglob("*.py")), PERCEPTION
    long = laser_chain_long_definitions(
        PERCEPTION, (ast.FunctionDef, ast.AsyncFunctionDef), MAX_PERCEPTION_FUNCTION_LINES
    )
    assert long == {}, "laser chain functions over 60 lines (split them): " + ", ".join(
        f"{file}:{name} ({lines} lines)" for (file, name), lines in sorted(long.items())
    )


def test_no_class_of_the_laser_chain_is_over_300_lines():
    long = laser_chain_long_definitions(PERCEPTION, (ast.ClassDef,), MAX_PERCEPTION_CLASS_LINES)
    assert long == {}, "laser chain classes over 300 lines (split them): " + ", ".join(
        f"{file}:{name} ({lines} lines)" for (file, name), lines in sorted(long.items())
    )


def test_the_definition_counter_counts_planted_long_ones(tmp_path):
    body = "\n".join(f"        x{i} = {i}" for i in range(60))
    (tmp_path / "chain.py").write_text(
        f"class Chain:\n    def long(self):\n{body}\n\n    def short(self):\n        return 1\n"
    )
    functions = laser_chain_long_definitions(tmp_path, (ast.FunctionDef,), 60)
    assert functions == {("chain.py", "long"): 61}
    assert laser_chain_long_definitions(tmp_path, (ast.ClassDef,), 64) == {("chain.py", "Chain"): 65}
    assert laser_chain_long_definitions(tmp_path, (ast.ClassDef,), 65) == {}


# The viapath planner (its package and its compiled steps): no function over 60 lines, no class over 300. What is
# still longer is listed with its length; the list only shrinks (a listed entry that is short now fails too).
PLANNER_FILES = ("viapath/planning/viapath", "viapath/compiled/planning.py", "viapath/compiled/arithmetic.py")
PLANNER_FUNCTION_LINES, PLANNER_CLASS_LINES = 60, 300
PLANNER_NOT_YET: dict[tuple[str, str], str] = {
    **{
        ("viapath/compiled/planning.py", name): "one loop nest, to be split into inlined steps"
        for name in (
            "legs_inside",
            "escape_contacts",
            "escape_scores",
            "_goal_legs_of",
            "_slow_nodes",
            "_corner_nodes",
            "_via_legs",
            "_via_children",
            "grow",
            "_follows",
            "choose_candidate",
        )
    },
}


def planner_long_definitions(root: Path = SRC) -> dict[tuple[str, str], int]:
    """(file relative to ``root``, function or class name) -> lines, for the planner's functions over 60 lines and
    classes over 300."""
    found = {}
    files = [path for part in PLANNER_FILES for path in sorted((root / part).rglob("*.py")) or [root / part]]
    for file in files:
        if not file.exists():
            continue
        for node in ast.walk(ast.parse(file.read_text())):
            limit = PLANNER_CLASS_LINES if isinstance(node, ast.ClassDef) else PLANNER_FUNCTION_LINES
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines > limit:
                    found[(file.relative_to(root).as_posix(), node.name)] = lines
    return found


def test_no_new_planner_function_over_60_lines_or_class_over_300():
    found = planner_long_definitions()
    new = {key: lines for key, lines in found.items() if key not in PLANNER_NOT_YET}
    assert new == {}, "planner functions over 60 lines or classes over 300 (split them): " + ", ".join(
        f"{file}:{name} ({lines} lines)" for (file, name), lines in sorted(new.items())
    )
    assert sorted(key for key in PLANNER_NOT_YET if key not in found) == [], "delete these from PLANNER_NOT_YET"


def test_the_planner_counter_counts_a_planted_long_class(tmp_path):
    package = tmp_path / "viapath" / "planning" / "viapath"
    package.mkdir(parents=True)
    body = "\n".join(f"    x{i} = {i}" for i in range(300))
    (package / "long.py").write_text(f"class Long:\n{body}\n\n\ndef short():\n    return 1\n")
    assert planner_long_definitions(tmp_path) == {("viapath/planning/viapath/long.py", "Long"): 301}
