"""The one decorator of the compiled steps: compiled and plain Python give the same answers."""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

from viapath import jit


@jit.compiled(inline=True)
def _square(x):
    return x * x


@jit.compiled
def _norms(points):
    out = np.empty(points.shape[0])
    for i in range(points.shape[0]):
        out[i] = math.sqrt(_square(points[i, 0]) + _square(points[i, 1]))
    return out


def test_compiled_and_plain_python_agree_with_numpy():
    points = np.random.default_rng(3).normal(size=(50, 2))
    expected = np.hypot(points[:, 0], points[:, 1])
    np.testing.assert_allclose(_norms(points), expected, rtol=1e-15)
    plain = jit.python_function(_norms)
    np.testing.assert_allclose(plain(points), expected, rtol=1e-15)


def test_compiled_when_numba_is_enabled():
    if jit.enabled():
        assert jit.python_function(_norms) is not _norms  # a dispatcher around the plain function
    else:
        assert jit.python_function(_norms) is _norms


def test_the_cache_follows_every_compiling_module(tmp_path):
    """numba notices changes of a function's own file only: the cache folder's digest covers every module
    that compiles, so a change to a compiled callee in another file is compiled afresh."""
    package = tmp_path / "package"
    package.mkdir()
    (package / "jit.py").write_text("# the decorator\n")
    (package / "steps.py").write_text("from viapath.jit import compiled\n")
    (package / "plain.py").write_text("x = 1\n")
    before = jit.source_digest(package)
    (package / "plain.py").write_text("x = 2\n")
    assert jit.source_digest(package) == before
    (package / "steps.py").write_text("from viapath.jit import compiled\n# changed\n")
    assert jit.source_digest(package) != before


def test_the_cache_follows_the_kinematics_compiled_from_its_source(tmp_path):
    """viapath.kinematics compiles nothing itself, but the guard's braking roll-out and the planner's roll-out
    compile its arc: a change to it must name a new cache folder."""
    package = tmp_path / "viapath"
    shutil.copytree(jit.PACKAGE, package, ignore=shutil.ignore_patterns("__pycache__"))
    before = jit.source_digest(package)
    kinematics = package / "kinematics.py"
    kinematics.write_text(kinematics.read_text().replace("half * half / 6.0", "half * half / 7.0"))
    assert kinematics.read_text() != (jit.PACKAGE / "kinematics.py").read_text()
    assert jit.source_digest(package) != before


def test_the_cache_directory_is_named_by_the_digest():
    assert jit.cache_directory().name == jit.source_digest()


def test_a_cache_is_warm_once_it_holds_compiled_code(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert not jit.cache_is_warm()
    folder = jit.cache_directory()
    folder.mkdir(parents=True)
    assert not jit.cache_is_warm()  # an empty folder holds nothing compiled
    (folder / "steps.step-1.py311.nbi").write_bytes(b"index")
    assert jit.cache_is_warm()


def test_a_first_run_is_told_it_compiles_until_the_cache_is_ready(tmp_path, monkeypatch):
    """Some compiled code in the cache is not enough (a run would compile the rest): the note goes only once
    viapath.precompile marked the cache ready."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    note = jit.first_compilation_note()
    if not jit.enabled():
        assert note is None
        return
    assert note is not None and str(jit.cache_directory()) in note
    jit.cache_directory().mkdir(parents=True)
    (jit.cache_directory() / "steps.step-1.py311.nbi").write_bytes(b"index")
    assert jit.cache_is_warm() and not jit.cache_is_ready()
    assert jit.first_compilation_note() is not None
    jit.ready_file().write_text("compiled\n")
    assert jit.cache_is_ready() and jit.first_compilation_note() is None


def _fresh(script: str, **env: str) -> list[str]:
    source = str(Path(__file__).resolve().parents[1] / "src")
    environment = {**os.environ, "PYTHONPATH": source + os.pathsep + os.environ.get("PYTHONPATH", ""), **env}
    environment.pop("NUMBA_DISABLE_JIT", None)
    environment.update(env)
    done = subprocess.run([sys.executable, "-c", script], env=environment, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


def test_numba_is_imported_only_when_a_step_is_compiled():
    """``import viapath`` and the CLI (``viapath --help``) decorate nothing and load no numba; the first compiled
    step does, unless the process chose plain Python first."""
    script = (
        "import sys\n"
        "import viapath.cli\n"
        "from viapath import jit\n"
        "print('numba' in sys.modules)\n"
        "if sys.argv[1] == 'plain': print(jit.run_plain())\n"
        "else: print('-')\n"
        "from viapath.path import corridor_excess_at\n"
        "print('numba' in sys.modules, hasattr(corridor_excess_at, 'py_func'), jit.run_plain())\n"
    )
    expected_compiled = str(jit.numba_installed())
    assert _fresh(script.replace("sys.argv[1]", "'compiled'")) == ["False", "-", *[expected_compiled] * 2, "False"]
    assert _fresh(script.replace("sys.argv[1]", "'plain'")) == ["False", "True", "False", "False", "True"]
    # NUMBA_DISABLE_JIT: plain Python too, numba never loaded
    assert _fresh(script.replace("sys.argv[1]", "'compiled'"), NUMBA_DISABLE_JIT="1") == [
        "False",
        "-",
        "False",
        "False",
        "True",
    ]
