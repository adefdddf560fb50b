"""Optional compiled helpers (extra ``fast``): the numba module of the per-cycle harness, loaded when numba is
installed. This module imports no numba itself, so the core runs without it (numpy code then)."""

from __future__ import annotations

_UNKNOWN = object()
_HARNESS = _UNKNOWN


def harness_kernels():
    """:mod:`viapath._harness_kernels` when numba is installed, else None; imported on first use (it compiles,
    or loads numba's on-disk cache, then)."""
    global _HARNESS
    if _HARNESS is _UNKNOWN:
        try:
            from viapath import _harness_kernels as kernels
        except ImportError:
            kernels = None
        _HARNESS = kernels
    return _HARNESS
