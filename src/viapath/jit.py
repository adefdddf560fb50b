"""The one decorator of viapath's compiled steps, and the on-disk cache they are compiled into.

A step that runs in the control loop and must be fast (the planner's leg checks and search, the shield's
braking sweep, the guard's checks, the laser chain's ray casting and fits) is written once, in the part of
Python that numba compiles, and decorated with :func:`compiled`:

* with numba installed, the function is compiled to machine code on its first call and kept in numba's
  on-disk cache, so later processes load it instead of compiling. numba checks only the defining file for
  changes, not the files of the compiled functions it calls; so the cache lives in a directory named by a
  digest of every module that compiles (:func:`cache_directory`): a change to any of them compiles afresh;
* with compilation off (``NUMBA_DISABLE_JIT=1``, :func:`run_plain`) or without numba, the decorator returns
  the function itself: it runs as plain Python, a debugger or a print statement sees the real step, only
  slower.

numba is imported only when the first function is decorated with compilation on (about 0.2 s), so a process
that runs plain Python, or imports no compiled step (``viapath --help``), never loads it. The choice is made
per process, when the first step is decorated: a compiled step calls other compiled steps, so they are all
compiled or all plain.

The cache of one version of the code is *ready* once :mod:`viapath.precompile` has compiled every step into
it (:func:`cache_is_ready`): a ``ready-…`` file it writes last. Until then a first ``viapath run`` runs plain
Python and compiles in the background (:mod:`viapath.cli.common`).

This is the only module that names numba. Everything else imports :func:`compiled` from here.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any, TypeVar, cast, overload

F = TypeVar("F", bound=Callable[..., Any])
PACKAGE = Path(__file__).resolve().parent
# How a module that compiles names the decorator (a module that only asks whether compilation is on, or
# mentions the decorator in a docstring, compiles nothing: a change to it keeps the cache).
_USES = (b"from viapath.jit import compiled", b"@jit.compiled", b"jit.compiled(")

_state: dict[str, Any] = {"plain": False, "numba": None, "decorated": []}


def source_digest(package: Path = PACKAGE) -> str:
    """A digest of the modules of ``package`` that compile (they decorate with :func:`compiled`), and of this module."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        text = path.read_bytes()
        if path.name == "jit.py" or any(use in text for use in _USES):
            digest.update(path.relative_to(package).as_posix().encode())
            digest.update(text.replace(b"\r\n", b"\n"))
    return digest.hexdigest()[:16]


def cache_directory() -> Path:
    """Where compiled steps are cached: ``$NUMBA_CACHE_DIR`` (else ``$XDG_CACHE_HOME/viapath/numba``, else
    ``~/.cache/viapath/numba``), in a folder named by :func:`source_digest`."""
    base = os.environ.get("NUMBA_CACHE_DIR") or Path(
        os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache", "viapath", "numba"
    )
    return Path(base) / source_digest()


def ready_file() -> Path:
    """The file :mod:`viapath.precompile` writes into :func:`cache_directory` once every step is compiled there.
    Named by the Python and numba versions too: numba keeps the code of each in the same folder."""
    return cache_directory() / f"ready-{sys.implementation.cache_tag}-numba{_numba_version()}"


@cache
def _numba_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("numba")
    except PackageNotFoundError:  # pragma: no cover - a stripped install runs plain Python
        return "none"


def cache_is_ready() -> bool:
    """Whether every compiled step of this version of the code is in the cache (:mod:`viapath.precompile` ran)."""
    return ready_file().is_file()


def cache_is_warm() -> bool:
    """Whether some compiled steps of this version of the code are in the cache (a run loads those and compiles
    the rest; :func:`cache_is_ready` says whether that is nothing)."""
    folder = cache_directory()
    return folder.is_dir() and any(folder.rglob("*.nbi"))


def first_compilation_note() -> str | None:
    """What to tell a user whose run compiles the steps for this machine (None when they are all cached, or
    when compilation is off)."""
    if not enabled() or cache_is_ready():
        return None
    return (
        "viapath: compiling its planner, shield and laser chain for this machine, once (about a minute of CPU); "
        f"later runs load them from {cache_directory()}"
    )


def numba_installed() -> bool:
    return importlib.util.find_spec("numba") is not None


def enabled() -> bool:
    """Whether decorated functions are compiled: numba installed, ``NUMBA_DISABLE_JIT`` not set and
    :func:`run_plain` not chosen."""
    if _state["plain"]:
        return False
    return os.environ.get("NUMBA_DISABLE_JIT", "0").strip() in ("", "0") and numba_installed()


def run_plain() -> bool:
    """Run every step of this process as plain Python, when no step has been compiled yet (True then).

    Decided before the first compiled step is decorated (a compiled step cannot call a plain one); False,
    and nothing changes, when one already is."""
    if _state["decorated"]:
        return False
    _state["plain"] = True
    return True


def _numba() -> Any:
    """numba, imported on first use, its cache in :func:`cache_directory` (set before any function is decorated:
    numba picks a cache folder per function then)."""
    if _state["numba"] is None:
        import numba

        config: Any = numba.config
        config.CACHE_DIR = str(cache_directory())
        _state["numba"] = numba
    return _state["numba"]


@overload
def compiled(function: F, /) -> F: ...
@overload
def compiled(*, signature: str | None = None, inline: bool = False, **options: Any) -> Callable[[F], F]: ...
def compiled(
    function: F | None = None, /, *, signature: str | None = None, inline: bool = False, **options: Any
) -> F | Callable[[F], F]:
    """Compile ``function`` with numba (``nopython``, cached on disk, releasing the GIL).

    ``signature`` compiles eagerly for those types (the module compiles, or loads its cache, at import);
    ``inline`` inlines the function into its compiled callers (for small helpers called per element);
    other keywords go to ``numba.njit`` as they are (``error_model``, ``fastmath``). Used bare
    (``@compiled``) or with keywords (``@compiled(inline=True)``). With compilation off (:func:`enabled`)
    it returns ``function`` itself.
    """

    def wrap(f: F) -> F:
        if not enabled():
            return f
        numba = _numba()
        settings: dict[str, Any] = {"cache": True, "nogil": True, **options}
        if inline:
            settings["inline"] = "always"
        dispatcher = numba.njit(signature, **settings)(f) if signature is not None else numba.njit(**settings)(f)
        _state["decorated"].append(dispatcher)
        return cast(F, dispatcher)

    return wrap if function is None else wrap(function)


def python_function(function: Callable[..., Any]) -> Callable[..., Any]:
    """The plain Python function behind a compiled one (itself when compilation is off)."""
    return getattr(function, "py_func", function)
