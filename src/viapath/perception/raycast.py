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
* Every beam is tested against every disc and wall, one beam at a time, compiled
  (:func:`viapath.jit.compiled`; plain Python when compilation is off): for the few discs and walls of a
  scene this is faster than culling, and a beam's range is one loop anyone can step through. The beam
  directions' cosines and sines are numpy's (``np.cos``, ``np.sin``), computed before the loop.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from viapath.jit import compiled


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


@compiled
def beam_range(ox, oy, dx, dy, centres, radii, segments):
    """Range along the unit direction (dx, dy) from (ox, oy) to the nearest disc or wall; ``inf`` = no hit."""
    best = np.inf
    for j in range(centres.shape[0]):
        fx = ox - centres[j, 0]
        fy = oy - centres[j, 1]
        k = fx * fx + fy * fy - radii[j] * radii[j]
        if k <= 0.0:  # the origin is inside the disc
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


@compiled
def cast_beams(origins_x, origins_y, directions, centres, radii, segments, out):
    """:func:`beam_range` of every beam ``i`` (origin ``(origins_x[i], origins_y[i])``, unit direction
    ``directions[i]``) into ``out[i]``."""
    for i in range(directions.shape[0]):
        out[i] = beam_range(origins_x[i], origins_y[i], directions[i, 0], directions[i, 1], centres, radii, segments)


def cast_rays(origin, angles_rad, centres, radii, segments=None) -> np.ndarray:
    """Distance from ``origin`` along each world-frame angle to the first disc or wall; ``inf`` = no hit.

    ``centres`` (N, 2) (rows of NaN: absent), ``radii`` (N,), ``segments`` (W, 2, 2) walls.
    """
    centres, radii, segments = _as_inputs(centres, radii, np.zeros((0, 2, 2)) if segments is None else segments)
    angles_rad = np.asarray(angles_rad, dtype=float).reshape(-1)
    directions = np.stack([np.cos(angles_rad), np.sin(angles_rad)], axis=-1)
    out = np.empty(len(directions))
    origins_x = np.full(len(directions), float(origin[0]))
    origins_y = np.full(len(directions), float(origin[1]))
    cast_beams(origins_x, origins_y, directions, centres, radii, segments, out)
    return out


def simulate_scan(scanner, robot_pose, centres, radii, segments=None, rng=None) -> np.ndarray:
    """Readings of ``scanner`` mounted on a robot at ``robot_pose``, as its driver would report them."""
    x, y, yaw = scanner.world_pose(robot_pose)
    true_range = cast_rays((x, y), scanner.beam_angles_rad() + yaw, centres, radii, segments)
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


def simulate_scans(scanners, robot_pose, centres, radii, segments=None, rng=None) -> list[np.ndarray]:
    """``[simulate_scan(s, ...) for s in scanners]`` in one pass: the same readings, bit for bit, and the
    same draws from ``rng`` (one normal per hit beam, scanner after scanner)."""
    scanners = tuple(scanners)
    layout = _scan_layout(scanners)
    centres, radii, segments = _as_inputs(centres, radii, np.zeros((0, 2, 2)) if segments is None else segments)
    n_beams = int(layout.bounds[-1])
    origins_x = np.empty(n_beams)
    origins_y = np.empty(n_beams)
    angles = np.empty(n_beams)  # world frame
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
    directions = np.empty((n_beams, 2))  # cosines and sines of every scanner's beams in one call each,
    directions[:, 0] = np.cos(angles)  # on a contiguous array, as before (numpy may take another loop
    directions[:, 1] = np.sin(angles)  # for strided output)
    true_range = np.empty(n_beams)
    cast_beams(origins_x, origins_y, directions, centres, radii, segments, true_range)
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
