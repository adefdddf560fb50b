"""Fuse the scans of several scanners into one robot-frame point set, and know what none of them sees.

Source: paper §1.2 / §4.1 — two 240° scanners, forward and backward, 0.145 m from the centre,
"providing 360 degrees view". Because the scanners are offset from the centre, their fields of
view leave a region beside the robot that neither sees: with the paper's set-up it is a diamond
between the two scanners whose side tips reach 0.145·tan(60°) = 0.251 m from the centre (1 mm
beyond a 0.25 m body); narrower scanners (e.g. 180°) leave strips beside the robot that reach to
infinity.

What we chose:
* Points keep the scanner and beam they came from: detection segments each scan in its own beam
  order (where range jumps are defined) and merges clusters across scanners afterwards; a single
  360° ordering around the centre would interleave the two scanners in their overlap sectors.
* The blind region is computed from the field-of-view geometry only (no occlusion): along each
  direction from the robot centre, sampled every ``angle_step_rad``, the largest distance up to
  which no scanner covers the point (``blind_depth_m``), and the polygon it bounds. *Sectors* are
  the directions where that depth reaches beyond the robot body.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from viapath.perception.scanner import ScannerModel


@dataclass
class FusedScan:
    """All valid points of one cycle in the robot frame (x forward, y left)."""

    points_robot: np.ndarray  # (M, 2)
    scanner_index: np.ndarray  # (M,)
    beam_index: np.ndarray  # (M,)

    def to_world(self, robot_pose) -> np.ndarray:
        return robot_to_world(self.points_robot, robot_pose)


def robot_to_world(points: np.ndarray, robot_pose) -> np.ndarray:
    x, y, heading = (float(v) for v in robot_pose)
    c, s = np.cos(heading), np.sin(heading)
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    return np.stack([x + c * points[:, 0] - s * points[:, 1], y + s * points[:, 0] + c * points[:, 1]], axis=-1)


def covered(scanners, points_robot: np.ndarray) -> np.ndarray:
    """Whether each robot-frame point lies inside some scanner's field of view and range."""
    points_robot = np.asarray(points_robot, dtype=float).reshape(-1, 2)
    seen = np.zeros(len(points_robot), dtype=bool)
    for scanner in scanners:
        d = points_robot - np.array([scanner.mount_x_m, scanner.mount_y_m])
        distance = np.hypot(d[:, 0], d[:, 1])
        bearing = np.angle(np.exp(1j * (np.arctan2(d[:, 1], d[:, 0]) - scanner.mount_yaw_rad)))
        half = 0.5 * scanner.field_of_view_rad + 0.5 * scanner.angle_increment_rad
        seen |= (np.abs(bearing) <= half) & (distance >= scanner.range_min_m) & (distance <= scanner.range_max_m)
    return seen


@dataclass
class BlindRegion:
    """What no scanner sees, in the robot frame, by direction from the robot centre."""

    angles_rad: np.ndarray  # (S,) directions from the robot centre
    blind_depth_m: np.ndarray  # (S,) unseen from the centre out to this distance (inf: never seen)
    robot_radius_m: float
    max_range_m: float
    sectors_rad: list[tuple[float, float]] = field(default_factory=list)  # [start, end] where depth > body

    def polygon_robot(self, far_m: float | None = None) -> np.ndarray:
        """Closed polygon (S, 2) of the blind region; infinite depths drawn out to ``far_m``."""
        far = self.max_range_m if far_m is None else far_m
        depth = np.minimum(self.blind_depth_m, far)
        return np.stack([depth * np.cos(self.angles_rad), depth * np.sin(self.angles_rad)], axis=-1)

    def polygon_world(self, robot_pose, far_m: float | None = None) -> np.ndarray:
        return robot_to_world(self.polygon_robot(far_m), robot_pose)


@lru_cache(maxsize=32)
def blind_region(
    scanners: tuple[ScannerModel, ...],
    robot_radius_m: float = 0.25,
    angle_step_rad: float = np.deg2rad(0.5),
    radial_step_m: float = 0.001,
) -> BlindRegion:
    """Sample the field-of-view geometry of ``scanners`` around the robot centre (see module notes).

    Depth resolution: ``radial_step_m`` out to 1 m, 1 cm beyond. Cached: scanners are immutable.
    """
    scanners = tuple(scanners)
    max_range = max(s.range_max_m + np.hypot(s.mount_x_m, s.mount_y_m) for s in scanners)
    angles = np.arange(-np.pi, np.pi, angle_step_rad)
    radii = np.concatenate([np.arange(0.0, 1.0, radial_step_m), np.arange(1.0, max_range + 0.01, 0.01)])
    grid = np.stack(
        np.broadcast_arrays(radii[None, :] * np.cos(angles)[:, None], radii[None, :] * np.sin(angles)[:, None]), -1
    )
    seen = covered(scanners, grid.reshape(-1, 2)).reshape(len(angles), len(radii))
    first_seen = np.where(seen.any(axis=1), np.argmax(seen, axis=1), -1)
    depth = np.where(first_seen >= 0, radii[np.maximum(first_seen, 0)], np.inf)
    beyond = depth > robot_radius_m + radial_step_m
    sectors = []
    if beyond.all():
        sectors.append((float(angles[0]), float(angles[-1])))
    elif beyond.any():
        shift = int(np.argmin(beyond))  # walk from a covered direction: every blind run has a start
        rolled = np.roll(beyond, -shift)
        rolled_angles = np.roll(angles, -shift)
        edges = np.diff(rolled.astype(int))
        starts = np.flatnonzero(edges == 1) + 1
        ends = np.flatnonzero(edges == -1)
        if rolled[-1]:
            ends = np.append(ends, len(rolled) - 1)
        sectors = [(float(rolled_angles[a]), float(rolled_angles[b])) for a, b in zip(starts, ends, strict=True)]
    return BlindRegion(angles, depth, float(robot_radius_m), float(max_range), sectors)
