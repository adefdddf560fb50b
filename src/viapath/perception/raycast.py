"""Ray casting of a planar scan against moving discs (obstacles) and static wall segments.

Source: the standard closed forms. A ray ``o + t d`` (``|d| = 1``, ``t >= 0``) meets the circle
``|x - c| = r`` at ``t = -b - sqrt(b² - k)`` with ``b = (o - c)·d`` and ``k = |o - c|² - r²``; it
meets the segment ``p + s e`` (``0 <= s <= 1``) at ``t = ((p - o) × e) / (d × e)``,
``s = ((p - o) × d) / (d × e)``. The range of a beam is the smallest such ``t``.

What we chose:
* The obstacles are snapshots at the scan instant (a scan is treated as simultaneous).
* A scanner inside an obstacle reads range 0 on every beam (a surface touching the window), which
  the scanner model then reports as invalid, as a real URG does below 20 mm.
* A beam parallel to a wall (``d × e = 0``) does not hit it (it grazes an infinitely thin line).
* The robot's own body is not in the scene: the scanners sit on top of it and do not see it.
* Two back ends: vectorised numpy (``(B, N)`` broadcasting) and an optional numba loop
  (``pip install 'viapath[fast]'``). They evaluate the same expressions in the same order, without
  fast-math, so they agree bit for bit (tested). ``backend="auto"`` takes numba when it is
  installed; the first call on a machine compiles the kernel (~seconds, cached on disk:
  :mod:`~viapath.perception._numba_kernels`), later processes load it.
"""

from __future__ import annotations

import numpy as np

_NUMBA_KERNEL = None
_NUMBA_FAILED: str | None = None


def _as_inputs(centres, radii, segments):
    centres = np.ascontiguousarray(np.asarray(centres, dtype=float).reshape(-1, 2))
    radii = np.ascontiguousarray(np.asarray(radii, dtype=float).reshape(-1))
    if len(radii) != len(centres):
        raise ValueError(f"{len(centres)} disc centres but {len(radii)} radii")
    present = np.isfinite(centres).all(axis=1) & np.isfinite(radii)
    if not present.all():  # absent obstacles are NaN rows in a WorldSnapshot
        centres, radii = centres[present], radii[present]
    segments = np.ascontiguousarray(np.asarray(segments, dtype=float).reshape(-1, 2, 2))
    return centres, radii, segments


def cast_rays_numpy(origin, directions, centres, radii, segments) -> np.ndarray:
    """Exact hit distance of each ray; ``inf`` where a ray hits nothing.

    ``origin`` (2,), ``directions`` (B, 2) unit vectors, ``centres`` (N, 2), ``radii`` (N,),
    ``segments`` (W, 2, 2).
    """
    ox, oy = float(origin[0]), float(origin[1])
    dx = directions[:, 0][:, None]
    dy = directions[:, 1][:, None]
    best = np.full(len(directions), np.inf)
    if len(centres):
        fx = ox - centres[:, 0]
        fy = oy - centres[:, 1]
        k = fx * fx + fy * fy - radii * radii
        b = fx * dx + fy * dy
        disc = b * b - k
        with np.errstate(invalid="ignore"):
            t = -b - np.sqrt(disc)
        t = np.where((disc >= 0.0) & (t >= 0.0), t, np.inf)
        t = np.where(k <= 0.0, 0.0, t)
        best = np.minimum(best, t.min(axis=1))
    if len(segments):
        px = segments[:, 0, 0]
        py = segments[:, 0, 1]
        ex = segments[:, 1, 0] - px
        ey = segments[:, 1, 1] - py
        wx = px - ox
        wy = py - oy
        denom = dx * ey - dy * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (wx * ey - wy * ex) / denom
            s = (wx * dy - wy * dx) / denom
            ok = (denom != 0.0) & (t >= 0.0) & (s >= 0.0) & (s <= 1.0)
        t = np.where(ok, t, np.inf)
        best = np.minimum(best, t.min(axis=1))
    return best


def _load_numba_kernel():
    from viapath.perception._numba_kernels import cast_rays_kernel  # module-level: cached on disk once per machine

    return cast_rays_kernel


def numba_available() -> bool:
    global _NUMBA_KERNEL, _NUMBA_FAILED
    if _NUMBA_KERNEL is not None:
        return True
    if _NUMBA_FAILED is not None:
        return False
    try:
        _NUMBA_KERNEL = _load_numba_kernel()
    except Exception as error:  # ImportError, or a numba that does not support this numpy
        _NUMBA_FAILED = f"{type(error).__name__}: {error}"
        return False
    return True


def cast_rays_numba(origin, directions, centres, radii, segments) -> np.ndarray:
    if not numba_available():
        raise RuntimeError(f"numba back end unavailable ({_NUMBA_FAILED}); pip install 'viapath[fast]'")
    out = np.empty(len(directions))
    _NUMBA_KERNEL(float(origin[0]), float(origin[1]), np.ascontiguousarray(directions, dtype=float), centres, radii,
                  segments, out)
    return out


def cast_rays(origin, angles_rad, centres, radii, segments=None, backend: str = "numpy") -> np.ndarray:
    """Distance from ``origin`` along each world-frame angle to the first disc or wall; ``inf`` = no hit.

    ``backend``: ``"numpy"``, ``"numba"`` (error if numba is missing) or ``"auto"`` (numba if present).
    """
    centres, radii, segments = _as_inputs(centres, radii, np.zeros((0, 2, 2)) if segments is None else segments)
    angles_rad = np.asarray(angles_rad, dtype=float).reshape(-1)
    directions = np.stack([np.cos(angles_rad), np.sin(angles_rad)], axis=-1)
    if backend == "auto":
        backend = "numba" if numba_available() else "numpy"
    if backend == "numpy":
        return cast_rays_numpy(origin, directions, centres, radii, segments)
    if backend == "numba":
        return cast_rays_numba(origin, directions, centres, radii, segments)
    raise ValueError(f"backend must be 'numpy', 'numba' or 'auto', got {backend!r}")


def simulate_scan(scanner, robot_pose, centres, radii, segments=None, rng=None, backend: str = "numpy") -> np.ndarray:
    """Readings of ``scanner`` mounted on a robot at ``robot_pose``, as its driver would report them."""
    x, y, yaw = scanner.world_pose(robot_pose)
    true_range = cast_rays((x, y), scanner.beam_angles_rad() + yaw, centres, radii, segments, backend=backend)
    return scanner.measure(true_range, rng)
