"""Compiled (numba) kernels of the laser chain: ray casting, the batched circle fit, the detector's shape tests.

Source: the same closed forms as :mod:`~viapath.perception.raycast` and
:mod:`~viapath.perception.circle_fit` (their docstrings), written as loops.

Why a module of its own, with plain module-level functions:
* numba's on-disk cache (``cache=True``) only works for functions it can find again by module and
  qualified name, with no closure variables. The kernels used to be built inside functions
  (``_build_numba_fit.<locals>.fit``); the fit kernel closed over the ``solve`` dispatcher, whose
  pickled bytes differ in every process, so numba's cache index never matched: every process start
  compiled again (~10 s) and added another ``.nbc`` file next to the source.
* Imported only through the package's policy (:func:`viapath.compiled.kernels`, inside a ``try``): the
  numpy path never needs numba.
* Where the cache goes: numba writes next to the source (``__pycache__``) when that folder is
  writable, else (an installed, read-only site-packages) in the user-wide cache
  (``~/.cache/numba`` or ``$NUMBA_CACHE_DIR``). Either way the first process on a machine compiles
  and every later one loads (tested: ``tests/perception/test_numba_cache.py``).
* No fast-math: the kernels evaluate the numpy path's expressions in the same order, so ray
  casting and the shape tests agree bit for bit and the fit to round-off (tested).
"""

from __future__ import annotations

import numba
import numpy as np

from viapath.compiled import dependency_digest
from viapath.compiled.sums import pairwise_sum

# numba's cache keys on this file alone: the digest of the sums it compiles in (see viapath.compiled.planning).
DEPENDENCIES = ("sums",)
DEPENDENCY_DIGEST = "bda5224f64c1c850"
if dependency_digest(DEPENDENCIES) != DEPENDENCY_DIGEST:
    raise RuntimeError(
        f"viapath.compiled.perception: {', '.join(DEPENDENCIES)} changed: set DEPENDENCY_DIGEST in "
        f"{__file__} to {dependency_digest(DEPENDENCIES)!r} (numba then compiles the kernels again)"
    )


@numba.njit(cache=True, fastmath=False, nogil=True)
def beam_range(ox, oy, dx, dy, centres, radii, segments):  # pragma: no cover - compiled
    """Range along the unit direction (dx, dy) from (ox, oy) to the nearest disc or wall; ``inf`` = no hit."""
    best = np.inf
    for j in range(centres.shape[0]):
        fx = ox - centres[j, 0]
        fy = oy - centres[j, 1]
        k = fx * fx + fy * fy - radii[j] * radii[j]
        if k <= 0.0:
            best = min(best, 0.0)
            continue
        b = fx * dx + fy * dy
        disc = b * b - k
        if disc >= 0.0:
            t = -b - np.sqrt(disc)
            if t >= 0.0 and t < best:
                best = t
    for j in range(segments.shape[0]):
        px = segments[j, 0, 0]
        py = segments[j, 0, 1]
        ex = segments[j, 1, 0] - px
        ey = segments[j, 1, 1] - py
        wx = px - ox
        wy = py - oy
        denom = dx * ey - dy * ex
        if denom != 0.0:
            t = (wx * ey - wy * ex) / denom
            s = (wx * dy - wy * dx) / denom
            if t >= 0.0 and s >= 0.0 and s <= 1.0 and t < best:
                best = t
    return best


@numba.njit(cache=True, fastmath=False, nogil=True)
def cast_rays_kernel(ox, oy, directions, centres, radii, segments, out):  # pragma: no cover - compiled
    """:func:`beam_range` of every unit direction from one origin (one scanner)."""
    for i in range(directions.shape[0]):
        out[i] = beam_range(ox, oy, directions[i, 0], directions[i, 1], centres, radii, segments)


@numba.njit(cache=True, fastmath=False, nogil=True)
def cast_rays_from_kernel(origins_x, origins_y, directions, centres, radii, segments, out):  # pragma: no cover
    """:func:`beam_range` with one origin per beam (all scanners of a robot in one call)."""
    for i in range(directions.shape[0]):
        out[i] = beam_range(origins_x[i], origins_y[i], directions[i, 0], directions[i, 1], centres, radii, segments)


@numba.njit(cache=True, nogil=True)
def solve_sym3_scalar(a00, a01, a02, a11, a12, a22, b0, b1, b2):  # pragma: no cover - compiled
    """One symmetric 3x3 system by Cramer's rule: the solution and the centre block of the inverse."""
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    if not abs(det) > 1e-300:
        det = np.inf
    return (
        (c00 * b0 + c01 * b1 + c02 * b2) / det,
        (c01 * b0 + c11 * b1 + c12 * b2) / det,
        (c02 * b0 + c12 * b1 + c22 * b2) / det,
        c00 / det,
        c01 / det,
        c11 / det,
    )


