"""No import circles, lazy or not: no module in src/ imports one that imports it back (directly or
through others), and no subpackage of viapath imports one that imports it back. Imports are read from
the source (every ``import`` statement, inside functions too), so a lazy import counts."""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"


def _modules() -> dict[str, Path]:
    modules = {}
    for file in SRC.rglob("*.py"):
        parts = list(file.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        modules[".".join(parts)] = file
    return modules


def _imports(file: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(file.read_text())):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names |= {node.module} | {f"{node.module}.{alias.name}" for alias in node.names}
    return names


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    graph = {}
    for name, file in modules.items():
        edges = set()
        for imported in _imports(file):
            parts = imported.split(".")
            # Importing a.b.c runs a.b's __init__ too (unless it is the importer's own package).
            for k in range(2, len(parts) + 1):
                target = ".".join(parts[:k])
                if target in modules and target != name and not name.startswith(target + "."):
                    edges.add(target)
        graph[name] = edges
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one member (Tarjan, iterative)."""
    index, low, on_stack, stack, found, counter = {}, {}, set(), [], [], [0]

    def visit(root):
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter[0]
                    counter[0] += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_the_cycle_finder_finds_a_planted_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_module_imports_one_that_imports_it_back():
    assert _cycles(_graph()) == []


def test_no_subpackage_imports_one_that_imports_it_back():
    packages: dict[str, set[str]] = {}
    for name, edges in _graph().items():
        own = ".".join(name.split(".")[:2])
        packages.setdefault(own, set()).update(".".join(e.split(".")[:2]) for e in edges)
    for own, edges in packages.items():
        edges.discard(own)
    assert _cycles(packages) == []


CORE = (
    "viapath.geometry",
    "viapath.path",
    "viapath.observation",
    "viapath.planning",
    "viapath.safety",
    "viapath.guard",
    "viapath.static",
    "viapath.kinematics",
    "viapath.limits",
    "viapath.forecast",
)
OUTSIDE_THE_CORE = ("viapath.sim", "viapath.io", "viapath.viz", "viapath.bench", "viapath.ros2", "viapath.cli")


def _in(name: str, packages) -> bool:
    return any(name == package or name.startswith(package + ".") for package in packages)


def _reached_from(graph: dict[str, set[str]], start: str) -> dict[str, str]:
    """Every module ``start`` imports, directly or through others (lazy imports too): module -> who imports it."""
    seen, work = {start: ""}, [start]
    while work:
        module = work.pop()
        for imported in sorted(graph.get(module, ())):
            if imported not in seen:
                seen[imported] = module
                work.append(imported)
    return seen


def test_the_core_imports_nothing_outside_it():
    """geometry, path, observation, planning, safety, guard, static, kinematics, limits, forecast import
    (lazily or not, directly or through another module) no simulator, I/O, view, benchmark, ROS 2 or CLI module."""
    graph = _graph()
    found = []
    for module in graph:
        if not _in(module, CORE):
            continue
        reached = _reached_from(graph, module)
        for target, importer in reached.items():
            if _in(target, OUTSIDE_THE_CORE):
                found.append(f"{module} reaches {target} (imported by {importer})")
    assert found == []


def test_the_core_check_sees_a_planted_import():
    graph = {"viapath.path": {"viapath.options"}, "viapath.options": {"viapath.io.safe_read"}}
    assert "viapath.io.safe_read" in _reached_from(graph, "viapath.path")
