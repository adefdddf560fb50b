"""The one decorator of the compiled steps: compiled and plain Python give the same answers."""

from __future__ import annotations

import math

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


def test_a_first_run_is_told_it_compiles(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    note = jit.first_compilation_note()
    if not jit.enabled():
        assert note is None
        return
    assert note is not None and str(jit.cache_directory()) in note
    jit.cache_directory().mkdir(parents=True)
    (jit.cache_directory() / "steps.step-1.py311.nbi").write_bytes(b"index")
    assert jit.first_compilation_note() is None