@numba.njit(cache=True, nogil=True)
def fit_circles_kernel(
    points, starts, counts, origins, has_prior, prior, weight, range_sigma, iterations, out
):  # pragma: no cover - compiled
    """The batched geometric circle fit of :func:`~viapath.perception.circle_fit.fit_circles`, one loop per cluster.

    ``out[k]`` = (centre x, centre y, radius, rms, centre sigma).
    """
    for k in range(starts.shape[0]):
        s, m = starts[k], counts[k]
        mx = 0.0
        my = 0.0
        for i in range(s, s + m):
            mx += points[i, 0]
            my += points[i, 1]
        mx /= m
        my /= m
        vx = mx - origins[k, 0]
        vy = my - origins[k, 1]
        if has_prior:
            norm = max(np.sqrt(vx * vx + vy * vy), 1e-12)
            cx = vx / norm * (2.0 / np.pi * prior)
            cy = vy / norm * (2.0 / np.pi * prior)
            r = prior
            target = prior
        else:  # Kåsa
            sxx = sxy = sx = syy = sy = sxz = syz = sz = 0.0
            for i in range(s, s + m):
                x = points[i, 0] - mx
                y = points[i, 1] - my
                z = x * x + y * y
                sxx += x * x
                sxy += x * y
                sx += x
                syy += y * y
                sy += y
                sxz += x * z
                syz += y * z
                sz += z
            a, b, c, _, _, _ = solve_sym3_scalar(sxx, sxy, sx, syy, sy, float(m), -sxz, -syz, -sz)
            cx = -0.5 * a
            cy = -0.5 * b
            r = np.sqrt(max(cx * cx + cy * cy - c, 1e-12))
            target = 0.0
        rms = 0.0
        i00 = i01 = i11 = 0.0
        for it in range(iterations + 1):
            a00 = a01 = a02 = a11 = a12 = 0.0
            g0 = g1 = g2 = 0.0
            ss = 0.0
            for i in range(s, s + m):
                dx = points[i, 0] - mx - cx
                dy = points[i, 1] - my - cy
                dist = max(np.sqrt(dx * dx + dy * dy), 1e-12)
                ux = dx / dist
                uy = dy / dist
                res = dist - r
                a00 += ux * ux
                a01 += ux * uy
                a02 += ux
                a11 += uy * uy
                a12 += uy
                g0 -= ux * res
                g1 -= uy * res
                g2 -= res
                ss += res * res
            g2 += weight * (r - target)
            d0, d1, d2, i00, i01, i11 = solve_sym3_scalar(a00, a01, a02, a11, a12, m + weight, g0, g1, g2)
            rms = np.sqrt(ss / m)
            if it < iterations:
                cx -= d0
                cy -= d1
                r = abs(r - d2)
        sigma2 = max(rms, range_sigma) ** 2
        half_trace = 0.5 * (i00 + i11)
        half_diff = 0.5 * (i00 - i11)
        largest = half_trace + np.sqrt(half_diff * half_diff + i01 * i01)
        if cx * vx + cy * vy < 0:
            cx = -cx
            cy = -cy
        out[k, 0] = cx + mx
        out[k, 1] = cy + my
        out[k, 2] = r
        out[k, 3] = rms
        out[k, 4] = np.sqrt(max(largest * sigma2, 0.0))


# -- the detector's cheap shape tests ----------------------------------------------------------
# These must give the numpy path's values bit for bit (the detections decide which tracks exist), so
# they use only +, -, *, /, abs, max and sqrt (correctly rounded everywhere) and sum the way numpy
# sums a row: ``row.sum()`` starts from 0.0 and adds numpy's pairwise sum of the row
# (:func:`viapath.compiled.sums.pairwise_sum`).


