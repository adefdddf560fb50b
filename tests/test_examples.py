"""Every example of the README and the tutorial runs, as a reader would run it, with nothing from
outside the clone.

A small collector of our own rather than pytest-examples: that plugin runs (and lints) Python blocks
only, and the examples here are as much shell commands and scenario files as Python.

Collected: each ```python, ```bash and ```yaml block of ``README.md``, ``docs/tutorial*.md`` and
``docs/tutorial/**/*.md``, one test per block, run in the page's order in one working folder per page
(later blocks see the files earlier ones wrote). That folder holds links to the clone's top-level
files and folders (``src``, ``benchmarks``, ``docs``, ...) and nothing else: a path outside the
clone (``../shared/data``) is missing there, as in a fresh clone.

* bash: run by ``bash -e -o pipefail``; ``viapath``, ``python`` and ``python3`` are this
  interpreter with this tree's ``src`` first on ``PYTHONPATH``. Must exit 0.
* python: run as a script by this interpreter. Must exit 0.
* yaml: must parse; a scenario (a mapping with ``robot`` and ``path``) is run with
  ``viapath run FILE --json`` and must reach its goal.

Markers, in an HTML comment on the lines just above the block's opening fence (invisible on GitHub
and in the site):

* ``<!-- example: skip: REASON -->``: not run (a robot, a long benchmark, an install); the test is
  reported skipped with the reason.
* ``<!-- example: file: NAME -->``: the block is written to ``NAME`` in the page's folder for the
  blocks after it (Python is compiled, YAML parsed, neither run).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
LANGUAGES = {"python": "python", "py": "python", "bash": "bash", "sh": "bash", "shell": "bash", "yaml": "yaml"}
MARKER = re.compile(r"<!--\s*example:\s*(skip|file)\s*:\s*(.*?)\s*-->")
TIMEOUT_S = 600


@dataclass(frozen=True)
class Block:
    page: str  # relative to the clone
    line: int  # of the opening fence, 1-based
    language: str  # python | bash | yaml
    code: str
    skip: str | None = None
    file: str | None = None

    @property
    def name(self) -> str:
        return f"{self.page}:{self.line}:{self.language}"


def pages(root: Path = ROOT) -> list[Path]:
    docs = root / "docs"
    found = [root / "README.md", *sorted(docs.glob("tutorial*.md")), *sorted((docs / "tutorial").rglob("*.md"))]
    return [page for page in found if page.is_file()]


def blocks_of(page: Path, root: Path = ROOT) -> list[Block]:
    """The page's python / bash / yaml blocks with their markers."""
    lines = page.read_text().splitlines()
    found, k = [], 0
    while k < len(lines):
        opening = re.match(r"^(\s*)(`{3,})\s*([\w+-]*)", lines[k])
        if not opening:
            k += 1
            continue
        indent, fence, language = opening.group(1), opening.group(2), opening.group(3).lower()
        end = k + 1
        while end < len(lines) and not lines[end].strip().startswith(fence):
            end += 1
        markers, above = {}, k - 1
        while above >= 0 and (not lines[above].strip() or lines[above].strip().startswith("<!--")):
            for kind, value in MARKER.findall(lines[above]):
                markers.setdefault(kind, value)
            above -= 1
        if language in LANGUAGES:
            body = [line[len(indent) :] if line.startswith(indent) else line for line in lines[k + 1 : end]]
            found.append(
                Block(
                    str(page.relative_to(root)),
                    k + 1,
                    LANGUAGES[language],
                    "\n".join(body) + "\n",
                    markers.get("skip"),
                    markers.get("file"),
                )
            )
        k = end + 1
    return found


def _params():
    params = []
    for page in pages():
        for block in blocks_of(page):
            marks = []  # under pytest-xdist the file's tests run in order on one worker (tests/conftest.py)
            if block.skip is not None:
                marks.append(pytest.mark.skip(reason=f"{block.name}: {block.skip}"))
            params.append(pytest.param(block, id=block.name, marks=marks))
    return params


