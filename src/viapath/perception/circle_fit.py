"""Geometric circle fit to the visible arc of a leg or a disc, batched over all clusters of a scan.

Source: the geometric (orthogonal-distance) fit minimises ``Σ (|p_i - c| - r)²`` by Gauss–Newton
(Chernov, "Circular and Linear Regression", CRC 2010, ch. 4); a laser sees at most half of a round
object, and on such arcs the centroid lies ~0.6 r in front of the centre (a person of r = 0.25 m:
~15–20 cm off) and the algebraic (Kåsa) fit shrinks the radius; the geometric fit has neither bias.

What we chose where the sources are silent:
* A radius prior ``Σ (|p_i - c| - r)² / σ_range² + (r - r_prior)² / σ_prior²``: a short, noisy arc
  (a leg, ~10 points, ±1 cm) does not pin its own radius; the prior keeps it plausible. A *known*
  radius is the limit ``σ_prior -> 0`` (``fixed_radius_m``), a free fit is ``σ_prior = inf``.
* Start: the prior radius behind the arc's centroid, seen from the sensor (``centroid + 2r/π · û``,
  the centroid of a half circle); without a prior, the Kåsa fit. Then ``iterations`` Gauss–Newton
  steps, in coordinates centred on the arc's centroid (round-off stays at the scale of the arc).
* Compiled (:func:`viapath.jit.compiled`; plain Python when compilation is off), one loop per cluster:
  a scan has a few dozen clusters of 3–100 points, too small for numpy's per-call cost. The 3x3 systems
  are solved by Cramer's rule (:func:`solve_sym3`; a singular system gives a zero step).
* ``centre_sigma_m``: the Gauss–Newton covariance ``σ̂² (JᵀJ)⁻¹`` of the centre, with σ̂ the larger
  of the fit's residual RMS and the range noise — what the tracker takes as measurement noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from viapath.jit import compiled


@dataclass
class CircleFits:
    centres: np.ndarray  # (K, 2)
    radii_m: np.ndarray  # (K,)
    rms_m: np.ndarray  # (K,) RMS of |p - c| - r
    centre_sigma_m: np.ndarray  # (K,) sqrt of the larger eigenvalue of the centre covariance

    def __len__(self) -> int:
        return len(self.radii_m)


def clusters_of(starts, counts) -> tuple[np.ndarray, np.ndarray]:
    """``starts`` and ``counts`` of the clusters as int64 arrays; a cluster of fewer than 2 points is refused."""
    starts = np.asarray(starts, dtype=np.int64)
    counts = np.asarray(counts, dtype=np.int64)
    if (counts < 2).any():
        raise ValueError("every cluster needs at least 2 points")
    return starts, counts


def fit_circles(
    points: np.ndarray,
    starts: np.ndarray,
    counts: np.ndarray,
    sensor_origins: np.ndarray | None = None,
    *,
    radius_prior_m: float | None = None,
    radius_prior_sigma_m: float = 0.05,
    fixed_radius_m: float | None = None,
    range_sigma_m: float = 0.01,
    iterations: int = 4,
) -> CircleFits:
    """Fit one circle to each cluster ``points[starts[k] : starts[k] + counts[k]]``.

    ``sensor_origins`` (K, 2) or (2,): where each cluster was seen from, in the points' frame
    (default: the origin); used for the start and so that the centre lands *behind* the arc.
    """
    starts, counts = clusters_of(starts, counts)
    k_count = len(starts)
    if k_count == 0:
        return CircleFits(np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0))
    if sensor_origins is None:
        origins = np.zeros((k_count, 2))
    else:
        origins = np.broadcast_to(np.asarray(sensor_origins, float), (k_count, 2))
    prior = fixed_radius_m if fixed_radius_m is not None else radius_prior_m
    if fixed_radius_m is not None:  # a known radius: the limit of a prior with sigma -> 0
        weight = 1e12
    elif radius_prior_m is not None and np.isfinite(radius_prior_sigma_m) and radius_prior_sigma_m > 0:
        weight = (range_sigma_m / radius_prior_sigma_m) ** 2
    else:
        weight = 0.0
    out = np.empty((k_count, 5))
    fit_clusters(
        np.ascontiguousarray(points, dtype=float),
        starts,
        counts,
        np.ascontiguousarray(origins, dtype=float),
        prior is not None,
        0.0 if prior is None else float(prior),
        float(weight),
        float(range_sigma_m),
        int(iterations),
        out,
    )
    return CircleFits(out[:, :2].copy(), out[:, 2].copy(), out[:, 3].copy(), out[:, 4].copy())


@compiled
def solve_sym3(a00, a01, a02, a11, a12, a22, b0, b1, b2):
    """One symmetric 3x3 system ``A x = b`` by Cramer's rule: ``x`` and the entries 00, 01, 11 and 22 of ``A⁻¹``.

    A singular system (``|det| <= 1e-300``) gives ``x = 0`` and ``A⁻¹ = 0``.
    """
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
        c22 / det,
    )


@compiled
def fit_clusters(points, starts, counts, origins, has_prior, prior, weight, range_sigma, iterations, out):
    """The circle fit of every cluster: ``out[k]`` = (centre x, centre y, radius, rms, centre sigma).

    ``has_prior``: start from ``prior`` (the radius) behind the centroid and pull the radius towards it with
    ``weight`` = (σ_range / σ_prior)²; else start from the Kåsa fit, with ``weight`` 0.
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
        else:
            cx, cy, r = _kasa(points, s, m, mx, my)
            target = 0.0
        cx, cy, r, rms, i00, i01, i11 = _gauss_newton(points, s, m, mx, my, cx, cy, r, weight, target, iterations)
        sigma2 = max(rms, range_sigma) ** 2
        # Centre covariance σ̂² (JᵀJ)⁻¹ at the solution: the larger eigenvalue of its 2x2 centre block.
        half_trace = 0.5 * (i00 + i11)
        half_diff = 0.5 * (i00 - i11)
        largest = half_trace + np.sqrt(half_diff * half_diff + i01 * i01)
        # The centre must lie behind the arc, away from the sensor; a fit that flips to the near side
        # (possible on a nearly straight, noisy arc) is mirrored through the arc's centroid.
        if cx * vx + cy * vy < 0:
            cx = -cx
            cy = -cy
        out[k, 0] = cx + mx
        out[k, 1] = cy + my
        out[k, 2] = r
        out[k, 3] = rms
        out[k, 4] = np.sqrt(max(largest * sigma2, 0.0))


