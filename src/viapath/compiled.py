"""Optional compiled helpers (extra ``fast``): the numba module of the per-cycle harness, loaded when numba is
installed. This module imports no numba itself, so the core runs without it (numpy code then).

The guard runs every cycle of every planner: a numba that is installed but cannot compile or load its cache
(a broken install, a read-only tree without a cache directory) must not stop it. Any error while loading
the harness kernels is reported once as a warning and the numpy code is used.
"""

from __future__ import annotations

import warnings

_UNKNOWN = object()
_HARNESS = _UNKNOWN


def harness_kernels():
    """:mod:`viapath._harness_kernels` when numba is installed and works, else None; imported on first use (it
    compiles, or loads numba's on-disk cache, then)."""
    global _HARNESS
    if _HARNESS is _UNKNOWN:
        try:
            from viapath import _harness_kernels as kernels
        except ImportError:
            kernels = None
        except Exception as error:
            warnings.warn(
                f"viapath: the compiled harness kernels could not be loaded ({type(error).__name__}: "
                f"{error}); using the numpy code",
                RuntimeWarning,
                stacklevel=2,
            )
            kernels = None
        _HARNESS = kernels
    return _HARNESS
