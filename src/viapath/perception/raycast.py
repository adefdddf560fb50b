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
* This module is the numpy reference (``(B, N)`` broadcasting). The laser pipeline can hand it the same
  casting compiled (:func:`viapath.perception.laser.ray_casters`, ``pip install 'viapath[fast]'``): the
  same expressions in the same order, without fast-math, so they agree bit for bit (tested).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

#: A ray caster: (origin or per-beam origins, directions, centres, radii, segments[, beam groups]) -> ranges.
Caster = Callable[..., np.ndarray]


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


def cast_rays(origin, angles_rad, centres, radii, segments=None, caster: Caster | None = None) -> np.ndarray:
    r"""Distance from ``origin`` along each world-frame angle to the first disc or wall; ``inf`` = no hit.

    ``caster``: what casts the rays, :func:`cast_rays_numpy`\ 's arguments (default: that function).
    """
    centres, radii, segments = _as_inputs(centres, radii, np.zeros((0, 2, 2)) if segments is None else segments)
    angles_rad = np.asarray(angles_rad, dtype=float).reshape(-1)
    directions = np.stack([np.cos(angles_rad), np.sin(angles_rad)], axis=-1)
    return (caster or cast_rays_numpy)(origin, directions, centres, radii, segments)


def simulate_scan(
    scanner, robot_pose, centres, radii, segments=None, rng=None, caster: Caster | None = None
) -> np.ndarray:
    """Readings of ``scanner`` mounted on a robot at ``robot_pose``, as its driver would report them."""
    x, y, yaw = scanner.world_pose(robot_pose)
    true_range = cast_rays((x, y), scanner.beam_angles_rad() + yaw, centres, radii, segments, caster)
    return scanner.measure(true_range, rng)


# -- all scanners of a robot in one call (the laser loop) ------------------------------------------


@dataclass(frozen=True)
class _ScanLayout:
    """Per-beam constants of a set of scanners, concatenated (cached per scanner tuple)."""

    beam_angles_rad: tuple  # per scanner, scanner frame (ScannerModel.beam_angles_rad())
    bounds: np.ndarray  # (S + 1,) first beam of each scanner, then the total
    range_min_m: np.ndarray  # (B,)
    range_max_m: np.ndarray  # (B,)
    noise_sigma_near_m: np.ndarray  # (B,)
    noise_fraction_far: np.ndarray  # (B,)
    noise_switch_range_m: np.ndarray  # (B,)
    invalid_values: tuple  # per scanner: the value its driver reports for an invalid beam


@lru_cache(maxsize=16)
def _scan_layout(scanners) -> _ScanLayout:
    counts = [s.beam_count for s in scanners]
    rep = lambda name: np.repeat(np.array([getattr(s, name) for s in scanners], dtype=float), counts)
    return _ScanLayout(
        tuple(s.beam_angles_rad() for s in scanners),
        np.concatenate([[0], np.cumsum(counts)]),
        rep("range_min_m"),
        rep("range_max_m"),
        rep("noise_sigma_near_m"),
        rep("noise_fraction_far"),
        rep("noise_switch_range_m"),
        tuple({"inf": np.inf, "nan": np.nan, "zero": 0.0}[s.invalid_encoding] for s in scanners),
    )


def cast_rays_from_numpy(origins_x, origins_y, directions, centres, radii, segments, groups=None) -> np.ndarray:
    """:func:`cast_rays_numpy` for beams with their own origins (``origins_x``/``origins_y`` (B,)); same bits.

    ``groups``: optional list of ``(first, count, angle0_rad, increment_rad)`` — runs of beams from
    one origin at uniformly spaced world angles ``angle0 + i * increment`` (a scanner). With it, a
    disc is only tested against the beams within its angular extent plus two beams of margin (the
    others miss it by far more than round-off: ``b² - k <= -(d² sin²(α + 2Δφ) - r²)``), and a
    scanner inside a disc reads 0 on every beam, as in :func:`cast_rays_numpy`.
    """
    n_beams = len(directions)
    best = np.full(n_beams, np.inf)
    dx = directions[:, 0]
    dy = directions[:, 1]
    if len(centres):
        if groups is None:
            beam = np.repeat(np.arange(n_beams), len(centres))
            disc_of = np.tile(np.arange(len(centres)), n_beams)
        else:
            beam, disc_of = _candidate_pairs(origins_x, origins_y, centres, radii, groups, best)
        if len(beam):
            fx = origins_x[beam] - centres[disc_of, 0]
            fy = origins_y[beam] - centres[disc_of, 1]
            r = radii[disc_of]
            k = fx * fx + fy * fy - r * r
            b = fx * dx[beam] + fy * dy[beam]
            disc = b * b - k
            with np.errstate(invalid="ignore"):
                t = -b - np.sqrt(disc)
            t = np.where((disc >= 0.0) & (t >= 0.0), t, np.inf)
            t = np.where(k <= 0.0, 0.0, t)
            np.minimum.at(best, beam, t)
    if len(segments):
        # Walls along the first axis, beams along the second ((W, B), the transpose of cast_rays_numpy's
        # layout): the same products and differences, but numpy's loops run over the many beams, not
        # the few walls (about 3x faster for two walls), and the minimum over walls is elementwise.
        px = segments[:, 0, 0, None]
        py = segments[:, 0, 1, None]
        ex = segments[:, 1, 0, None] - px
        ey = segments[:, 1, 1, None] - py
        wx = px - origins_x
        wy = py - origins_y
        denom = dx * ey - dy * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (wx * ey - wy * ex) / denom
            s = (wx * dy - wy * dx) / denom
            ok = (denom != 0.0) & (t >= 0.0) & (s >= 0.0) & (s <= 1.0)
        t = np.where(ok, t, np.inf)
        best = np.minimum(best, t.min(axis=0))
    return best


