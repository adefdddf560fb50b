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
  the centroid of a half circle); without a prior, the Kåsa fit. Then ``iterations`` damped
  Gauss–Newton steps, all clusters at once on a padded ``(K, P)`` array (no Python loop per cluster).
* ``centre_sigma_m``: the Gauss–Newton covariance ``σ̂² (JᵀJ)⁻¹`` of the centre, with σ̂ the larger
  of the fit's residual RMS and the range noise — what the tracker takes as measurement noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class CircleFits:
    centres: np.ndarray  # (K, 2)
    radii_m: np.ndarray  # (K,)
    rms_m: np.ndarray  # (K,) RMS of |p - c| - r
    centre_sigma_m: np.ndarray  # (K,) sqrt of the larger eigenvalue of the centre covariance

    def __len__(self) -> int:
        return len(self.radii_m)


def _padded(points: np.ndarray, starts: np.ndarray, counts: np.ndarray):
    width = int(counts.max())
    column = np.arange(width)
    mask = column[None, :] < counts[:, None]
    index = np.where(mask, starts[:, None] + column[None, :], starts[:, None])
    return points[index], mask.astype(float)


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
    The numpy reference; the laser pipeline's dispatch (:func:`viapath.perception.detection.fit_circles_as`)
    runs the same algorithm compiled when asked (one loop per cluster; equal to round-off).
    """
    starts, counts = clusters_of(starts, counts)
    k_count = len(starts)
    if k_count == 0:
        return CircleFits(np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0))
    p, mask = _padded(np.asarray(points, dtype=float), starts, counts)
    n = counts.astype(float)
    mean = (p * mask[..., None]).sum(axis=1) / n[:, None]
    origins = (
        np.zeros((k_count, 2))
        if sensor_origins is None
        else np.broadcast_to(np.asarray(sensor_origins, float), (k_count, 2))
    )
    q = (p - mean[:, None, :]) * mask[..., None]  # centred, padded rows are 0

    prior = fixed_radius_m if fixed_radius_m is not None else radius_prior_m
    if prior is not None:
        view = mean - origins
        view /= np.maximum(np.hypot(view[:, 0], view[:, 1]), 1e-12)[:, None]
        centre = view * (2.0 / np.pi * prior)  # relative to the mean
        radius = np.full(k_count, float(prior))
    else:
        centre, radius = _kasa(q, mask, n)
    if fixed_radius_m is not None:
        weight = np.full(k_count, 1e12)
    elif radius_prior_m is not None and np.isfinite(radius_prior_sigma_m) and radius_prior_sigma_m > 0:
        weight = np.full(k_count, (range_sigma_m / radius_prior_sigma_m) ** 2)
    else:
        weight = np.zeros(k_count)
    target = radius.copy() if prior is not None else np.zeros(k_count)

    qz = q[..., 0] + 1j * q[..., 1]  # points as complex numbers: fewer numpy calls per iteration
    cz = centre[:, 0] + 1j * centre[:, 1]
    for _ in range(iterations):
        normal, _, jtr = _normal_equations(qz, mask, cz, radius, n, weight, target)
        step, _, _ = solve_sym3(normal, jtr)
        cz = cz - (step[0] + 1j * step[1])
        radius = np.abs(radius - step[2])

    normal, rms, jtr = _normal_equations(qz, mask, cz, radius, n, weight, target)
    # Centre covariance: σ̂² (JᵀJ)⁻¹ at the solution; its 2x2 centre block from the cofactors.
    _, cofactors, det = solve_sym3(normal, jtr)
    sigma2 = np.maximum(rms, range_sigma_m) ** 2
    c00, c01, _, c11, _, _ = (c / det for c in cofactors)
    half_trace, half_diff = 0.5 * (c00 + c11), 0.5 * (c00 - c11)
    largest = half_trace + np.sqrt(half_diff**2 + c01**2)
    centre_sigma = np.sqrt(np.maximum(largest * sigma2, 0.0))
    centre = np.stack([cz.real, cz.imag], axis=-1)
    # The centre must lie behind the arc, away from the sensor; a fit that flips to the near side
    # (possible on a nearly straight, noisy arc) is mirrored through the arc's centroid.
    view = mean - origins
    behind = (centre * view).sum(1) >= 0
    centre = np.where(behind[:, None], centre, -centre)
    return CircleFits(centre + mean, radius, rms, centre_sigma)


def _normal_equations(qz, mask, cz, radius, n, weight, target):
    """Gauss–Newton normal equations for (cx, cy, r): the six entries of ``JᵀJ``, the residual RMS and ``Jᵀr``.

    Residual ``|p - c| - r``; Jacobian rows ``(-u_x, -u_y, -1)`` with ``u`` the unit vector from the
    centre to the point (complex ``u``; ``Σu² = Σ(u_x² - u_y²) + 2iΣu_x u_y`` and ``u_x² + u_y² = 1``
    give the 2x2 block in one sum); the prior adds ``weight (r - target)²``. The step is
    ``δ = -(JᵀJ)⁻¹ Jᵀr``.
    """
    d = qz - cz[:, None]
    dist = np.abs(d)
    np.maximum(dist, 1e-12, out=dist)
    u = d / dist * mask
    res = (dist - radius[:, None]) * mask
    u2 = (u * u).sum(1)
    u1 = u.sum(1)
    ur = (u * res).sum(1)
    normal = (0.5 * (n + u2.real), 0.5 * u2.imag, u1.real, 0.5 * (n - u2.real), u1.imag, n + weight)
    rms = np.sqrt((res * res).sum(1) / n)
    jtr = (-ur.real, -ur.imag, -res.sum(1) + weight * (radius - target))
    return normal, rms, jtr


def solve_sym3(a, b):
    """Solve K symmetric 3x3 systems given as entries ``a = (a00, a01, a02, a11, a12, a22)`` (each (K,)).

    Cramer's rule on (K,) arrays: for a handful of clusters this is far faster than
    ``np.linalg.solve``. Returns ``(x (3, K), cofactors (6 arrays), det)``; a singular system gives
    a zero step.
    """
    a00, a01, a02, a11, a12, a22 = a
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    ok = np.abs(det) > 1e-300
    det = np.where(ok, det, np.inf)
    b0, b1, b2 = b
    x = (
        np.stack([(c00 * b0 + c01 * b1 + c02 * b2), (c01 * b0 + c11 * b1 + c12 * b2), (c02 * b0 + c12 * b1 + c22 * b2)])
        / det
    )
    return x, (c00, c01, c02, c11, c12, c22), det


def _kasa(q: np.ndarray, mask: np.ndarray, n: np.ndarray):
    """Algebraic fit ``x² + y² + a x + b y + c = 0`` (Kåsa), batched; ``q`` centred and masked."""
    x, y = q[..., 0], q[..., 1]
    z = x * x + y * y
    a = ((x * x).sum(1), (x * y).sum(1), x.sum(1), (y * y).sum(1), y.sum(1), n)
    sol, _, _ = solve_sym3(a, (-(x * z).sum(1), -(y * z).sum(1), -z.sum(1)))
    centre = -0.5 * sol[:2].T
    radius = np.sqrt(np.maximum((centre**2).sum(1) - sol[2], 1e-12))
    return centre, radius


def fit_circle(points: np.ndarray, sensor_origin=(0.0, 0.0), **options):
    """Convenience for one cluster: returns ``(centre (2,), radius_m, rms_m)``."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    fits = fit_circles(
        points, np.array([0]), np.array([len(points)]), np.asarray(sensor_origin, float)[None, :], **options
    )
    return fits.centres[0], float(fits.radii_m[0]), float(fits.rms_m[0])
