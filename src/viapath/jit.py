"""The one decorator of viapath's compiled steps.

A step that runs in the control loop and must be fast (the planner's leg checks and search, the shield's
braking sweep, the guard's checks, the laser chain's ray casting and fits) is written once, in the part of
Python that numba compiles, and decorated with :func:`compiled`:

* with numba installed, the function is compiled to machine code on its first call and kept in numba's
  on-disk cache (``__pycache__`` beside the module), so later processes load it instead of compiling;
* with compilation off (``NUMBA_DISABLE_JIT=1``) or without numba, the same function runs as plain Python:
  a debugger or a print statement sees the real step, only slower.

This is the only module that names numba. Everything else imports :func:`compiled` from here.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any, TypeVar, cast, overload

_numba: Any
try:  # numba is a dependency; without it (a stripped install) the steps run as plain Python
    import numba as _numba
except ImportError:  # pragma: no cover - exercised by installs without numba
    _numba = None

F = TypeVar("F", bound=Callable[..., Any])


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
