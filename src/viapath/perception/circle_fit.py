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
    iterations: int = 8,
) -> CircleFits:
    """Fit one circle to each cluster ``points[starts[k] : starts[k] + counts[k]]``.

    ``sensor_origins`` (K, 2) or (2,): where each cluster was seen from, in the points' frame
    (default: the origin); used for the start and so that the centre lands *behind* the arc.
    """
    starts = np.asarray(starts, dtype=int)
    counts = np.asarray(counts, dtype=int)
    k_count = len(starts)
    if k_count == 0:
        return CircleFits(np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0))
    if (counts < 2).any():
        raise ValueError("every cluster needs at least 2 points")
    p, mask = _padded(np.asarray(points, dtype=float), starts, counts)
    n = counts.astype(float)
    mean = (p * mask[..., None]).sum(axis=1) / n[:, None]
    origins = np.zeros((k_count, 2)) if sensor_origins is None else np.broadcast_to(np.asarray(sensor_origins, float), (k_count, 2))
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

    jtj = np.zeros((k_count, 3, 3))
    for _ in range(iterations):
        d = q - centre[:, None, :]
        dist = np.maximum(np.hypot(d[..., 0], d[..., 1]), 1e-12)
        u = d / dist[..., None]
        res = (dist - radius[:, None]) * mask
        jx, jy = -u[..., 0] * mask, -u[..., 1] * mask
        jr = -mask
        jtj[:, 0, 0] = (jx * jx).sum(1)
        jtj[:, 0, 1] = jtj[:, 1, 0] = (jx * jy).sum(1)
        jtj[:, 1, 1] = (jy * jy).sum(1)
        jtj[:, 0, 2] = jtj[:, 2, 0] = (jx * jr).sum(1)
        jtj[:, 1, 2] = jtj[:, 2, 1] = (jy * jr).sum(1)
        jtj[:, 2, 2] = n + weight
        jtr = np.stack([(jx * res).sum(1), (jy * res).sum(1), (jr * res).sum(1) + weight * (radius - target)], axis=-1)
        damped = jtj + 1e-9 * np.eye(3)
        step = -np.linalg.solve(damped, jtr[..., None])[..., 0]
        centre = centre + step[:, :2]
        radius = np.abs(radius + step[:, 2])

    d = q - centre[:, None, :]
    dist = np.hypot(d[..., 0], d[..., 1])
    res = (dist - radius[:, None]) * mask
    rms = np.sqrt((res**2).sum(1) / n)
    # Centre covariance: σ̂² (JᵀJ)⁻¹ at the solution (the last Jacobian is close enough).
    sigma2 = np.maximum(rms, range_sigma_m) ** 2
    cov = np.linalg.inv(jtj + 1e-9 * np.eye(3))[:, :2, :2] * sigma2[:, None, None]
    centre_sigma = np.sqrt(np.maximum(np.linalg.eigvalsh(cov)[:, -1], 0.0))
    # The centre must lie behind the arc, away from the sensor; a fit that flips to the near side
    # (possible on a nearly straight, noisy arc) is mirrored through the arc's centroid.
    view = mean - origins
    behind = (centre * view).sum(1) >= 0
    centre = np.where(behind[:, None], centre, -centre)
    return CircleFits(centre + mean, radius, rms, centre_sigma)


def _kasa(q: np.ndarray, mask: np.ndarray, n: np.ndarray):
    """Algebraic fit ``x² + y² + a x + b y + c = 0`` (Kåsa), batched; ``q`` centred and masked."""
    x, y = q[..., 0], q[..., 1]
    z = x * x + y * y
    a = np.zeros((len(n), 3, 3))
    a[:, 0, 0] = (x * x).sum(1)
    a[:, 0, 1] = a[:, 1, 0] = (x * y).sum(1)
    a[:, 1, 1] = (y * y).sum(1)
    a[:, 0, 2] = a[:, 2, 0] = x.sum(1)
    a[:, 1, 2] = a[:, 2, 1] = y.sum(1)
    a[:, 2, 2] = n
    rhs = -np.stack([(x * z).sum(1), (y * z).sum(1), z.sum(1)], axis=-1)
    sol = np.linalg.solve(a + 1e-12 * np.eye(3), rhs[..., None])[..., 0]
    centre = -0.5 * sol[:, :2]
    radius = np.sqrt(np.maximum((centre**2).sum(1) - sol[:, 2], 1e-12))
    return centre, radius


def fit_circle(points: np.ndarray, sensor_origin=(0.0, 0.0), **options):
    """Convenience for one cluster: returns ``(centre (2,), radius_m, rms_m)``."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    fits = fit_circles(points, np.array([0]), np.array([len(points)]), np.asarray(sensor_origin, float)[None, :], **options)
    return fits.centres[0], float(fits.radii_m[0]), float(fits.rms_m[0])