@pytest.fixture(scope="session")
def page_folders(tmp_path_factory):
    """One working folder per page, made on first use: links to the clone's top level, and shims."""
    folders: dict[str, tuple[Path, dict[str, str]]] = {}

    def folder(page: str) -> tuple[Path, dict[str, str]]:
        if page not in folders:
            work = tmp_path_factory.mktemp("example")
            for entry in ROOT.iterdir():
                if entry.name not in {".git", ".venv", "build"} and not entry.name.endswith(".egg-info"):
                    (work / entry.name).symlink_to(entry)
            shims = tmp_path_factory.mktemp("shims")
            for name, module in (("viapath", "-m viapath.cli "), ("python", ""), ("python3", "")):
                shim = shims / name
                shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" {module}"$@"\n')
                shim.chmod(0o755)
            env = dict(os.environ)
            env.update(
                PATH=f"{shims}{os.pathsep}{env.get('PATH', '')}",
                PYTHONPATH=os.pathsep.join(p for p in (str(ROOT / "src"), env.get("PYTHONPATH", "")) if p),
                MPLBACKEND="Agg",
            )
            folders[page] = (work, env)
        return folders[page]

    return folder


def _run(args: list[str], work: Path, env: dict[str, str], block: Block) -> subprocess.CompletedProcess:
    done = subprocess.run(
        args, cwd=work, env=env, capture_output=True, text=True, timeout=TIMEOUT_S, stdin=subprocess.DEVNULL
    )
    assert done.returncode == 0, (
        f"{block.name} exited {done.returncode}\n--- block\n{block.code}--- stdout\n{done.stdout[-3000:]}"
        f"\n--- stderr\n{done.stderr[-3000:]}"
    )
    return done


@pytest.mark.parametrize("block", _params())
def test_example_runs(block: Block, page_folders):
    work, env = page_folders(block.page)
    if block.file is not None:
        target = work / block.file
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(block.code)
        if block.language == "python":
            compile(block.code, block.file, "exec")
        elif block.language == "yaml":
            assert yaml.safe_load(block.code) is not None, block.name
        return
    stem = f"example_{Path(block.page).stem}_{block.line}"
    if block.language == "bash":
        script = work / f"{stem}.sh"
        script.write_text(block.code)
        _run(["bash", "-e", "-o", "pipefail", str(script)], work, env, block)
    elif block.language == "python":
        script = work / f"{stem}.py"
        script.write_text(block.code)
        _run([sys.executable, str(script)], work, env, block)
    else:
        content = yaml.safe_load(block.code)
        assert isinstance(content, dict | list), f"{block.name}: not a YAML mapping or list"
        if isinstance(content, dict) and {"robot", "path"} <= content.keys():
            scenario = work / f"{stem}.yaml"
            scenario.write_text(block.code)
            done = _run([sys.executable, "-m", "viapath.cli", "run", str(scenario), "--json"], work, env, block)
            metrics = json.loads(done.stdout.strip().splitlines()[-1])
            assert metrics["reached_goal"], f"{block.name}: the scenario does not reach its goal: {metrics}"


def test_the_collector_reads_markers_languages_and_indented_fences(tmp_path):
    """The collector itself, on a page made for it: which blocks, their lines, markers and code."""
    page = tmp_path / "README.md"
    page.write_text(
        "text\n"
        "<!-- example: skip: needs a robot -->\n"
        "```bash\n"
        "viapath ros2 node\n"
        "```\n"
        "\n"
        "<!-- example: file: my.yaml -->\n"
        "\n"
        "```yaml\n"
        "a: 1\n"
        "```\n"
        "```toml\n"
        "x = 1\n"
        "```\n"
        "1. a list item\n"
        "   ```python\n"
        "   print('in a list')\n"
        "   ```\n"
    )
    found = blocks_of(page, tmp_path)
    assert [(b.line, b.language, b.skip, b.file) for b in found] == [
        (3, "bash", "needs a robot", None),
        (9, "yaml", None, "my.yaml"),
        (16, "python", None, None),
    ]
    assert found[2].code == "print('in a list')\n"
    assert found[0].code == "viapath ros2 node\n"