@numba.njit(cache=True, nogil=True, error_model="numpy")
def segment_shape_kernel(
    points,
    starts,
    counts,
    width,
    first,
    chord,
    extent,
    origins,
    distance,
    noise_switch_range,
    noise_sigma_near,
    noise_fraction_far,
    sagitta,
    t_convex,
):  # pragma: no cover
    """Per segment: the sagitta (largest distance from the chord) and the convexity t-statistic of
    :func:`~viapath.perception.detection._chord_coordinates` / ``_convexity_t``, same values.

    Each segment is laid out as the numpy path's padded row of ``width`` entries (padding: the
    segment's first point, multiplied by a 0 mask), so that the pairwise sums group alike.
    ``distance``: |mid - origin| per segment, from numpy (``np.hypot``).
    """
    terms = np.empty((8, width))
    sums = np.empty(8)
    for k in range(starts.shape[0]):
        ux = chord[k, 0] / max(extent[k], 1e-12)
        uy = chord[k, 1] / max(extent[k], 1e-12)
        mx = first[k, 0] + 0.5 * chord[k, 0]
        my = first[k, 1] + 0.5 * chord[k, 1]
        nx = -uy
        ny = ux
        if (0.0 + (origins[k, 0] - mx) * nx) + (origins[k, 1] - my) * ny < 0:  # n points towards the sensor
            nx = nx * -1.0
            ny = ny * -1.0
        largest = 0.0
        for p in range(width):
            on = p < counts[k]
            mask = 1.0 if on else 0.0
            i = starts[k] + p if on else starts[k]
            rx = points[i, 0] - mx
            ry = points[i, 1] - my
            x = (rx * ux + ry * uy) * mask
            y = (rx * nx + ry * ny) * mask
            largest = max(largest, abs(y))
            x2 = x * x
            terms[0, p] = mask
            terms[1, p] = x
            terms[2, p] = x2
            terms[3, p] = x2 * x
            terms[4, p] = x2 * x2
            terms[5, p] = y
            terms[6, p] = x * y
            terms[7, p] = x2 * y
        sagitta[k] = largest
        for q in range(8):
            sums[q] = 0.0 + pairwise_sum(terms[q], 0, width)
        # solve_sym3 on (count, Σx, Σx², Σx², Σx³, Σx⁴) and (Σy, Σxy, Σx²y): the curvature and (A⁻¹)₂₂.
        a00, a01, a02, a11, a12, a22 = sums[0], sums[1], sums[2], sums[2], sums[3], sums[4]
        b0, b1, b2 = sums[5], sums[6], sums[7]
        c02 = a01 * a12 - a02 * a11
        c12 = a01 * a02 - a00 * a12
        c22 = a00 * a11 - a01 * a01
        c00 = a11 * a22 - a12 * a12
        c01 = a02 * a12 - a01 * a22
        det = a00 * c00 + a01 * c01 + a02 * c02
        if not abs(det) > 1e-300:
            det = np.inf
        curvature = (c02 * b0 + c12 * b1 + c22 * b2) / det
        inv22 = c22 / det
        sigma = noise_sigma_near if distance[k] < noise_switch_range else noise_fraction_far * distance[k]
        t_convex[k] = -curvature / (sigma * np.sqrt(max(inv22, 1e-30)))


@numba.njit(cache=True, nogil=True)
def split_clusters_kernel(
    points,
    r,
    valid,
    scans,
    sin_gap,
    sin_rest,
    max_gap_beams,
    noise_switch_range,
    noise_sigma_near,
    noise_fraction_far,
    min_jump,
    min_points,
    starts,
    counts,
    occluded,
    cluster_scan,
    kept_points,
):  # pragma: no cover - compiled
    """The clustering of :func:`~viapath.perception.segmentation.segment_beams` after the points, with
    its breakpoint thresholds from :class:`~viapath.perception.segmentation.BeamTables`: the same
    expressions, one pair of neighbouring valid beams at a time (elementwise: the same values).

    Fills, for the clusters of at least ``min_points`` points, ``starts`` (into the valid points),
    ``counts``, ``occluded``, ``cluster_scan`` and the kept points' indices ``kept_points``; returns
    (clusters kept, points kept).
    """
    n = r.shape[0]
    reach = max_gap_beams + 1
    adjacent = np.empty(max(n - 1, 0), dtype=np.bool_)
    split = np.empty(max(n - 1, 0), dtype=np.bool_)
    for k in range(n - 1):
        beam_step = valid[k + 1] - valid[k]
        adjacent[k] = beam_step <= reach and scans[k + 1] == scans[k]
        dx = points[k + 1, 0] - points[k, 0]
        dy = points[k + 1, 1] - points[k, 1]
        gap = np.sqrt(dx * dx + dy * dy)
        near = min(r[k], r[k + 1])
        row = min(beam_step, reach) - 1
        sigma = noise_sigma_near if near < noise_switch_range else noise_fraction_far * near
        jump = near * sin_gap[row, valid[k]] / sin_rest[row, valid[k]] + 3.0 * sigma
        threshold = max(jump, min_jump)
        split[k] = gap > threshold or not adjacent[k]
    kept = 0
    kept_total = 0
    first = 0
    for k in range(n):
        if k < n - 1 and not split[k]:
            continue
        last = k  # the cluster is first..last
        count = last - first + 1
        if count >= min_points:
            hidden = first > 0 and adjacent[first - 1] and r[first - 1] < r[first]
            hidden = hidden or (last < n - 1 and adjacent[last] and r[last + 1] < r[last])
            starts[kept] = first
            counts[kept] = count
            occluded[kept] = hidden
            cluster_scan[kept] = scans[first]
            for i in range(first, last + 1):
                kept_points[kept_total] = i
                kept_total += 1
            kept += 1
        first = k + 1
    return kept, kept_total
