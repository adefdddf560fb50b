"""The compiled code of viapath (extra ``fast``: numba), in one package, and the one policy that decides whether
it runs. docs/speed.md is the guide.

Modules (the kernel modules import numba; this one does not, so the core runs without it):

* :mod:`.planning`: the viapath planner's kernels (leg checks, via points, corridor, the candidate tree, the
  choice, the escape, the roll-outs); :mod:`.slots` the layouts of their settings arrays and node store;
  :mod:`.arithmetic` the planner's dispatch between its numpy reference and these kernels.
* :mod:`.shield`: the passive-safety shield's test and search; :mod:`.perception`: ray casting, the circle fit,
  the detector's shape tests and splits; :mod:`.harness`: the guard and the inflation every planner gets.
* :mod:`.sums`: numpy's pairwise summation, for the kernels that must give numpy's sums bit for bit.
* :mod:`.table`: every compiled entry with its numpy reference and the test that holds them equal.
* :mod:`.choice`: the option ``compute`` that picks the arithmetic (formerly ``backend``), defined once.

The policy (one for the planner, the shield, the perception chain and the harness):

* Option ``compute`` (planner and shield): ``auto`` (default), ``numpy`` or ``numba``; the environment variable
  ``VIAPATH_PLANNER_BACKEND`` (same choices) overrides ``auto`` only (:func:`resolve`). ``numba`` without numba
  installed is an error naming the extra.
* A plain ``auto`` (no environment variable: :func:`explicit` is False) takes the kernels that cost seconds
  to compile only once they are in numba's on-disk cache (:func:`ready`), so that a first short run does not
  wait for them; ``viapath bench`` and the ROS 2 node compile them before they start
  (:func:`viapath.precompile.precompile`).
* A kernel module that fails to load for another reason than a missing numba (a broken install, a read-only
  tree without a cache directory) is reported once as a warning and the numpy code runs (:func:`kernels`).
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import warnings
from pathlib import Path
from types import ModuleType

COMPUTE_CHOICES = ("auto", "numpy", "numba")  # the values of the option compute
ENVIRONMENT_VARIABLE = "VIAPATH_PLANNER_BACKEND"
KERNEL_MODULES = ("planning", "perception")

_import = importlib.import_module
_LOADED: dict[str, ModuleType | None] = {}
_FAILED: dict[str, str] = {}


def numba_available() -> bool:
    """Whether numba is installed (found, not imported)."""
    return importlib.util.find_spec("numba") is not None


def _environment() -> str:
    return os.environ.get(ENVIRONMENT_VARIABLE, "").strip().lower()


def explicit(choice: str) -> bool:
    """Whether the arithmetic was asked for by name (the option, or the environment variable over ``auto``)."""
    return choice != "auto" or _environment() not in ("", "auto")


def resolve(choice: str) -> str:
    """``numpy`` or ``numba`` for an option value (``auto`` looks at the environment, then at numba)."""
    if choice == "auto":
        override = _environment()
        if override and override != "auto":
            if override not in COMPUTE_CHOICES:
                expected = ", ".join(COMPUTE_CHOICES)
                raise ValueError(
                    f"environment variable {ENVIRONMENT_VARIABLE}={override!r}: expected one of {expected}"
                )
            choice = override
        else:
            return "numba" if numba_available() else "numpy"
    if choice == "numba" and not numba_available():
        raise ValueError(
            "viapath option compute='numba' needs numba: install the extra 'fast' (pip install 'viapath[fast]')"
        )
    if choice not in ("numpy", "numba"):
        raise ValueError(f"viapath option compute={choice!r}: expected one of {', '.join(COMPUTE_CHOICES)}")
    return choice


def kernels(name: str) -> ModuleType | None:
    """The kernel module ``viapath.compiled.<name>`` when numba is installed and works, else None; imported on
    first use (it compiles, or loads numba's on-disk cache, then) and decided once per process. A failure
    other than a missing numba is reported once as a RuntimeWarning."""
    if name not in _LOADED:
        try:
            module = _import(f"viapath.compiled.{name}")
        except ImportError as error:
            _FAILED[name] = f"{type(error).__name__}: {error}"
            module = None
        except Exception as error:
            _FAILED[name] = f"{type(error).__name__}: {error}"
            warnings.warn(
                f"viapath: the compiled {name} kernels could not be loaded ({_FAILED[name]}); using the numpy code",
                RuntimeWarning,
                stacklevel=2,
            )
            module = None
        _LOADED[name] = module
    return _LOADED[name]


def require(name: str) -> ModuleType:
    """:func:`kernels`, or a RuntimeError saying why they cannot run (for compiled arithmetic asked for by name)."""
    module = kernels(name)
    if module is None:
        raise RuntimeError(f"numba back end unavailable ({_FAILED.get(name)}); pip install 'viapath[fast]'")
    return module


def harness_kernels() -> ModuleType | None:
    """:mod:`.harness` (the guard's and the inflation's kernels) or None: :func:`kernels`."""
    return kernels("harness")


def ready(*dispatchers) -> bool:
    """Whether using these kernels now costs no compilation: each compiled in this process or in numba's on-disk
    cache."""
    for kernel in dispatchers:
        if kernel.signatures:
            continue
        cache_file = getattr(getattr(kernel, "_cache", None), "_cache_file", None)
        index = getattr(cache_file, "_index_path", None)
        if index is None or not os.path.exists(index):
            return False
    return True


def dependency_digest(names) -> str:
    """The first 16 hex digits of the SHA-256 of these modules' source files in this package (a kernel module
    holds the digest of the modules it compiles in, as numba's cache notices a change of its own file only)."""
    digest = hashlib.sha256()
    for name in names:
        digest.update((Path(__file__).parent / f"{name}.py").read_bytes().replace(b"\r\n", b"\n"))
    return digest.hexdigest()[:16]


def compiled_harness() -> ModuleType | None:
    """:mod:`.harness` or None (:func:`harness_kernels`), under the name the core's modules call it by."""
    return harness_kernels()