@compiled
def _kasa(points, s, m, mx, my):
    """Algebraic fit ``x² + y² + a x + b y + c = 0`` (Kåsa) of ``points[s : s + m]`` about their centroid
    ``(mx, my)``: the centre (relative to the centroid) and the radius."""
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
    a, b, c, _, _, _, _ = solve_sym3(sxx, sxy, sx, syy, sy, float(m), -sxz, -syz, -sz)
    cx = -0.5 * a
    cy = -0.5 * b
    return cx, cy, np.sqrt(max(cx * cx + cy * cy - c, 1e-12))


@compiled
def _gauss_newton(points, s, m, mx, my, cx, cy, r, weight, target, iterations):
    """``iterations`` Gauss–Newton steps on ``Σ (|p_i - c| - r)² + weight (r - target)²`` from ``(cx, cy, r)``
    (centre relative to the centroid ``(mx, my)``), then the normal equations once more at the solution.

    Residual ``|p - c| - r``; Jacobian rows ``(-u_x, -u_y, -1)`` with ``u`` the unit vector from the centre to
    the point; the step is ``δ = -(JᵀJ)⁻¹ Jᵀr``. Returns the centre, the radius, the residual RMS and the
    entries 00, 01, 11 of ``(JᵀJ)⁻¹`` at the solution.
    """
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
        d0, d1, d2, i00, i01, i11, _ = solve_sym3(a00, a01, a02, a11, a12, m + weight, g0, g1, g2)
        rms = np.sqrt(ss / m)
        if it < iterations:
            cx -= d0
            cy -= d1
            r = abs(r - d2)
    return cx, cy, r, rms, i00, i01, i11
