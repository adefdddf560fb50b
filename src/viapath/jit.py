"""The one decorator of viapath's compiled steps.

A step that runs in the control loop and must be fast (the planner's leg checks and search, the shield's
braking sweep, the guard's checks, the laser chain's ray casting and fits) is written once, in the part of
Python that numba compiles, and decorated with :func:`compiled`:

* with numba installed, the function is compiled to machine code on its first call and kept in numba's
  on-disk cache, so later processes load it instead of compiling. numba checks only the defining file for
  changes, not the files of the compiled functions it calls; so the cache lives in a directory named by a
  digest of every module that compiles (:func:`cache_directory`): a change to any of them compiles afresh;
* with compilation off (``NUMBA_DISABLE_JIT=1``) or without numba, the same function runs as plain Python:
  a debugger or a print statement sees the real step, only slower.

This is the only module that names numba. Everything else imports :func:`compiled` from here.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast, overload

_numba: Any
try:  # numba is a dependency; without it (a stripped install) the steps run as plain Python
    import numba as _numba
except ImportError:  # pragma: no cover - exercised by installs without numba
    _numba = None

F = TypeVar("F", bound=Callable[..., Any])
PACKAGE = Path(__file__).resolve().parent
_USES = (b"viapath.jit", b"from viapath import jit")


def source_digest(package: Path = PACKAGE) -> str:
    """A digest of the modules of ``package`` that compile (they import this module), and of this module."""
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


def cache_is_warm() -> bool:
    """Whether compiled steps of this version of the code are in the cache (a first run compiles them)."""
    folder = cache_directory()
    return folder.is_dir() and any(folder.rglob("*.nbi"))


def first_compilation_note() -> str | None:
    """What to tell a user whose run compiles the steps for this machine (None when they are cached, or when
    compilation is off)."""
    if not enabled() or cache_is_warm():
        return None
    return (
        "viapath: compiling its planner, shield and guard for this machine, once (about a minute); "
        f"later runs load them from {cache_directory()}"
    )


if _numba is not None:  # before any function is decorated: numba picks a cache folder per function then
    _numba.config.CACHE_DIR = str(cache_directory())


def enabled() -> bool:
    """Whether decorated functions are compiled (numba installed and ``NUMBA_DISABLE_JIT`` not set)."""
    return _numba is not None and os.environ.get("NUMBA_DISABLE_JIT", "0").strip() in ("", "0")


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
    (``@compiled``) or with keywords (``@compiled(inline=True)``).
    """

    def wrap(f: F) -> F:
        if _numba is None:
            return f
        settings: dict[str, Any] = {"cache": True, "nogil": True, **options}
        if inline:
            settings["inline"] = "always"
        if signature is not None:
            return cast(F, _numba.njit(signature, **settings)(f))
        return cast(F, _numba.njit(**settings)(f))

    return wrap if function is None else wrap(function)


def python_function(function: Callable[..., Any]) -> Callable[..., Any]:
    """The plain Python function behind a compiled one (itself when compilation is off)."""
    return getattr(function, "py_func", function)