def _candidate_pairs(origins_x, origins_y, centres, radii, groups, best):
    """(beam, disc) pairs that may hit, per uniform beam group; beams of a scanner inside a disc set to 0."""
    beams, discs = [], []
    two_pi = 2.0 * np.pi
    for first, count, angle0, increment in groups:
        ox, oy = origins_x[first], origins_y[first]
        fx = ox - centres[:, 0]
        fy = oy - centres[:, 1]
        k = fx * fx + fy * fy - radii * radii  # the expression of the per-pair test: same sign
        inside = k <= 0.0
        if inside.any():
            best[first : first + count] = 0.0  # t = 0 on every beam, whatever else it meets
            continue
        distance = np.sqrt(fx * fx + fy * fy)
        half = np.arcsin(np.minimum(radii / distance, 1.0)) + 2.0 * increment
        bearing = np.mod(np.arctan2(-fy, -fx) - angle0, two_pi)
        lo = np.ceil((bearing - half) / increment)
        hi = np.floor((bearing + half) / increment)
        everything = half >= 0.5 * np.pi
        # The beam range of each disc, and its copies one turn before and after (a disc across the
        # ends of a 360° scan); they cannot overlap (half < π/2), and a repeated pair would do no harm.
        shifts = np.array([-two_pi / increment, 0.0, two_pi / increment])
        start = np.maximum((lo[:, None] + np.floor(shifts)).astype(int) - 1, 0)
        stop = np.minimum((hi[:, None] + np.ceil(shifts)).astype(int) + 1, count - 1)
        start[everything] = (0, 1, 1)
        stop[everything] = (count - 1, 0, 0)
        length = np.maximum(stop - start + 1, 0).ravel()
        if not length.any():
            continue
        start = start.ravel()
        offsets = np.repeat(start - (np.cumsum(length) - length), length)
        beams.append(first + np.arange(int(length.sum())) + offsets)
        discs.append(np.repeat(np.repeat(np.arange(len(centres)), 3), length))
    if not beams:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    return np.concatenate(beams), np.concatenate(discs)


def simulate_scans(
    scanners, robot_pose, centres, radii, segments=None, rng=None, caster: Caster | None = None
) -> list[np.ndarray]:
    r"""``[simulate_scan(s, ...) for s in scanners]`` in one pass: the same readings, bit for bit, and the
    same draws from ``rng`` (one normal per hit beam, scanner after scanner). ``caster``: what casts the rays
    of every beam, :func:`cast_rays_from_numpy`\ 's arguments (default: that function)."""
    scanners = tuple(scanners)
    layout = _scan_layout(scanners)
    centres, radii, segments = _as_inputs(centres, radii, np.zeros((0, 2, 2)) if segments is None else segments)
    n_beams = int(layout.bounds[-1])
    origins_x = np.empty(n_beams)
    origins_y = np.empty(n_beams)
    angles = np.empty(n_beams)  # world frame
    groups = []
    # ScannerModel.world_pose of each scanner, with the heading's cosine and sine computed once.
    robot_x, robot_y, heading = (float(v) for v in robot_pose)
    c, s = np.cos(heading), np.sin(heading)
    for index, scanner in enumerate(scanners):
        x = robot_x + c * scanner.mount_x_m - s * scanner.mount_y_m
        y = robot_y + s * scanner.mount_x_m + c * scanner.mount_y_m
        yaw = heading + scanner.mount_yaw_rad
        first, last = int(layout.bounds[index]), int(layout.bounds[index + 1])
        np.add(layout.beam_angles_rad[index], yaw, out=angles[first:last])
        origins_x[first:last] = x
        origins_y[first:last] = y
        groups.append((first, last - first, float(angles[first]), scanner.angle_increment_rad))
    directions = np.empty((n_beams, 2))  # cosines and sines of every scanner's beams in one call each,
    directions[:, 0] = np.cos(angles)  # on a contiguous array, as before (numpy may take another loop
    directions[:, 1] = np.sin(angles)  # for strided output)
    true_range = (caster or cast_rays_from_numpy)(origins_x, origins_y, directions, centres, radii, segments, groups)
    # ScannerModel.measure on every scanner at once: same expressions, per-beam parameters.
    reading = true_range.copy()
    if rng is not None:
        hit = np.isfinite(true_range)
        # σ of every beam (inf where nothing was hit), then the hit ones: the same values as on the hits alone.
        sigma = np.where(
            true_range < layout.noise_switch_range_m, layout.noise_sigma_near_m, layout.noise_fraction_far * true_range
        )[hit]
        reading[hit] += rng.standard_normal(int(hit.sum())) * sigma
    invalid = ~np.isfinite(reading) | (reading < layout.range_min_m) | (reading > layout.range_max_m)
    out = []
    for index, value in enumerate(layout.invalid_values):
        first, last = int(layout.bounds[index]), int(layout.bounds[index + 1])
        part = reading[first:last]
        part[invalid[first:last]] = value
        out.append(part)
    return out
