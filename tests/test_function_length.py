"""No function over 80 lines in src, except the compiled steps (decorated with ``compiled``): none of them over 150
lines (they are written as one loop nest on purpose; the last tests). A function outside that must stay longer
is listed in KNOWN_EXCEPTIONS with the reason; a new long function fails, and so does an entry once its
function is short (then delete the entry)."""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
MAX_LINES = 80

KNOWN_EXCEPTIONS: dict[tuple[str, str], str] = {}  # (file, function) -> why it is still long; empty now


def _is_compiled(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    """Whether the function is a compiled step: decorated with ``compiled`` (bare or with keywords)."""
    return any(
        isinstance(target := (d.func if isinstance(d, ast.Call) else d), ast.Name) and target.id == "compiled"
        for d in node.decorator_list
    )


def long_functions(root: Path = SRC, limit: int = MAX_LINES) -> dict[tuple[str, str], int]:
    """(file relative to ``root``, function name) -> lines, for every function (nested ones too) over ``limit``."""
    found = {}
    for file in sorted(root.rglob("*.py")):
        relative = file.relative_to(root).as_posix()
        for node in ast.walk(ast.parse(file.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and not _is_compiled(node):
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


MAX_COMPILED_LINES = 150


def compiled_long_functions(root: Path = SRC, limit: int = MAX_COMPILED_LINES) -> dict[tuple[str, str], int]:
    """(file relative to ``root``, function name) -> lines, for every compiled step (nested functions too) over
    ``limit``: the compiled steps may be long loop nests, but none over 150 lines."""
    found = {}
    for file in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(file.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and _is_compiled(node):
                lines = node.end_lineno - node.lineno + 1
                if lines > limit:
                    found[(file.relative_to(root).as_posix(), node.name)] = lines
    return found


def test_no_compiled_step_is_over_150_lines():
    assert (
        sum(
            _is_compiled(node)
            for file in SRC.rglob("*.py")
            for node in ast.walk(ast.parse(file.read_text()))
            if isinstance(node, ast.FunctionDef)
        )
        >= 40
    )
    long = compiled_long_functions()
    assert long == {}, "compiled functions over 150 lines (split them): " + ", ".join(
        f"{file}:{name} ({lines} lines)" for (file, name), lines in sorted(long.items())
    )


def test_the_compiled_counter_counts_a_planted_long_function(tmp_path):
    body = "\n".join(f"    x{i} = {i}" for i in range(150))
    (tmp_path / "kernels.py").write_text(
        f"@compiled\ndef long():\n{body}\n\n\n@compiled(inline=True)\ndef short():\n    return 1\n\n\n"
        f"def plain():\n{body}\n"
    )
    (tmp_path / "limit.py").write_text(
        "@compiled\ndef at_limit():\n" + "\n".join(f"    y{i} = {i}" for i in range(149)) + "\n"
    )
    assert compiled_long_functions(tmp_path) == {("kernels.py", "long"): 151}
    assert long_functions(tmp_path) == {("kernels.py", "plain"): 151}  # a compiled step has the 150-line limit


# The steps written once (the shield, the guard, the laser chain): no function over 60 lines and no class over
# 300 lines in them, compiled steps included.
ONCE_WRITTEN = ("viapath/safety/*.py", "viapath/guard.py", "viapath/guard_checks.py", "viapath/perception/*.py")
PLANNER = ("viapath/planning/viapath/*.py",)
MAX_ONCE_FUNCTION_LINES, MAX_ONCE_CLASS_LINES = 60, 300


def long_definitions(
    root: Path = SRC,
    patterns: tuple[str, ...] = ONCE_WRITTEN,
    function_limit: int = MAX_ONCE_FUNCTION_LINES,
    class_limit: int = MAX_ONCE_CLASS_LINES,
) -> dict[tuple[str, str], int]:
    """(file relative to ``root``, name) -> lines, for every function over ``function_limit`` and every class over
    ``class_limit`` (nested ones too) in the files ``patterns`` match."""
    found = {}
    for file in sorted({file for pattern in patterns for file in root.glob(pattern)}):
        for node in ast.walk(ast.parse(file.read_text())):
            limit = (
                function_limit
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
                else class_limit
                if isinstance(node, ast.ClassDef)
                else None
            )
            if limit is not None and node.end_lineno - node.lineno + 1 > limit:
                found[(file.relative_to(root).as_posix(), node.name)] = node.end_lineno - node.lineno + 1
    return found


def test_the_steps_written_once_have_no_function_over_60_lines_nor_class_over_300():
    assert len({file for pattern in ONCE_WRITTEN for file in SRC.glob(pattern)}) >= 20
    long = long_definitions()
    assert long == {}, "split them: " + ", ".join(
        f"{file}:{name} ({lines} lines)" for (file, name), lines in long.items()
    )


def test_the_once_written_counter_counts_a_planted_long_function_and_class(tmp_path):
    (tmp_path / "viapath" / "safety").mkdir(parents=True)
    body = "\n".join(f"    x{i} = {i}" for i in range(60))
    methods = "\n".join(f"    def m{i}(self):\n        return {i}\n" for i in range(101))
    (tmp_path / "viapath" / "safety" / "long.py").write_text(
        f"def long():\n{body}\n\n\ndef short():\n    return 1\n\n\nclass Big:\n{methods}"
    )
    (tmp_path / "viapath" / "guard.py").write_text(
        "def at_limit():\n" + "\n".join(f"    y{i} = {i}" for i in range(59)) + "\n"
    )
    assert long_definitions(tmp_path) == {
        ("viapath/safety/long.py", "long"): 61,
        ("viapath/safety/long.py", "Big"): 303,
    }


def test_the_planner_has_no_function_over_60_lines_nor_class_over_300():
    found = long_definitions(patterns=PLANNER)
    assert found == {}, "planner functions over 60 lines or classes over 300 (split them): " + ", ".join(
        f"{file}:{name} ({lines} lines)" for (file, name), lines in sorted(found.items())
    )
